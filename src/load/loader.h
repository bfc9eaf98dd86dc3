/* What the mesh loaders share: the loader signature, growth arrays, line tokens, error lines and
 * the common end of a load. Only src/mesh.c and src/load/ include this; the rest of the program
 * sees mesh.h alone. */
#ifndef AO_LOAD_H
#define AO_LOAD_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "budget.h"
#include "mesh.h"

/* An absent OBJ normal in a face corner; also one past the largest usable vertex index. */
#define AO_LOAD_NO_INDEX UINT32_MAX
/* The most vertices a face may have: its fan then takes at most 1.5 MB, where a 100 MB line of
 * corners would take gigabytes (and polygons that large are no real model's). */
#define AO_LOAD_MAX_FACE_VERTICES 65536

/* A growable array of fixed-size elements; doubling keeps appends amortized O(1). */
struct ao_load_array {
    unsigned char *data;
    size_t count, capacity, size;
};

/* A token: the characters [begin, end) of the file text. */
struct ao_load_span {
    const char *begin, *end;
};

/* The unread rest of one line of text. */
struct ao_load_tokens {
    const char *p, *end;
};

/* A format's loader: parses a whole file (size bytes, followed by a NUL) into the empty mesh,
 * ending with ao_load_finish; on failure prints one line and returns false (the caller empties
 * the mesh). Normals the file does not give are left missing (normals NULL, or a vertex's
 * ao_load_missing_normal), given ones that are zero or not finite too, counted in
 * mesh->invalid_normals; mesh.c makes them (ao_load_complete_normals). Before it allocates for triangles and vertices it checks that their charge fits in
 * budget (ao_load_fits), from the file's counts where it has them, else as the counts grow; what
 * else it holds for a while (a parser's tree, buffers) it takes from budget and gives back. */
typedef bool ao_load_format(struct ao_mesh *mesh, const char *path, const char *text, size_t size,
                            struct ao_budget *budget);

/* A loader of files that hold several meshes and place them (glTF): parses a whole file into the
 * empty model (mesh.h), each mesh ended by ao_load_finish_mesh; reports, checks the budget (with
 * ao_load_fits_model: unique meshes and placements) and holds as ao_load_format does. */
typedef bool ao_load_model_format(struct ao_model *model, const char *path, const char *text, size_t size,
                                  struct ao_budget *budget);

/* The loaders, one file each under src/load/. */
ao_load_format ao_load_obj, ao_load_ply, ao_load_stl;
ao_load_model_format ao_load_gltf;

/* Makes room for n more elements of a without appending them (one allocation where the count is
 * known ahead); false when memory or size_t runs out. */
bool ao_load_reserve(struct ao_load_array *a, size_t n);

/* Appends n elements to a (storage exists after any call) and returns the first, or NULL when memory runs out. */
void *ao_load_append(struct ao_load_array *a, size_t n);

/* Arrays of at least this many bytes are advised into huge pages (ao_load_advise_huge). */
#define AO_LOAD_HUGE_ARRAY ((size_t)4 << 20)

/* Asks the system to back the array [data, data + size) (malloc'd, not yet filled) with huge pages
 * when it is AO_LOAD_HUGE_ARRAY bytes or more: filling 240 MB of fresh 4 KiB pages costs 0.8 s of
 * page faults in a virtual machine, of 2 MiB pages 0.02 s. Does nothing where the system cannot. */
void ao_load_advise_huge(void *data, size_t size);

/* Hands the array's storage to the caller (who frees it) and empties the array. */
void *ao_load_take(struct ao_load_array *a);

/* Frees the array's storage. */
void ao_load_free(struct ao_load_array *a);

/* Prints the load's one error line: "path:line: message", or "path: message" when line is 0. */
void ao_load_report(const char *path, size_t line, const char *format, ...);

/* True when a mesh of so many triangles and vertices fits in what budget has left (ao_budget_charge);
 * else reports "path:line: T triangles and V vertices need about ..." and returns false. */
bool ao_load_fits(const struct ao_budget *budget, uint64_t triangles, uint64_t vertices, const char *path,
                  size_t line);

/* ao_load_fits for unique meshes of so many triangles and vertices placed so many times in all
 * (ao_budget_charge); the report names the placements too. */
bool ao_load_fits_model(const struct ao_budget *budget, uint64_t triangles, uint64_t vertices, uint64_t placements,
                        const char *path);

/* Appends a printf-formatted note to note (AO_MESH_NOTE_SIZE bytes: what a load tells of what it
 * ignored or made), after a "; " when there are others; what does not fit is left out. */
void ao_load_vnote(char *note, const char *format, va_list args);

/* Reports an allocation failure; returns false for the caller to pass on. */
bool ao_load_out_of_memory(const char *path);

/* Whitespace inside a line ('\r' too, so CRLF files need no special case). */
bool ao_load_is_blank(char c);

/* Moves to the next whitespace-separated token of the line; false at its end. */
bool ao_load_next_token(struct ao_load_tokens *t, struct ao_load_span *s);

/* True when the token is exactly word. */
bool ao_load_span_is(struct ao_load_span s, const char *word);

/* Token length for "%.*s" in messages, capped so one bad token cannot flood the line. */
int ao_load_span_length(struct ao_load_span s);

/* Parses a whole token as a number (strtod syntax); false when anything is left over. */
bool ao_load_parse_number(struct ao_load_span s, double *out);

/* Parses a whole token as a finite single-precision number. */
bool ao_load_parse_float(struct ao_load_span s, float *out);

/* Appends the fan triangulation (v0, vi, vi+1) of the polygon face (elements of any size, at
 * least 3) to triangles. */
bool ao_load_fan(struct ao_load_array *triangles, const struct ao_load_array *face);

/* The unit vector along (x, y, z) in single precision, or zero when it is zero or not finite;
 * exact-enough for any finite double components (no square overflows or vanishes). */
struct ao_vec3 ao_load_unit(double x, double y, double z);

/* Percent-decodes the URI of a glTF buffer (not a data: URI) into out, a file name of at most
 * size - 1 bytes; false with the reason in why when it is empty, has a scheme, is absolute, holds
 * a bad escape or %00, or does not fit. */
bool ao_load_uri_decode(const char *uri, char *out, size_t size, char *why, size_t why_size);

/* Opens the file at the decoded relative path inside the folder of the model at model_path into
 * *fd (the caller closes it), following no symbolic link; false with the reason in why when the
 * path leaves that folder or cannot be opened there. */
bool ao_load_uri_open(const char *model_path, const char *relative, int *fd, char *why, size_t why_size);

/* A normal that a file does not give (or gives as zero or not finite), as the loaders store it
 * until ao_load_complete_normals makes it: NaN. */
struct ao_vec3 ao_load_missing_normal(void);

/* True when n is ao_load_missing_normal's marker. */
bool ao_load_normal_is_missing(struct ao_vec3 n);

/* A normal as a file gives it, as the loaders store it: made unit, or the missing marker when it is
 * zero or not finite (counted in *invalid). */
struct ao_vec3 ao_load_given_normal(double x, double y, double z, size_t *invalid);

/* The end of one mesh of a model: drops its degenerate triangles (counting them in
 * mesh->degenerate_count; a mesh may be left with none, for the caller to drop). */
void ao_load_finish_mesh(struct ao_mesh *mesh);

/* Common end of the single-mesh loaders: drops degenerate triangles and refuses a mesh without
 * triangles (reported). The normals the file did not give stay missing (NULL, or the marker) for
 * ao_load_complete_normals. */
bool ao_load_finish(struct ao_mesh *mesh, const char *path);

/* Makes the normals a loaded mesh lacks (mesh->normals NULL: all; else those with the missing
 * marker): with crease 0 or less flat (the zero vector, which shading replaces by the triangle's
 * own normal); from 180 on angle-weighted over every triangle at the vertex; between, angle-weighted
 * over the triangles joined to the vertex's through edges flatter than crease degrees, the vertex
 * split into one per side of the sharper edges (new vertices at the end, charged to budget first).
 * A mesh without such an edge keeps its vertices and gets the normals 180 gives, bit for bit.
 * False (reported, naming path) when memory or the budget runs out. Any thread. */
bool ao_load_complete_normals(struct ao_mesh *mesh, const char *path, double crease, const struct ao_budget *budget);

/* Angle-weighted normals of every vertex into mesh->normals (allocated when NULL), on so many
 * threads (0: one per core for a big mesh), the same bit for bit on any number; false when memory
 * runs out (not reported). Any thread. */
bool ao_load_normals(struct ao_mesh *mesh, int threads);

#endif
