/* STL, binary and ASCII. A file is binary when its size is exactly 84 + 50·n bytes for the
 * triangle count n its header gives (many binary files begin with "solid" too, so that prefix
 * decides nothing); otherwise it must be ASCII ("solid ... facet ... outer loop ... vertex x y z
 * ... endloop endfacet ... endsolid", loops of more than 3 vertices fanned). STL repeats each
 * vertex in every triangle that uses it: equal positions are welded into one vertex through a
 * hash, so that the computed vertex normals are shared and Phong shading works. Facet normals are
 * ignored (the normals are computed from the welded triangles). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loader.h"
#include "text.h"

/* Bytes of the binary header, of its triangle count and of one triangle record. */
enum { BINARY_HEADER = 80, BINARY_PREFIX = 84, BINARY_RECORD = 50 };

/* Welded vertices: positions, and an open-addressing hash set of their indices. */
struct weld {
    struct ao_load_array positions;  /* struct ao_vec3 */
    uint32_t *slots;                 /* vertex index, or AO_LOAD_NO_INDEX when empty */
    size_t capacity;                 /* a power of two, at most half full */
    const struct ao_load_array *corners;  /* the mesh's triangle corners so far */
    const struct ao_budget *budget;  /* checked as vertices are made */
};

/* The hash of a position's bits (after -0 became +0). */
static size_t hash_position(struct ao_vec3 p)
{
    uint32_t bits[3];
    memcpy(&bits[0], &p.x, 4);
    memcpy(&bits[1], &p.y, 4);
    memcpy(&bits[2], &p.z, 4);
    uint64_t h = bits[0] * 0x9E3779B97F4A7C15u;
    h = (h ^ h >> 29 ^ bits[1]) * 0xBF58476D1CE4E5B9u;
    h = (h ^ h >> 31 ^ bits[2]) * 0x94D049BB133111EBu;
    return (size_t)(h ^ h >> 32);
}

/* The slot holding a vertex at position p, or the empty slot where it belongs. */
static uint32_t *weld_slot(const struct weld *w, struct ao_vec3 p)
{
    const struct ao_vec3 *positions = (const struct ao_vec3 *)w->positions.data;
    size_t mask = w->capacity - 1, i = hash_position(p) & mask;
    while (w->slots[i] != AO_LOAD_NO_INDEX && memcmp(&positions[w->slots[i]], &p, sizeof p) != 0)
        i = (i + 1) & mask;
    return &w->slots[i];
}

/* Makes room for one more vertex, doubling and rehashing when half full. */
static bool weld_reserve(struct weld *w)
{
    if (2 * (w->positions.count + 1) <= w->capacity)
        return true;
    struct weld grown = {w->positions, NULL, w->capacity ? 2 * w->capacity : 1024, w->corners, w->budget};
    if (grown.capacity > SIZE_MAX / sizeof *grown.slots ||
        !(grown.slots = malloc(grown.capacity * sizeof *grown.slots)))
        return false;
    memset(grown.slots, 0xff, grown.capacity * sizeof *grown.slots);
    const struct ao_vec3 *positions = (const struct ao_vec3 *)w->positions.data;
    for (size_t i = 0; i < w->capacity; i++)
        if (w->slots[i] != AO_LOAD_NO_INDEX)
            *weld_slot(&grown, positions[w->slots[i]]) = w->slots[i];
    free(w->slots);
    *w = grown;
    return true;
}

/* Appends to indices the vertex at the finite position p, made on first sight. */
static bool weld_vertex(struct weld *w, struct ao_vec3 p, struct ao_load_array *indices,
                        const char *path, size_t line)
{
    /* -0 and +0 are one position: adding +0 turns -0 into +0 and changes nothing else. */
    p = ao_vec3_make(p.x + 0.0f, p.y + 0.0f, p.z + 0.0f);
    if (!weld_reserve(w))
        return ao_load_out_of_memory(path);
    uint32_t *slot = weld_slot(w, p);
    if (*slot == AO_LOAD_NO_INDEX) {
        if (w->positions.count == AO_LOAD_NO_INDEX - 1) {
            ao_text_report_at(path, line, "too many distinct vertices for 32-bit indices");
            return false;
        }
        if (!ao_mesh_fits(w->budget, w->corners->count / 3 + 1, w->positions.count + 1, path, line))
            return false;
        struct ao_vec3 *stored = ao_load_append(&w->positions, 1);
        if (!stored)
            return ao_load_out_of_memory(path);
        *stored = p;
        *slot = (uint32_t)(w->positions.count - 1);
    }
    uint32_t *index = ao_load_append(indices, 1);
    if (!index)
        return ao_load_out_of_memory(path);
    *index = *slot;
    return true;
}

/* A little-endian 32-bit word. */
static uint32_t le32(const char *bytes)
{
    const unsigned char *b = (const unsigned char *)bytes;
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* A little-endian IEEE single. */
static float le_float(const char *bytes)
{
    uint32_t word = le32(bytes);
    float f;
    memcpy(&f, &word, sizeof f);
    return f;
}

/* Binary: n records of a normal, three vertices and an attribute word. */
static bool read_binary(struct weld *w, struct ao_load_array *indices, const char *path,
                        const char *text, uint32_t n)
{
    for (uint32_t t = 0; t < n; t++) {
        const char *record = text + BINARY_PREFIX + (size_t)t * BINARY_RECORD;
        for (int k = 0; k < 3; k++) {
            const char *v = record + 12 + 12 * k;
            struct ao_vec3 p = ao_vec3_make(le_float(v), le_float(v + 4), le_float(v + 8));
            if (!ao_vec3_is_finite(p)) {
                ao_text_report_at(path, 0, "triangle %u: vertex position is not a finite float", t);
                return false;
            }
            if (!weld_vertex(w, p, indices, path, 0))
                return false;
        }
    }
    return true;
}

/* Where an ASCII reader is. */
struct ascii_reader {
    const char *path;
    size_t line;
    bool in_solid, in_facet, in_loop;
    size_t facet_loops;                /* loops in the open facet */
    size_t polygons;                   /* loops of more than 3 vertices, fanned */
    struct ao_load_array loop;         /* uint32_t: welded vertices of the open loop */
};

/* Reports at the reader's line; returns false. */
static bool ascii_error(const struct ascii_reader *r, const char *message)
{
    ao_text_report_at(r->path, r->line, "%s", message);
    return false;
}

/* "vertex x y z" inside a loop. */
static bool ascii_vertex(struct ascii_reader *r, struct ao_load_tokens *t, struct weld *w)
{
    struct ao_load_span s;
    float f[3];
    if (!r->in_loop)
        return ascii_error(r, "'vertex' outside 'outer loop'");
    for (int i = 0; i < 3; i++) {
        if (!ao_load_next_token(t, &s))
            return ascii_error(r, "expected 'vertex x y z'");
        if (!ao_load_parse_float(s, &f[i])) {
            ao_text_report_at(r->path, r->line, "bad number '%.*s' (must be a finite float)",
                           ao_load_span_length(s), s.begin);
            return false;
        }
    }
    if (ao_load_next_token(t, &s))
        return ascii_error(r, "expected 'vertex x y z'");
    if (r->loop.count == AO_LOAD_MAX_FACE_VERTICES) {
        ao_text_report_at(r->path, r->line, "loop with more than %d vertices",
                       AO_LOAD_MAX_FACE_VERTICES);
        return false;
    }
    return weld_vertex(w, ao_vec3_make(f[0], f[1], f[2]), &r->loop, r->path, r->line);
}

/* One line: its keyword moves the reader between solid, facet and loop. */
static bool ascii_line(struct ascii_reader *r, struct ao_load_tokens *t, struct weld *w,
                       struct ao_load_array *indices)
{
    struct ao_load_span keyword, word;
    if (!ao_load_next_token(t, &keyword))
        return true;
    if (ao_load_span_is(keyword, "vertex"))
        return ascii_vertex(r, t, w);
    if (ao_load_span_is(keyword, "solid")) {
        if (r->in_solid)
            return ascii_error(r, "'solid' inside a solid");
        r->in_solid = true;
        return true;
    }
    if (ao_load_span_is(keyword, "endsolid")) {
        if (!r->in_solid || r->in_facet)
            return ascii_error(r, r->in_facet ? "'endsolid' inside a facet"
                                              : "'endsolid' without 'solid'");
        r->in_solid = false;
        return true;
    }
    if (ao_load_span_is(keyword, "facet")) {
        if (!r->in_solid || r->in_facet)
            return ascii_error(r, r->in_facet ? "'facet' inside a facet"
                                              : "'facet' outside 'solid'");
        r->in_facet = true;
        r->facet_loops = 0;
        return true;
    }
    if (ao_load_span_is(keyword, "outer")) {
        if (!ao_load_next_token(t, &word) || !ao_load_span_is(word, "loop") ||
            ao_load_next_token(t, &word))
            return ascii_error(r, "expected 'outer loop'");
        if (!r->in_facet || r->in_loop || r->facet_loops)
            return ascii_error(r, "'outer loop' must open a facet's one loop");
        r->in_loop = true;
        r->loop.count = 0;
        return true;
    }
    if (ao_load_span_is(keyword, "endloop")) {
        if (!r->in_loop)
            return ascii_error(r, "'endloop' without 'outer loop'");
        if (r->loop.count < 3) {
            ao_text_report_at(r->path, r->line, "loop with %zu vertices; at least 3 needed",
                           r->loop.count);
            return false;
        }
        r->in_loop = false;
        r->facet_loops++;
        r->polygons += r->loop.count > 3;
        if (!ao_mesh_fits(w->budget, indices->count / 3 + r->loop.count - 2, w->positions.count, r->path,
                          r->line))
            return false;
        return ao_load_fan(indices, &r->loop) || ao_load_out_of_memory(r->path);
    }
    if (ao_load_span_is(keyword, "endfacet")) {
        if (!r->in_facet || r->in_loop || !r->facet_loops)
            return ascii_error(r, "'endfacet' without a facet and its closed loop");
        r->in_facet = false;
        return true;
    }
    ao_text_report_at(r->path, r->line, "unknown STL keyword '%.*s'", ao_load_span_length(keyword),
                   keyword.begin);
    return false;
}

/* ASCII: line by line, then the file must not end inside a solid's facet or loop. What the format
 * does not allow but can be read, a loop of more than 3 vertices (fanned) and a last solid without
 * 'endsolid' (the file may have been cut between facets), is said in note. */
static bool read_ascii(struct weld *w, struct ao_load_array *indices, const char *path,
                       const char *text, size_t size, char note[AO_MESH_NOTE_SIZE])
{
    struct ascii_reader r = {.path = path, .loop = {.size = sizeof(uint32_t)}};
    const char *end = text + size;
    bool ok = true;
    for (const char *line = text; ok && line < end;) {
        const char *newline = memchr(line, '\n', (size_t)(end - line));
        struct ao_load_tokens t = {line, newline ? newline : end};
        r.line++;
        ok = ascii_line(&r, &t, w, indices);
        line = newline ? newline + 1 : end;
    }
    if (ok && (r.in_facet || r.in_loop))
        ok = ascii_error(&r, "file ends inside a facet");
    if (ok && r.polygons)
        snprintf(note, AO_MESH_NOTE_SIZE, "%zu facet%s of more than 3 vertices fanned into triangles (STL's facets "
                 "are triangles)%s", r.polygons, r.polygons == 1 ? "" : "s", r.in_solid ? "; " : "");
    if (ok && r.in_solid)
        snprintf(note + strlen(note), AO_MESH_NOTE_SIZE - strlen(note),
                 "no 'endsolid' after its last solid (the file may be cut short)");
    ao_load_free(&r.loop);
    return ok;
}

/* True when the text begins, after blanks and newlines, with the word "solid". */
static bool starts_with_solid(const char *text, size_t size)
{
    size_t i = 0;
    while (i < size && (text[i] == '\n' || ao_load_is_blank(text[i])))
        i++;
    return size - i >= 5 && memcmp(text + i, "solid", 5) == 0;
}

bool ao_load_stl(struct ao_mesh *mesh, const char *path, const char *text, size_t size,
                 struct ao_budget *budget)
{
    struct ao_load_array indices = {.size = sizeof(uint32_t)};
    struct weld w = {.positions = {.size = sizeof(struct ao_vec3)}, .corners = &indices, .budget = budget};
    uint32_t n = size >= BINARY_PREFIX ? le32(text + BINARY_HEADER) : 0;
    bool binary = size >= BINARY_PREFIX &&
                  (uint64_t)size == BINARY_PREFIX + (uint64_t)n * BINARY_RECORD;
    bool ok;
    if (binary) {
        /* The header's count is real (the file's size matches it): check it before reading. */
        ok = ao_mesh_fits(budget, n, 0, path, 0) && read_binary(&w, &indices, path, text, n);
    } else if (starts_with_solid(text, size) && strlen(text) == size) {
        ok = read_ascii(&w, &indices, path, text, size, mesh->note);
    } else if (size < BINARY_PREFIX) {
        ao_text_report_at(path, 0, "neither ASCII STL (no 'solid') nor binary (%zu bytes, fewer "
                       "than the 84 of a header)", size);
        ok = false;
    } else {
        ao_text_report_at(path, 0, "binary STL header declares %u triangles (%llu bytes) but the "
                       "file has %zu bytes", n,
                       (unsigned long long)(BINARY_PREFIX + (uint64_t)n * BINARY_RECORD), size);
        ok = false;
    }
    if (ok) {
        mesh->vertex_count = w.positions.count;
        mesh->positions = ao_load_take(&w.positions);
        mesh->triangle_count = indices.count / 3;
        mesh->indices = ao_load_take(&indices);
        ok = ao_load_finish(mesh, path);
    }
    ao_load_free(&w.positions);
    free(w.slots);
    ao_load_free(&indices);
    return ok;
}
