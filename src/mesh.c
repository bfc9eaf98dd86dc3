/* OBJ and PLY loaders. The whole file is read into memory and parsed in place into amortized
 * growth arrays, so loading is linear in the file size and never allocates per vertex. Every
 * failure prints exactly one "path:line: message" line (binary PLY rows: "path: element row:
 * message") and leaves the mesh empty. */
#include "mesh.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "file.h"

/* An absent OBJ normal in a face corner; also one past the largest usable vertex index. */
#define NO_INDEX UINT32_MAX
/* Parsed indices saturate here, far above any possible vertex count. */
#define INDEX_SATURATION 1000000000000000LL
/* The most vertices a face may have: its fan then takes at most 1.5 MB, where a 100 MB line of
 * corners would take gigabytes (and polygons that large are no real model's). */
#define MAX_FACE_VERTICES 65536

/* ------------------------------------------------------------------ shared helpers */

/* A growable array of fixed-size elements; doubling keeps appends amortized O(1). */
struct array {
    unsigned char *data;
    size_t count, capacity, size;
};

/* A token: the characters [begin, end) of the file text. */
struct span {
    const char *begin, *end;
};

/* The unread rest of one line of text. */
struct tokens {
    const char *p, *end;
};

/* A point or direction in double precision, for exact-enough normals of float positions. */
struct dvec {
    double x, y, z;
};

/* Appends n elements and returns the first, or NULL when memory or size_t runs out. */
static void *array_append(struct array *a, size_t n)
{
    if (n > a->capacity - a->count) {
        size_t want = a->capacity ? a->capacity : 64;
        while (want - a->count < n) {
            if (want > SIZE_MAX / 2 / a->size)
                return NULL;
            want *= 2;
        }
        unsigned char *data = realloc(a->data, want * a->size);
        if (!data)
            return NULL;
        a->data = data;
        a->capacity = want;
    }
    void *first = a->data + a->count * a->size;
    a->count += n;
    return first;
}

/* Hands the array's storage to the caller (who frees it) and empties the array. */
static void *array_take(struct array *a)
{
    void *data = a->data;
    a->data = NULL;
    a->count = a->capacity = 0;
    return data;
}

/* Frees the array's storage. */
static void array_free(struct array *a)
{
    free(array_take(a));
}

/* Prints the load's one error line: "path:line: message", or "path: message" when line is 0. */
static void report(const char *path, size_t line, const char *format, ...)
{
    char message[512];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    if (line)
        fprintf(stderr, "%s:%zu: %s\n", path, line, message);
    else
        fprintf(stderr, "%s: %s\n", path, message);
}

/* Reports an allocation failure; returns false for the caller to pass on. */
static bool out_of_memory(const char *path)
{
    report(path, 0, "out of memory");
    return false;
}

/* Whitespace inside a line ('\r' too, so CRLF files need no special case). */
static bool is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

/* Moves to the next whitespace-separated token of the line; false at its end. */
static bool next_token(struct tokens *t, struct span *s)
{
    while (t->p < t->end && is_blank(*t->p))
        t->p++;
    if (t->p == t->end)
        return false;
    s->begin = t->p;
    while (t->p < t->end && !is_blank(*t->p))
        t->p++;
    s->end = t->p;
    return true;
}

/* True when the token is exactly word. */
static bool span_is(struct span s, const char *word)
{
    size_t n = strlen(word);
    return (size_t)(s.end - s.begin) == n && memcmp(s.begin, word, n) == 0;
}

/* Token length for "%.*s" in messages, capped so one bad token cannot flood the line. */
static int span_print_length(struct span s)
{
    ptrdiff_t n = s.end - s.begin;
    return n < 40 ? (int)n : 40;
}

/* Parses a whole token as a number (strtod syntax); false when anything is left over. A token
 * always ends at a blank, a newline, '#' or the text's terminating NUL, where strtod stops. */
static bool parse_number(struct span s, double *out)
{
    char *stop;
    *out = strtod(s.begin, &stop);
    return stop == s.end;
}

/* Parses a whole token as a finite single-precision number. */
static bool parse_float(struct span s, float *out)
{
    char *stop;
    *out = strtof(s.begin, &stop);
    return stop == s.end && isfinite(*out);
}

/* Appends the fan triangulation (v0, vi, vi+1) of the polygon face (elements of any size, at
 * least 3) to triangles. */
static bool fan(struct array *triangles, const struct array *face)
{
    size_t size = face->size;
    unsigned char *out = array_append(triangles, 3 * (face->count - 2));
    if (!out)
        return false;
    for (size_t i = 1; i + 1 < face->count; i++, out += 3 * size) {
        memcpy(out, face->data, size);
        memcpy(out + size, face->data + i * size, 2 * size);
    }
    return true;
}

/* ------------------------------------------------------------------ normals */

/* The unit vector along (x, y, z) in single precision, or zero when its length is zero. */
static struct ao_vec3 unit(double x, double y, double z)
{
    double length = sqrt(x * x + y * y + z * z);
    if (length == 0.0)
        return ao_vec3_make(0.0f, 0.0f, 0.0f);
    return ao_vec3_make((float)(x / length), (float)(y / length), (float)(z / length));
}

/* A vertex position in double precision. */
static struct dvec position(const struct ao_mesh *mesh, uint32_t vertex)
{
    struct ao_vec3 p = mesh->positions[vertex];
    struct dvec d = {p.x, p.y, p.z};
    return d;
}

/* b - a. */
static struct dvec dsub(struct dvec b, struct dvec a)
{
    struct dvec d = {b.x - a.x, b.y - a.y, b.z - a.z};
    return d;
}

/* a . b */
static double ddot(struct dvec a, struct dvec b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

/* Twice the area vector of triangle t, (p1 - p0) x (p2 - p0), exact for float positions up
 * to one rounding; zero exactly when the triangle is degenerate. */
static struct dvec area_vector(const struct ao_mesh *mesh, size_t t)
{
    const uint32_t *v = mesh->indices + 3 * t;
    struct dvec p0 = position(mesh, v[0]);
    struct dvec a = dsub(position(mesh, v[1]), p0), b = dsub(position(mesh, v[2]), p0);
    struct dvec n = {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
    return n;
}

/* Removes zero-area triangles (a repeated index included), counting them. */
static void drop_degenerate(struct ao_mesh *mesh)
{
    size_t kept = 0;
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        struct dvec n = area_vector(mesh, t);
        if (ddot(n, n) == 0.0) {
            mesh->degenerate_count++;
            continue;
        }
        memmove(mesh->indices + 3 * kept, mesh->indices + 3 * t, 3 * sizeof *mesh->indices);
        kept++;
    }
    mesh->triangle_count = kept;
}

/* Angle-weighted vertex normals (Thürmer and Wüthrich 1998): each triangle adds its unit normal
 * times its interior angle at the vertex, so the result does not depend on how a surface is
 * split into triangles; the sum is then normalized. Vertices without a nondegenerate triangle
 * get the zero vector. Writes all mesh->vertex_count normals into out. */
static void angle_weighted_normals(const struct ao_mesh *mesh, struct ao_vec3 *out)
{
    memset(out, 0, mesh->vertex_count * sizeof *out);
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *v = mesh->indices + 3 * t;
        struct dvec n = area_vector(mesh, t);
        double twice_area = sqrt(ddot(n, n));
        if (twice_area == 0.0)
            continue;
        for (int k = 0; k < 3; k++) {
            struct dvec p = position(mesh, v[k]);
            struct dvec a = dsub(position(mesh, v[(k + 1) % 3]), p);
            struct dvec b = dsub(position(mesh, v[(k + 2) % 3]), p);
            /* |a x b| = twice the area at every corner, so atan2 gives the angle stably. */
            double weight = atan2(twice_area, ddot(a, b)) / twice_area;
            struct ao_vec3 add = ao_vec3_make((float)(n.x * weight), (float)(n.y * weight),
                                              (float)(n.z * weight));
            out[v[k]] = ao_vec3_add(out[v[k]], add);
        }
    }
    for (size_t i = 0; i < mesh->vertex_count; i++)
        out[i] = unit(out[i].x, out[i].y, out[i].z);
}

/* Allocates mesh->normals when missing and fills them all; false when memory runs out. */
static bool compute_all_normals(struct ao_mesh *mesh)
{
    if (mesh->vertex_count == 0)
        return true;
    if (!mesh->normals && !(mesh->normals = malloc(mesh->vertex_count * sizeof *mesh->normals)))
        return false;
    angle_weighted_normals(mesh, mesh->normals);
    return true;
}

bool ao_mesh_compute_normals(struct ao_mesh *mesh)
{
    if (compute_all_normals(mesh))
        return true;
    fprintf(stderr, "out of memory computing mesh normals\n");
    return false;
}

/* Gives the vertices flagged in lacking (which the file gave no normal) computed normals. */
static bool fill_lacking_normals(struct ao_mesh *mesh, const bool *lacking, const char *path)
{
    struct ao_vec3 *computed = malloc(mesh->vertex_count * sizeof *computed);
    if (!computed)
        return out_of_memory(path);
    angle_weighted_normals(mesh, computed);
    for (size_t i = 0; i < mesh->vertex_count; i++)
        if (lacking[i])
            mesh->normals[i] = computed[i];
    free(computed);
    return true;
}

/* Common end of both loaders: drops degenerate triangles, refuses a mesh without triangles and
 * computes the normals the file did not give (all when mesh->normals is NULL, else those
 * flagged in lacking, which may be NULL). */
static bool finish_mesh(struct ao_mesh *mesh, const char *path, const bool *lacking)
{
    drop_degenerate(mesh);
    if (mesh->triangle_count == 0) {
        report(path, 0, "no triangles (%zu degenerate ones skipped)", mesh->degenerate_count);
        return false;
    }
    if (!mesh->normals)
        return compute_all_normals(mesh) || out_of_memory(path);
    return lacking ? fill_lacking_normals(mesh, lacking, path) : true;
}

/* ------------------------------------------------------------------ OBJ */

/* One OBJ face corner: 0-based position and normal indices (normal NO_INDEX when absent). */
struct corner {
    uint32_t position, normal;
};

/* What an OBJ file has given so far, and where the reader is. */
struct obj_reader {
    const char *path;
    size_t line;
    struct array positions;   /* struct ao_vec3 */
    struct array normals;     /* struct ao_vec3, normalized */
    size_t texcoord_count;    /* vt lines, only to check indices */
    struct array face;        /* struct corner: the face being read */
    struct array corners;     /* struct corner: 3 per triangle */
    bool has_normals;         /* some corner references a normal */
};

/* Reads the rest of the line as at most 6 finite numbers into out, counting them. */
static bool read_floats(struct obj_reader *o, struct tokens *t, float *out, size_t *count,
                        const char *usage)
{
    struct span s;
    for (*count = 0; next_token(t, &s); ++*count) {
        if (*count == 6) {
            report(o->path, o->line, "too many numbers; expected %s", usage);
            return false;
        }
        if (!parse_float(s, &out[*count])) {
            report(o->path, o->line, "bad number '%.*s' (must be finite)", span_print_length(s),
                   s.begin);
            return false;
        }
    }
    return true;
}

/* "v x y z [w]" (or "v x y z r g b"). */
static bool parse_obj_vertex(struct obj_reader *o, struct tokens *t)
{
    float f[6];
    size_t n;
    if (!read_floats(o, t, f, &n, "'v x y z [w]'"))
        return false;
    if (n != 3 && n != 4 && n != 6) {
        report(o->path, o->line, "expected 'v x y z [w]', found %zu numbers", n);
        return false;
    }
    if (o->positions.count == NO_INDEX - 1) {
        report(o->path, o->line, "too many vertices for 32-bit indices");
        return false;
    }
    struct ao_vec3 *p = array_append(&o->positions, 1);
    if (!p)
        return out_of_memory(o->path);
    *p = ao_vec3_make(f[0], f[1], f[2]);
    return true;
}

/* "vn x y z", stored normalized (zero stays zero). */
static bool parse_obj_normal(struct obj_reader *o, struct tokens *t)
{
    float f[6];
    size_t n;
    if (!read_floats(o, t, f, &n, "'vn x y z'"))
        return false;
    if (n != 3) {
        report(o->path, o->line, "expected 'vn x y z', found %zu numbers", n);
        return false;
    }
    if (o->normals.count == NO_INDEX - 1) {
        report(o->path, o->line, "too many normals for 32-bit indices");
        return false;
    }
    struct ao_vec3 *normal = array_append(&o->normals, 1);
    if (!normal)
        return out_of_memory(o->path);
    *normal = unit(f[0], f[1], f[2]);
    return true;
}

/* Parses an optionally signed decimal integer at *p, stopping before end or a non-digit;
 * huge values saturate (they are out of range anyway). */
static bool parse_int(const char **p, const char *end, long long *out)
{
    const char *q = *p;
    bool negative = false;
    if (q < end && (*q == '-' || *q == '+'))
        negative = *q++ == '-';
    const char *digits = q;
    long long value = 0;
    for (; q < end && *q >= '0' && *q <= '9'; q++)
        value = value < INDEX_SATURATION ? value * 10 + (*q - '0') : value;
    if (q == digits)
        return false;
    *out = negative ? -value : value;
    *p = q;
    return true;
}

/* Splits a corner "v", "v/vt", "v//vn" or "v/vt/vn" into its three indices; 0 marks an absent
 * one, so a written 0 (OBJ counts from 1) is a syntax error here. */
static bool split_corner(struct span s, long long index[3])
{
    const char *p = s.begin;
    index[0] = index[1] = index[2] = 0;
    for (int field = 0; field < 3; field++) {
        if (field > 0) {
            if (p == s.end)
                return true;
            if (*p++ != '/')
                return false;
        }
        if (field == 1 && p < s.end && *p == '/')
            continue;
        if (!parse_int(&p, s.end, &index[field]) || index[field] == 0)
            return false;
    }
    return p == s.end;
}

/* Turns a 1-based or negative (relative to the count so far) OBJ index into a 0-based one. */
static bool resolve(long long index, size_t count, uint32_t *out)
{
    if (index > 0 && (unsigned long long)index <= count)
        *out = (uint32_t)(index - 1);
    else if (index < 0 && (unsigned long long)-index <= count)
        *out = (uint32_t)(count - (size_t)-index);
    else
        return false;
    return true;
}

/* Reports an out-of-range index of face corner s; returns false. */
static bool index_error(const struct obj_reader *o, struct span s, const char *what,
                        size_t count)
{
    report(o->path, o->line, "face corner '%.*s': %s index out of range (%zu defined so far)",
           span_print_length(s), s.begin, what, count);
    return false;
}

/* One face corner, its indices checked against what the file has defined up to this line. */
static bool parse_corner(struct obj_reader *o, struct span s, struct corner *c)
{
    long long index[3];
    uint32_t texcoord;
    if (!split_corner(s, index)) {
        report(o->path, o->line, "bad face corner '%.*s' (expected v, v/vt, v//vn or v/vt/vn "
               "with nonzero indices)", span_print_length(s), s.begin);
        return false;
    }
    if (!resolve(index[0], o->positions.count, &c->position))
        return index_error(o, s, "vertex", o->positions.count);
    if (index[1] && !resolve(index[1], o->texcoord_count, &texcoord))
        return index_error(o, s, "texture coordinate", o->texcoord_count);
    c->normal = NO_INDEX;
    if (index[2] && !resolve(index[2], o->normals.count, &c->normal))
        return index_error(o, s, "normal", o->normals.count);
    o->has_normals |= index[2] != 0;
    return true;
}

/* "f c1 c2 c3 ...": a polygon, fanned into triangles. */
static bool parse_obj_face(struct obj_reader *o, struct tokens *t)
{
    struct span s;
    o->face.count = 0;
    while (next_token(t, &s)) {
        if (o->face.count == MAX_FACE_VERTICES) {
            report(o->path, o->line, "face with more than %d vertices", MAX_FACE_VERTICES);
            return false;
        }
        struct corner *c = array_append(&o->face, 1);
        if (!c)
            return out_of_memory(o->path);
        if (!parse_corner(o, s, c))
            return false;
    }
    if (o->face.count < 3) {
        report(o->path, o->line, "face with %zu vertices; at least 3 needed", o->face.count);
        return false;
    }
    return fan(&o->corners, &o->face) || out_of_memory(o->path);
}

/* One line; '#' starts a comment, statements other than v, vn, vt and f are ignored. */
static bool parse_obj_line(struct obj_reader *o, const char *begin, const char *end)
{
    const char *hash = memchr(begin, '#', (size_t)(end - begin));
    struct tokens t = {begin, hash ? hash : end};
    struct span keyword;
    if (!next_token(&t, &keyword))
        return true;
    if (span_is(keyword, "v"))
        return parse_obj_vertex(o, &t);
    if (span_is(keyword, "vn"))
        return parse_obj_normal(o, &t);
    if (span_is(keyword, "f"))
        return parse_obj_face(o, &t);
    if (span_is(keyword, "vt"))
        o->texcoord_count++;
    return true;
}

/* Without any file normals: positions are the vertices, as in the file. */
static bool build_shared_vertices(struct obj_reader *o, struct ao_mesh *mesh)
{
    const struct corner *corners = (const struct corner *)o->corners.data;
    if (!(mesh->indices = malloc(o->corners.count * sizeof *mesh->indices)))
        return out_of_memory(o->path);
    for (size_t i = 0; i < o->corners.count; i++)
        mesh->indices[i] = corners[i].position;
    mesh->vertex_count = o->positions.count;
    mesh->positions = array_take(&o->positions);
    return finish_mesh(mesh, o->path, NULL);
}

/* Open-addressing hash map from a (position, normal) pair to the vertex made for it. */
struct vertex_map {
    struct vertex_slot {
        uint64_t key;       /* position << 32 | normal; UINT64_MAX when empty */
        uint32_t vertex;
    } *slots;
    size_t capacity, count; /* capacity is a power of two, at most half full */
};

/* The slot holding key, or the empty slot where it belongs. */
static struct vertex_slot *map_slot(const struct vertex_map *map, uint64_t key)
{
    uint64_t hash = key * 0x9E3779B97F4A7C15u;
    size_t mask = map->capacity - 1, i = (size_t)(hash ^ hash >> 29) & mask;
    while (map->slots[i].key != UINT64_MAX && map->slots[i].key != key)
        i = (i + 1) & mask;
    return &map->slots[i];
}

/* Makes room for one more entry, doubling and rehashing when half full. */
static bool map_reserve(struct vertex_map *map)
{
    if (2 * (map->count + 1) <= map->capacity)
        return true;
    struct vertex_map grown = {NULL, map->capacity ? 2 * map->capacity : 1024, map->count};
    if (grown.capacity > SIZE_MAX / sizeof *grown.slots ||
        !(grown.slots = malloc(grown.capacity * sizeof *grown.slots)))
        return false;
    memset(grown.slots, 0xff, grown.capacity * sizeof *grown.slots);
    for (size_t i = 0; i < map->capacity; i++)
        if (map->slots[i].key != UINT64_MAX)
            *map_slot(&grown, map->slots[i].key) = map->slots[i];
    free(map->slots);
    *map = grown;
    return true;
}

/* The output arrays of build_split_vertices. */
struct split_output {
    struct array positions, normals, lacking;   /* ao_vec3, ao_vec3, bool */
    size_t lacking_count;
};

/* The vertex for corner c, made (with its position and file normal) on first sight. */
static bool split_vertex(struct obj_reader *o, struct vertex_map *map, struct split_output *out,
                         struct corner c, uint32_t *vertex)
{
    uint64_t key = (uint64_t)c.position << 32 | c.normal;
    if (!map_reserve(map))
        return out_of_memory(o->path);
    struct vertex_slot *slot = map_slot(map, key);
    if (slot->key == key) {
        *vertex = slot->vertex;
        return true;
    }
    if (map->count == NO_INDEX - 1) {
        report(o->path, 0, "too many distinct vertices for 32-bit indices");
        return false;
    }
    struct ao_vec3 *p = array_append(&out->positions, 1), *n = array_append(&out->normals, 1);
    bool *lacking = array_append(&out->lacking, 1);
    if (!p || !n || !lacking)
        return out_of_memory(o->path);
    *p = ((const struct ao_vec3 *)o->positions.data)[c.position];
    *lacking = c.normal == NO_INDEX;
    out->lacking_count += *lacking;
    *n = *lacking ? ao_vec3_make(0.0f, 0.0f, 0.0f)
                  : ((const struct ao_vec3 *)o->normals.data)[c.normal];
    slot->key = key;
    slot->vertex = *vertex = (uint32_t)map->count++;
    return true;
}

/* With file normals: one vertex per distinct (position, normal) pair, so the mesh stays indexed
 * with one normal per vertex. Corners without a normal (a face without normals, or one with
 * normals on some corners only) share one vertex per position, whose normal is then computed
 * from the triangles using that vertex; file-normal vertices keep theirs. */
static bool build_split_vertices(struct obj_reader *o, struct ao_mesh *mesh)
{
    struct vertex_map map = {0};
    struct split_output out = {.positions = {.size = sizeof(struct ao_vec3)},
                               .normals = {.size = sizeof(struct ao_vec3)},
                               .lacking = {.size = sizeof(bool)}};
    const struct corner *corners = (const struct corner *)o->corners.data;
    bool ok = (mesh->indices = malloc(o->corners.count * sizeof *mesh->indices)) != NULL;
    if (!ok)
        out_of_memory(o->path);
    for (size_t i = 0; ok && i < o->corners.count; i++)
        ok = split_vertex(o, &map, &out, corners[i], &mesh->indices[i]);
    free(map.slots);
    if (ok) {
        mesh->vertex_count = out.positions.count;
        mesh->positions = array_take(&out.positions);
        mesh->normals = array_take(&out.normals);
        ok = finish_mesh(mesh, o->path,
                         out.lacking_count ? (const bool *)out.lacking.data : NULL);
    }
    array_free(&out.positions);
    array_free(&out.normals);
    array_free(&out.lacking);
    return ok;
}

/* Parses OBJ text line by line, then builds the indexed mesh. */
static bool load_obj(struct ao_mesh *mesh, const char *path, const char *text, size_t size)
{
    struct obj_reader o = {
        .path = path,
        .positions = {.size = sizeof(struct ao_vec3)},
        .normals = {.size = sizeof(struct ao_vec3)},
        .face = {.size = sizeof(struct corner)},
        .corners = {.size = sizeof(struct corner)},
    };
    const char *end = text + size;
    bool ok = true;
    for (const char *line = text; ok && line < end;) {
        const char *newline = memchr(line, '\n', (size_t)(end - line));
        const char *line_end = newline ? newline : end;
        o.line++;
        ok = parse_obj_line(&o, line, line_end);
        line = newline ? newline + 1 : end;
    }
    if (ok) {
        mesh->triangle_count = o.corners.count / 3;
        ok = o.has_normals ? build_split_vertices(&o, mesh) : build_shared_vertices(&o, mesh);
    }
    array_free(&o.positions);
    array_free(&o.normals);
    array_free(&o.face);
    array_free(&o.corners);
    return ok;
}

/* ------------------------------------------------------------------ PLY */

/* PLY scalar types, indexing ply_types. */
enum ply_type { PLY_INT8, PLY_UINT8, PLY_INT16, PLY_UINT16, PLY_INT32, PLY_UINT32, PLY_FLOAT32,
                PLY_FLOAT64, PLY_TYPE_COUNT };

/* Names (classic and sized alias), byte sizes and signedness of the PLY scalar types. */
static const struct {
    const char *name, *alias;
    unsigned size;
    bool is_signed_int;
} ply_types[PLY_TYPE_COUNT] = {
    [PLY_INT8] = {"char", "int8", 1, true},
    [PLY_UINT8] = {"uchar", "uint8", 1, false},
    [PLY_INT16] = {"short", "int16", 2, true},
    [PLY_UINT16] = {"ushort", "uint16", 2, false},
    [PLY_INT32] = {"int", "int32", 4, true},
    [PLY_UINT32] = {"uint", "uint32", 4, false},
    [PLY_FLOAT32] = {"float", "float32", 4, false},
    [PLY_FLOAT64] = {"double", "float64", 8, false},
};

/* What the loader does with a property's values. */
enum ply_role { ROLE_NONE, ROLE_X, ROLE_Y, ROLE_Z, ROLE_NX, ROLE_NY, ROLE_NZ, ROLE_INDICES,
                ROLE_COUNT };

/* Vertex property names by role. */
static const char *const role_names[ROLE_INDICES] = {NULL, "x", "y", "z", "nx", "ny", "nz"};

/* One "property" header line. */
struct ply_property {
    struct span name;
    bool is_list;
    enum ply_type count_type;   /* lists only */
    enum ply_type type;         /* of the value, or of each list item */
    enum ply_role role;
};

/* One "element" header line and its properties properties[first, first + property_count). */
struct ply_element {
    struct span name;
    uint64_t count;
    size_t line;
    size_t first, property_count;
};

/* A PLY file being read: the header's declarations and the cursor in the data. */
struct ply_reader {
    const char *path;
    bool binary;
    struct array elements;     /* struct ply_element */
    struct array properties;   /* struct ply_property */
    size_t vertex_element, face_element;  /* indices into elements, SIZE_MAX when absent */
    bool has_normals;
    const char *cur, *end;     /* unread data */
    size_t line;               /* header or ascii data line */
    size_t data_line;          /* the end_header line */
    struct tokens row;         /* ascii: the rest of the current row's line */
    const struct ply_element *element;  /* element being read, NULL in the header */
    uint64_t row_index;
    struct array positions, normals;    /* struct ao_vec3 */
    struct array face, indices;         /* uint32_t */
};

/* The reader's one error line, located by line (header, ascii) or element row (binary). */
static bool ply_error(const struct ply_reader *r, const char *format, ...)
{
    char message[400];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    if (r->binary && r->element)
        report(r->path, 0, "%.*s %llu: %s", span_print_length(r->element->name),
               r->element->name.begin, (unsigned long long)r->row_index, message);
    else
        report(r->path, r->line, "%s", message);
    return false;
}

/* The element at index i. */
static struct ply_element *element_at(const struct ply_reader *r, size_t i)
{
    return (struct ply_element *)r->elements.data + i;
}

/* The property at index i. */
static struct ply_property *property_at(const struct ply_reader *r, size_t i)
{
    return (struct ply_property *)r->properties.data + i;
}

/* Takes exactly n more tokens from the line, else reports usage. */
static bool take_tokens(const struct ply_reader *r, struct tokens *t, struct span *out, size_t n,
                        const char *usage)
{
    struct span extra;
    for (size_t i = 0; i < n; i++)
        if (!next_token(t, &out[i]))
            return ply_error(r, "expected '%s'", usage);
    return !next_token(t, &extra) || ply_error(r, "expected '%s'", usage);
}

/* "format ascii|binary_little_endian 1.0". */
static bool parse_format(struct ply_reader *r, struct tokens *t, bool *have_format)
{
    struct span s[2];
    if (!take_tokens(r, t, s, 2, "format ascii|binary_little_endian 1.0"))
        return false;
    if (*have_format)
        return ply_error(r, "second format line");
    if (span_is(s[0], "binary_big_endian"))
        return ply_error(r, "big-endian binary PLY is not supported; convert it to "
                         "binary_little_endian or ascii");
    if (!span_is(s[0], "ascii") && !span_is(s[0], "binary_little_endian"))
        return ply_error(r, "unknown PLY format '%.*s'", span_print_length(s[0]), s[0].begin);
    if (!span_is(s[1], "1.0"))
        return ply_error(r, "unsupported PLY version '%.*s'", span_print_length(s[1]),
                         s[1].begin);
    r->binary = span_is(s[0], "binary_little_endian");
    *have_format = true;
    return true;
}

/* A decimal count without sign, as in "element vertex 8". */
static bool parse_count(struct span s, uint64_t *out)
{
    uint64_t value = 0;
    for (const char *p = s.begin; p < s.end; p++) {
        if (*p < '0' || *p > '9' || value > (UINT64_MAX - 9) / 10)
            return false;
        value = value * 10 + (uint64_t)(*p - '0');
    }
    *out = value;
    return s.begin < s.end;
}

/* "element NAME COUNT". */
static bool parse_element(struct ply_reader *r, struct tokens *t)
{
    struct span s[2];
    if (!take_tokens(r, t, s, 2, "element NAME COUNT"))
        return false;
    struct ply_element *e = array_append(&r->elements, 1);
    if (!e)
        return out_of_memory(r->path);
    *e = (struct ply_element){s[0], 0, r->line, r->properties.count, 0};
    return parse_count(s[1], &e->count) ||
           ply_error(r, "bad element count '%.*s'", span_print_length(s[1]), s[1].begin);
}

/* Looks a type name up. */
static bool parse_type(const struct ply_reader *r, struct span s, enum ply_type *type)
{
    for (int i = 0; i < PLY_TYPE_COUNT; i++) {
        if (span_is(s, ply_types[i].name) || span_is(s, ply_types[i].alias)) {
            *type = (enum ply_type)i;
            return true;
        }
    }
    return ply_error(r, "unknown property type '%.*s'", span_print_length(s), s.begin);
}

/* "property TYPE NAME" or "property list COUNT_TYPE ITEM_TYPE NAME". */
static bool parse_property(struct ply_reader *r, struct tokens *t)
{
    struct span s[4];
    struct tokens probe = *t;
    bool is_list = next_token(&probe, &s[0]) && span_is(s[0], "list");
    if (r->elements.count == 0)
        return ply_error(r, "property before any element");
    if (is_list ? !take_tokens(r, t, s, 4, "property list COUNT_TYPE ITEM_TYPE NAME")
                : !take_tokens(r, t, s + 2, 2, "property TYPE NAME"))
        return false;
    struct ply_property p = {s[3], is_list, PLY_UINT8, PLY_UINT8, ROLE_NONE};
    if ((is_list && !parse_type(r, s[1], &p.count_type)) || !parse_type(r, s[2], &p.type))
        return false;
    struct ply_property *slot = array_append(&r->properties, 1);
    if (!slot)
        return out_of_memory(r->path);
    *slot = p;
    element_at(r, r->elements.count - 1)->property_count++;
    return true;
}

/* One header line after "ply"; sets *done at "end_header". */
static bool parse_header_line(struct ply_reader *r, struct tokens *t, bool *have_format,
                              bool *done)
{
    struct span keyword;
    if (!next_token(t, &keyword) || span_is(keyword, "comment") || span_is(keyword, "obj_info"))
        return true;
    if (span_is(keyword, "format"))
        return parse_format(r, t, have_format);
    if (span_is(keyword, "element"))
        return parse_element(r, t);
    if (span_is(keyword, "property"))
        return parse_property(r, t);
    if (span_is(keyword, "end_header")) {
        *done = true;
        return take_tokens(r, t, NULL, 0, "end_header") &&
               (*have_format || ply_error(r, "no format line before end_header"));
    }
    return ply_error(r, "unknown header keyword '%.*s'", span_print_length(keyword),
                     keyword.begin);
}

/* The header, from "ply" to "end_header"; leaves r->cur at the first data byte. */
static bool parse_ply_header(struct ply_reader *r, const char *text, size_t size)
{
    const char *end = text + size, *line = text;
    bool have_format = false, done = false;
    while (!done) {
        if (line == end)
            return ply_error(r, r->line ? "header ends without end_header" : "empty file");
        const char *newline = memchr(line, '\n', (size_t)(end - line));
        struct tokens t = {line, newline ? newline : end};
        struct span magic;
        line = newline ? newline + 1 : end;
        if (++r->line == 1) {
            if (!next_token(&t, &magic) || !span_is(magic, "ply") || next_token(&t, &magic))
                return ply_error(r, "not a PLY file (no 'ply' first line)");
        } else if (!parse_header_line(r, &t, &have_format, &done)) {
            return false;
        }
    }
    r->cur = line;
    r->end = end;
    r->data_line = r->line;
    return true;
}

/* Finds the element named name; reports a second one. */
static bool find_element(struct ply_reader *r, const char *name, size_t *index)
{
    *index = SIZE_MAX;
    for (size_t i = 0; i < r->elements.count; i++) {
        if (!span_is(element_at(r, i)->name, name))
            continue;
        if (*index != SIZE_MAX) {
            r->line = element_at(r, i)->line;
            return ply_error(r, "second '%s' element", name);
        }
        *index = i;
    }
    r->line = 0;
    return *index != SIZE_MAX || ply_error(r, "no '%s' element in the header", name);
}

/* Gives the property of element e named name the role, checking it is unique and scalar or list
 * as required; *found counts the roles given. */
static bool assign_role(struct ply_reader *r, const struct ply_element *e, const char *name,
                        enum ply_role role, bool list, int *found)
{
    bool seen = false;
    r->line = e->line;
    for (size_t i = e->first; i < e->first + e->property_count; i++) {
        struct ply_property *p = property_at(r, i);
        if (!span_is(p->name, name))
            continue;
        if (seen)
            return ply_error(r, "element '%.*s' has two '%s' properties",
                             span_print_length(e->name), e->name.begin, name);
        if (p->is_list != list)
            return ply_error(r, "property '%s' must be a %s", name, list ? "list" : "scalar");
        p->role = role;
        seen = true;
    }
    *found += seen;
    return true;
}

/* Finds the vertex and face elements and the properties the loader uses. */
static bool assign_roles(struct ply_reader *r)
{
    int positions = 0, normals = 0, indices = 0;
    if (!find_element(r, "vertex", &r->vertex_element) ||
        !find_element(r, "face", &r->face_element))
        return false;
    const struct ply_element *vertex = element_at(r, r->vertex_element);
    const struct ply_element *face = element_at(r, r->face_element);
    for (int role = ROLE_X; role < ROLE_INDICES; role++)
        if (!assign_role(r, vertex, role_names[role], role, false,
                         role < ROLE_NX ? &positions : &normals))
            return false;
    if (!assign_role(r, face, "vertex_indices", ROLE_INDICES, true, &indices) ||
        !assign_role(r, face, "vertex_index", ROLE_INDICES, true, &indices))
        return false;
    r->line = vertex->line;
    if (positions != 3)
        return ply_error(r, "vertex element needs x, y and z properties");
    if (normals != 0 && normals != 3)
        return ply_error(r, "vertex normals need all of nx, ny and nz");
    if (vertex->count >= NO_INDEX)
        return ply_error(r, "%llu vertices are too many for 32-bit indices",
                         (unsigned long long)vertex->count);
    r->line = face->line;
    if (indices != 1)
        return ply_error(r, "face element needs one list property vertex_indices");
    r->has_normals = normals == 3;
    return true;
}

/* Binary files: refuses a header whose rows cannot fit in the bytes after it, before anything
 * is allocated for them (a 100-byte file may claim 4 billion vertices). */
static bool check_binary_size(struct ply_reader *r)
{
    uint64_t left = (uint64_t)(r->end - r->cur);
    for (size_t i = 0; i < r->elements.count; i++) {
        const struct ply_element *e = element_at(r, i);
        uint64_t row = 0;
        for (size_t j = e->first; j < e->first + e->property_count; j++) {
            const struct ply_property *p = property_at(r, j);
            row += ply_types[p->is_list ? p->count_type : p->type].size;
        }
        if (row && e->count > left / row) {
            r->line = e->line;
            return ply_error(r, "element '%.*s' declares %llu rows of at least %llu bytes, but "
                             "only %llu bytes of data remain in the file",
                             span_print_length(e->name), e->name.begin,
                             (unsigned long long)e->count, (unsigned long long)row,
                             (unsigned long long)left);
        }
        left -= e->count * row;
    }
    return true;
}

/* Decodes the little-endian bytes of one value of a PLY type. */
static double decode(enum ply_type type, const unsigned char *bytes)
{
    unsigned size = ply_types[type].size;
    uint64_t bits = 0;
    for (unsigned i = size; i-- > 0;)
        bits = bits << 8 | bytes[i];
    if (type == PLY_FLOAT32) {
        uint32_t word = (uint32_t)bits;
        float f;
        memcpy(&f, &word, sizeof f);
        return f;
    }
    if (type == PLY_FLOAT64) {
        double d;
        memcpy(&d, &bits, sizeof d);
        return d;
    }
    double value = (double)bits;
    if (ply_types[type].is_signed_int && bits >> (8 * size - 1))
        value -= ldexp(1.0, (int)(8 * size));
    return value;
}

/* Reads one value of the given type (binary), or the row's next number (ascii). */
static bool read_value(struct ply_reader *r, enum ply_type type, double *out)
{
    struct span s;
    if (r->binary) {
        if ((size_t)(r->end - r->cur) < ply_types[type].size)
            return ply_error(r, "unexpected end of file");
        *out = decode(type, (const unsigned char *)r->cur);
        r->cur += ply_types[type].size;
        return true;
    }
    if (!next_token(&r->row, &s))
        return ply_error(r, "too few values for a '%.*s' row", span_print_length(r->element->name),
                         r->element->name.begin);
    return parse_number(s, out) ||
           ply_error(r, "bad number '%.*s'", span_print_length(s), s.begin);
}

/* Ascii: moves to the next non-blank line, which holds one row. */
static bool begin_row(struct ply_reader *r)
{
    struct span s;
    struct tokens probe;
    if (r->binary)
        return true;
    do {
        if (r->cur == r->end)
            return ply_error(r, "unexpected end of file: '%.*s' declares %llu rows, found %llu",
                             span_print_length(r->element->name), r->element->name.begin,
                             (unsigned long long)r->element->count,
                             (unsigned long long)r->row_index);
        const char *newline = memchr(r->cur, '\n', (size_t)(r->end - r->cur));
        r->row = (struct tokens){r->cur, newline ? newline : r->end};
        r->cur = newline ? newline + 1 : r->end;
        r->line++;
        probe = r->row;
    } while (!next_token(&probe, &s));
    return true;
}

/* Ascii: the row's line must hold nothing more. */
static bool end_row(struct ply_reader *r)
{
    struct span s;
    return r->binary || !next_token(&r->row, &s) ||
           ply_error(r, "more values than the header declares for a '%.*s' row",
                     span_print_length(r->element->name), r->element->name.begin);
}

/* A vertex index from a face list: integral and below the declared vertex count. */
static bool add_index(struct ply_reader *r, double value)
{
    uint64_t vertices = element_at(r, r->vertex_element)->count;
    if (!(value >= 0.0 && value < (double)vertices && value == floor(value)))
        return ply_error(r, "vertex index %.17g is not an integer in [0, %llu)", value,
                         (unsigned long long)vertices);
    uint32_t *slot = array_append(&r->face, 1);
    if (!slot)
        return out_of_memory(r->path);
    *slot = (uint32_t)value;
    return true;
}

/* A list property: its count, then the items (vertex indices kept, others skipped). */
static bool read_list(struct ply_reader *r, const struct ply_property *p)
{
    double count, item;
    if (!read_value(r, p->count_type, &count))
        return false;
    if (!(count >= 0.0 && count <= UINT32_MAX && count == floor(count)))
        return ply_error(r, "bad list count %.17g", count);
    if (r->binary && count > (double)((size_t)(r->end - r->cur) / ply_types[p->type].size))
        return ply_error(r, "list of %.0f items runs past the end of the file", count);
    if (p->role == ROLE_INDICES && count > MAX_FACE_VERTICES)
        return ply_error(r, "face with %.0f vertices (more than %d)", count, MAX_FACE_VERTICES);
    for (uint32_t i = 0; i < (uint32_t)count; i++)
        if (!read_value(r, p->type, &item) || (p->role == ROLE_INDICES && !add_index(r, item)))
            return false;
    return true;
}

/* One row of element e: scalar values by role into values, face indices into r->face. */
static bool read_row(struct ply_reader *r, const struct ply_element *e, double values[ROLE_COUNT])
{
    if (!begin_row(r))
        return false;
    for (size_t i = e->first; i < e->first + e->property_count; i++) {
        const struct ply_property *p = property_at(r, i);
        if (p->is_list ? !read_list(r, p) : !read_value(r, p->type, &values[p->role]))
            return false;
    }
    return end_row(r);
}

/* Stores a vertex row: a finite position and, when present, a finite normal (normalized). */
static bool add_vertex(struct ply_reader *r, const double v[ROLE_COUNT])
{
    struct ao_vec3 p = ao_vec3_make((float)v[ROLE_X], (float)v[ROLE_Y], (float)v[ROLE_Z]);
    if (!ao_vec3_is_finite(p))
        return ply_error(r, "vertex position is not a finite float");
    struct ao_vec3 *slot = array_append(&r->positions, 1);
    if (!slot)
        return out_of_memory(r->path);
    *slot = p;
    if (!r->has_normals)
        return true;
    if (!isfinite(v[ROLE_NX]) || !isfinite(v[ROLE_NY]) || !isfinite(v[ROLE_NZ]))
        return ply_error(r, "vertex normal is not finite");
    if (!(slot = array_append(&r->normals, 1)))
        return out_of_memory(r->path);
    *slot = unit(v[ROLE_NX], v[ROLE_NY], v[ROLE_NZ]);
    return true;
}

/* Stores a face row's polygon as a triangle fan. */
static bool add_face(struct ply_reader *r)
{
    if (r->face.count < 3)
        return ply_error(r, "face with %zu vertices; at least 3 needed", r->face.count);
    return fan(&r->indices, &r->face) || out_of_memory(r->path);
}

/* Every row of every element, in header order. */
static bool read_elements(struct ply_reader *r)
{
    r->line = r->data_line;
    for (size_t i = 0; i < r->elements.count; i++) {
        r->element = element_at(r, i);
        /* An element without properties has no bytes, whatever its count. */
        if (r->element->property_count == 0)
            continue;
        for (r->row_index = 0; r->row_index < r->element->count; r->row_index++) {
            double values[ROLE_COUNT] = {0};
            r->face.count = 0;
            if (!read_row(r, r->element, values) ||
                (i == r->vertex_element && !add_vertex(r, values)) ||
                (i == r->face_element && !add_face(r)))
                return false;
        }
    }
    return true;
}

/* After the last element only blank lines (ascii) or nothing (binary) may follow, else the
 * header's counts are wrong. */
static bool check_trailing_data(struct ply_reader *r)
{
    r->element = NULL;
    if (r->binary) {
        r->line = 0;
        return r->cur == r->end ||
               ply_error(r, "%zu bytes after the last element; the header's counts are wrong",
                         (size_t)(r->end - r->cur));
    }
    for (const char *p = r->cur; p < r->end; p++) {
        if (*p != '\n' && !is_blank(*p)) {
            r->line++;
            return ply_error(r, "data after the last element; the header's counts are wrong");
        }
        r->line += *p == '\n';
    }
    return true;
}

/* Parses a PLY header and its ascii or binary little-endian data into mesh. */
static bool load_ply(struct ao_mesh *mesh, const char *path, const char *text, size_t size)
{
    struct ply_reader r = {
        .path = path,
        .elements = {.size = sizeof(struct ply_element)},
        .properties = {.size = sizeof(struct ply_property)},
        .positions = {.size = sizeof(struct ao_vec3)},
        .normals = {.size = sizeof(struct ao_vec3)},
        .face = {.size = sizeof(uint32_t)},
        .indices = {.size = sizeof(uint32_t)},
    };
    bool ok = parse_ply_header(&r, text, size) && assign_roles(&r) &&
              (!r.binary || check_binary_size(&r)) && read_elements(&r) &&
              check_trailing_data(&r);
    if (ok) {
        mesh->vertex_count = r.positions.count;
        mesh->positions = array_take(&r.positions);
        mesh->normals = array_take(&r.normals);
        mesh->triangle_count = r.indices.count / 3;
        mesh->indices = array_take(&r.indices);
        ok = finish_mesh(mesh, path, NULL);
    }
    array_free(&r.elements);
    array_free(&r.properties);
    array_free(&r.positions);
    array_free(&r.normals);
    array_free(&r.face);
    array_free(&r.indices);
    return ok;
}

/* ------------------------------------------------------------------ entry points */

/* A format's loader: parses a file's text (NUL-terminated, size bytes) into mesh. */
typedef bool loader(struct ao_mesh *mesh, const char *path, const char *text, size_t size);

/* The loader for path's extension (.obj or .ply, any case), or NULL. */
static loader *loader_for(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (!dot || strchr(dot, '/'))
        return NULL;
    if (strcasecmp(dot, ".obj") == 0)
        return load_obj;
    if (strcasecmp(dot, ".ply") == 0)
        return load_ply;
    return NULL;
}

bool ao_mesh_load(struct ao_mesh *mesh, const char *path)
{
    memset(mesh, 0, sizeof *mesh);
    loader *load = loader_for(path);
    char *text;
    size_t size;
    if (!load) {
        report(path, 0, "unknown mesh format; expected a .obj or .ply file");
        return false;
    }
    if (!ao_file_read(path, &text, &size))
        return false;
    bool ok = load(mesh, path, text, size);
    free(text);
    if (!ok)
        ao_mesh_finish(mesh);
    return ok;
}

void ao_mesh_finish(struct ao_mesh *mesh)
{
    free(mesh->positions);
    free(mesh->normals);
    free(mesh->indices);
    memset(mesh, 0, sizeof *mesh);
}
