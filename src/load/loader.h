/* What the mesh loaders share: the loader signature, growth arrays, line tokens, error lines and
 * the common end of a load. Private to src/load/; the rest of the program sees load/load.h and
 * mesh.h alone. */
#ifndef AO_LOADER_H
#define AO_LOADER_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "budget.h"
#include "mesh.h"

/* An absent OBJ normal in a face corner; also one past the largest usable vertex index. */
#define AO_LOAD_NO_INDEX AO_MESH_INDEX_LIMIT
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
 * ao_mesh_missing_normal), given ones that are zero or not finite too, counted in
 * mesh->invalid_normals; load.c then has mesh.c make them (ao_mesh_complete_normals). Before it
 * allocates for triangles and vertices it checks that their charge fits in budget (ao_mesh_fits),
 * from the file's counts where it has them, else as the counts grow; what else it holds for a
 * while (a parser's tree, buffers) it takes from budget and gives back. */
typedef bool ao_load_format(struct ao_mesh *mesh, const char *path, const char *text, size_t size,
                            struct ao_budget *budget);

/* A loader of files that hold several meshes and place them (glTF): parses a whole file into the
 * empty model (mesh.h), each mesh ended by ao_mesh_drop_degenerate; reports, checks the budget (with
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

/* Hands the array's storage to the caller (who frees it) and empties the array. */
void *ao_load_take(struct ao_load_array *a);

/* Frees the array's storage. */
void ao_load_free(struct ao_load_array *a);

/* ao_mesh_fits for unique meshes of so many triangles and vertices placed so many times in all
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

/* Percent-decodes the URI of a glTF buffer (not a data: URI) into out, a file name of at most
 * size - 1 bytes; false with the reason in why when it is empty, has a scheme, is absolute, holds
 * a bad escape or %00, or does not fit. */
bool ao_load_uri_decode(const char *uri, char *out, size_t size, char *why, size_t why_size);

/* Opens the file at the decoded relative path inside the folder of the model at model_path into
 * *fd (the caller closes it), following no symbolic link; false with the reason in why when the
 * path leaves that folder or cannot be opened there. */
bool ao_load_uri_open(const char *model_path, const char *relative, int *fd, char *why, size_t why_size);

/* Common end of the single-mesh loaders (load.c): drops degenerate triangles and refuses a mesh
 * without triangles (reported). The normals the file did not give stay missing (NULL, or mesh.h's
 * marker) for ao_mesh_complete_normals, which load.c calls for the whole model. */
bool ao_load_finish(struct ao_mesh *mesh, const char *path);

#endif
