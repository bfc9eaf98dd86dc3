/* OBJ: v, vn, f (polygons fanned; v, v/vt, v//vn and v/vt/vn corners; negative indices); other
 * statements ignored. The text is parsed line by line into growth arrays, then indexed: one vertex
 * per position without file normals, else one per distinct (position, normal) pair. */
#include <stdlib.h>
#include <string.h>

#include "loader.h"
#include "text.h"

/* Parsed indices saturate here, far above any possible vertex count. */
#define INDEX_SATURATION 1000000000000000LL

/* One OBJ face corner: 0-based position and normal indices (normal AO_LOAD_NO_INDEX when absent). */
struct corner {
    uint32_t position, normal;
};

/* What an OBJ file has given so far, and where the reader is. */
struct obj_reader {
    const char *path;
    size_t line;
    struct ao_load_array positions;   /* struct ao_vec3 */
    struct ao_load_array normals;     /* struct ao_vec3, normalized */
    size_t texcoord_count;    /* vt lines, only to check indices */
    struct ao_load_array face;        /* struct corner: the face being read */
    struct ao_load_array corner_positions;  /* uint32_t, 3 per triangle: the mesh's indices when
                                               the file gives no normals */
    struct ao_load_array corner_normals;    /* uint32_t, one per corner from the first face
                                               with a normal on (earlier ones backfilled) */
    bool has_normals;         /* some corner references a normal */
    size_t invalid_normals;   /* vn lines of a zero or non-finite normal */
    struct ao_budget *budget;
};

/* Reads the rest of the line as at most 6 finite numbers into out, counting them. */
static bool read_floats(struct obj_reader *o, struct ao_load_tokens *t, float *out, size_t *count,
                        const char *usage)
{
    struct ao_load_span s;
    for (*count = 0; ao_load_next_token(t, &s); ++*count) {
        if (*count == 6) {
            ao_text_report_at(o->path, o->line, "too many numbers; expected %s", usage);
            return false;
        }
        if (!ao_load_parse_float(s, &out[*count])) {
            ao_text_report_at(o->path, o->line, "bad number '%.*s' (must be finite)",
                           ao_load_span_length(s), s.begin);
            return false;
        }
    }
    return true;
}

/* "v x y z [w]" (or "v x y z r g b"). */
static bool parse_obj_vertex(struct obj_reader *o, struct ao_load_tokens *t)
{
    float f[6];
    size_t n;
    if (!read_floats(o, t, f, &n, "'v x y z [w]'"))
        return false;
    if (n != 3 && n != 4 && n != 6) {
        ao_text_report_at(o->path, o->line, "expected 'v x y z [w]', found %zu numbers", n);
        return false;
    }
    if (o->positions.count == AO_LOAD_NO_INDEX - 1) {
        ao_text_report_at(o->path, o->line, "too many vertices for 32-bit indices");
        return false;
    }
    struct ao_vec3 *p = ao_load_append(&o->positions, 1);
    if (!p)
        return ao_load_out_of_memory(o->path);
    *p = ao_vec3_make(f[0], f[1], f[2]);
    return true;
}

/* "vn x y z", stored normalized; a zero or non-finite one (nan and inf are numbers here) is
 * stored missing and counted, its corners then made as those without a normal. */
static bool parse_obj_normal(struct obj_reader *o, struct ao_load_tokens *t)
{
    double f[3];
    size_t n = 0;
    struct ao_load_span s;
    for (; ao_load_next_token(t, &s); n++)
        if (n < 3 && !ao_load_parse_number(s, &f[n])) {
            ao_text_report_at(o->path, o->line, "bad number '%.*s'", ao_load_span_length(s), s.begin);
            return false;
        }
    if (n != 3) {
        ao_text_report_at(o->path, o->line, "expected 'vn x y z', found %zu numbers", n);
        return false;
    }
    if (o->normals.count == AO_LOAD_NO_INDEX - 1) {
        ao_text_report_at(o->path, o->line, "too many normals for 32-bit indices");
        return false;
    }
    struct ao_vec3 *normal = ao_load_append(&o->normals, 1);
    if (!normal)
        return ao_load_out_of_memory(o->path);
    *normal = ao_mesh_given_normal(f[0], f[1], f[2], &o->invalid_normals);
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
static bool split_corner(struct ao_load_span s, long long index[3])
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
static bool index_error(const struct obj_reader *o, struct ao_load_span s, const char *what,
                        size_t count)
{
    ao_text_report_at(o->path, o->line, "face corner '%.*s': %s index out of range (%zu defined so far)",
                   ao_load_span_length(s), s.begin, what, count);
    return false;
}

/* One face corner, its indices checked against what the file has defined up to this line. */
static bool parse_corner(struct obj_reader *o, struct ao_load_span s, struct corner *c)
{
    long long index[3];
    uint32_t texcoord;
    if (!split_corner(s, index)) {
        ao_text_report_at(o->path, o->line, "bad face corner '%.*s' (expected v, v/vt, v//vn or v/vt/vn "
                       "with nonzero indices)", ao_load_span_length(s), s.begin);
        return false;
    }
    if (!resolve(index[0], o->positions.count, &c->position))
        return index_error(o, s, "vertex", o->positions.count);
    if (index[1] && !resolve(index[1], o->texcoord_count, &texcoord))
        return index_error(o, s, "texture coordinate", o->texcoord_count);
    c->normal = AO_LOAD_NO_INDEX;
    if (index[2] && !resolve(index[2], o->normals.count, &c->normal))
        return index_error(o, s, "normal", o->normals.count);
    o->has_normals |= index[2] != 0;
    return true;
}

/* "f c1 c2 c3 ...": a polygon, fanned into triangles. */
static bool parse_obj_face(struct obj_reader *o, struct ao_load_tokens *t)
{
    struct ao_load_span s;
    o->face.count = 0;
    while (ao_load_next_token(t, &s)) {
        if (o->face.count == AO_LOAD_MAX_FACE_VERTICES) {
            ao_text_report_at(o->path, o->line, "face with more than %d vertices",
                           AO_LOAD_MAX_FACE_VERTICES);
            return false;
        }
        struct corner *c = ao_load_append(&o->face, 1);
        if (!c)
            return ao_load_out_of_memory(o->path);
        if (!parse_corner(o, s, c))
            return false;
    }
    if (o->face.count < 3) {
        ao_text_report_at(o->path, o->line, "face with %zu vertices; at least 3 needed", o->face.count);
        return false;
    }
    /* The fan (c0, ci, ci+1): positions, and normals (AO_LOAD_NO_INDEX where absent) once any
     * corner has had one, the corners before it backfilled. */
    const struct corner *c = (const struct corner *)o->face.data;
    size_t fan = 3 * (o->face.count - 2), missing = o->corner_positions.count - o->corner_normals.count;
    uint32_t *p = ao_load_append(&o->corner_positions, fan);
    uint32_t *n = p && o->has_normals ? ao_load_append(&o->corner_normals, missing + fan) : NULL;
    if (!p || (o->has_normals && !n))
        return ao_load_out_of_memory(o->path);
    for (size_t i = 0; n && i < missing; i++)
        *n++ = AO_LOAD_NO_INDEX;
    for (size_t i = 1; i + 1 < o->face.count; i++, p += 3) {
        p[0] = c[0].position, p[1] = c[i].position, p[2] = c[i + 1].position;
        if (n)
            n[0] = c[0].normal, n[1] = c[i].normal, n[2] = c[i + 1].normal, n += 3;
    }
    return true;
}

/* The file has no counts ahead of its data: the budget is checked as they grow, after each line
 * that adds positions, normals (both held like vertices) or triangles. */
static bool within_budget(const struct obj_reader *o)
{
    return ao_mesh_fits(o->budget, o->corner_positions.count / 3, o->positions.count + o->normals.count, o->path,
                        o->line);
}

/* One line; '#' starts a comment, statements other than v, vn, vt and f are ignored. */
static bool parse_obj_line(struct obj_reader *o, const char *begin, const char *end)
{
    const char *hash = memchr(begin, '#', (size_t)(end - begin));
    struct ao_load_tokens t = {begin, hash ? hash : end};
    struct ao_load_span keyword;
    if (!ao_load_next_token(&t, &keyword))
        return true;
    if (ao_load_span_is(keyword, "v"))
        return parse_obj_vertex(o, &t) && within_budget(o);
    if (ao_load_span_is(keyword, "vn"))
        return parse_obj_normal(o, &t) && within_budget(o);
    if (ao_load_span_is(keyword, "f"))
        return parse_obj_face(o, &t) && within_budget(o);
    if (ao_load_span_is(keyword, "vt"))
        o->texcoord_count++;
    return true;
}

/* Without any file normals: positions are the vertices, as in the file. */
static bool build_shared_vertices(struct obj_reader *o, struct ao_mesh *mesh)
{
    mesh->indices = ao_load_take(&o->corner_positions);
    mesh->vertex_count = o->positions.count;
    mesh->positions = ao_load_take(&o->positions);
    return ao_load_finish(mesh, o->path);
}

/* Open-addressing hash map from a (position, normal) pair to the vertex made for it; its slots
 * are taken from the budget as it grows (both tables while it rehashes: just past a power of two,
 * 96 bytes a pair, where a vertex is charged 60) and given back when it is freed. */
struct vertex_map {
    struct vertex_slot {
        uint64_t key;       /* position << 32 | normal; UINT64_MAX when empty */
        uint32_t vertex;
    } *slots;
    size_t capacity, count; /* capacity is a power of two, at most half full */
    struct ao_budget *budget;
    uint64_t taken;         /* the slots' bytes taken from it */
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

/* Makes room for one more entry, doubling and rehashing when half full; false when memory runs out
 * (not reported) or the grown table would not fit in the budget beside `mesh` bytes, the charge of
 * the mesh with that entry (*over; reported, naming path). */
static bool map_reserve(struct vertex_map *map, uint64_t mesh, const char *path, bool *over)
{
    if (2 * (map->count + 1) <= map->capacity)
        return true;
    struct vertex_map grown = {NULL, map->capacity ? 2 * map->capacity : 1024, map->count, map->budget, map->taken};
    uint64_t bytes = (uint64_t)grown.capacity * sizeof *grown.slots;
    if (grown.capacity > SIZE_MAX / sizeof *grown.slots)
        return false;
    if (mesh > UINT64_MAX - bytes || !ao_budget_fits(map->budget, mesh + bytes)) {
        char why[200];
        ao_budget_explain(map->budget, mesh > UINT64_MAX - bytes ? UINT64_MAX : mesh + bytes, why, sizeof why);
        ao_text_report_at(path, 0, "%zu distinct position/normal pairs and the table that indexes them %s",
                       map->count + 1, why);
        return !(*over = true);
    }
    ao_budget_take(map->budget, bytes);
    grown.taken += bytes;
    if (!(grown.slots = malloc((size_t)bytes))) {
        ao_budget_give(map->budget, bytes);
        return false;
    }
    memset(grown.slots, 0xff, (size_t)bytes);
    for (size_t i = 0; i < map->capacity; i++)
        if (map->slots[i].key != UINT64_MAX)
            *map_slot(&grown, map->slots[i].key) = map->slots[i];
    free(map->slots);
    ao_budget_give(map->budget, (uint64_t)map->capacity * sizeof *map->slots);
    grown.taken -= (uint64_t)map->capacity * sizeof *map->slots;
    *map = grown;
    return true;
}

/* The output arrays of build_split_vertices. */
struct split_output {
    struct ao_load_array positions, normals;   /* ao_vec3 */
};

/* The vertex for corner c, made (with its position and file normal, or the missing marker) on
 * first sight; corners whose normal is missing share one vertex per position. */
static bool split_vertex(struct obj_reader *o, struct vertex_map *map, struct split_output *out,
                         struct corner c, uint32_t *vertex)
{
    const struct ao_vec3 *normals = (const struct ao_vec3 *)o->normals.data;
    if (c.normal != AO_LOAD_NO_INDEX && ao_mesh_normal_is_missing(normals[c.normal]))
        c.normal = AO_LOAD_NO_INDEX;
    uint64_t key = (uint64_t)c.position << 32 | c.normal;
    bool over = false;
    uint64_t mesh = ao_budget_charge(o->budget, o->corner_positions.count / 3, map->count + 1, 0);
    if (!map_reserve(map, mesh, o->path, &over))
        return over ? false : ao_load_out_of_memory(o->path);
    struct vertex_slot *slot = map_slot(map, key);
    if (slot->key == key) {
        *vertex = slot->vertex;
        return true;
    }
    if (map->count == AO_LOAD_NO_INDEX - 1) {
        ao_text_report_at(o->path, 0, "too many distinct vertices for 32-bit indices");
        return false;
    }
    if (!ao_mesh_fits(o->budget, o->corner_positions.count / 3, map->count + 1, o->path, 0))
        return false;
    struct ao_vec3 *p = ao_load_append(&out->positions, 1), *n = ao_load_append(&out->normals, 1);
    if (!p || !n)
        return ao_load_out_of_memory(o->path);
    *p = ((const struct ao_vec3 *)o->positions.data)[c.position];
    *n = c.normal == AO_LOAD_NO_INDEX ? ao_mesh_missing_normal() : normals[c.normal];
    slot->key = key;
    slot->vertex = *vertex = (uint32_t)map->count++;
    return true;
}

/* With file normals: one vertex per distinct (position, normal) pair, so the mesh stays indexed
 * with one normal per vertex. Corners without a normal (a face without normals, or one with
 * normals on some corners only, or a zero or non-finite one) share one vertex per position, whose
 * normal is missing, to be made from the triangles using that vertex; file-normal vertices keep
 * theirs. */
static bool build_split_vertices(struct obj_reader *o, struct ao_mesh *mesh)
{
    struct vertex_map map = {.budget = o->budget};
    struct split_output out = {.positions = {.size = sizeof(struct ao_vec3)},
                               .normals = {.size = sizeof(struct ao_vec3)}};
    const uint32_t *positions = (const uint32_t *)o->corner_positions.data;
    const uint32_t *normals = (const uint32_t *)o->corner_normals.data;
    size_t count = o->corner_positions.count;
    bool ok = (mesh->indices = malloc(count * sizeof *mesh->indices)) != NULL;
    if (!ok)
        ao_load_out_of_memory(o->path);
    for (size_t i = 0; ok && i < count; i++)
        ok = split_vertex(o, &map, &out, (struct corner){positions[i], normals[i]}, &mesh->indices[i]);
    free(map.slots);
    ao_budget_give(o->budget, map.taken);
    if (ok) {
        mesh->vertex_count = out.positions.count;
        mesh->positions = ao_load_take(&out.positions);
        mesh->normals = ao_load_take(&out.normals);
        ok = ao_load_finish(mesh, o->path);
    }
    ao_load_free(&out.positions);
    ao_load_free(&out.normals);
    return ok;
}

/* Parses OBJ text line by line, then builds the indexed mesh. */
bool ao_load_obj(struct ao_mesh *mesh, const char *path, const char *text, size_t size,
                 struct ao_budget *budget)
{
    struct obj_reader o = {
        .path = path,
        .budget = budget,
        .positions = {.size = sizeof(struct ao_vec3)},
        .normals = {.size = sizeof(struct ao_vec3)},
        .face = {.size = sizeof(struct corner)},
        .corner_positions = {.size = sizeof(uint32_t)},
        .corner_normals = {.size = sizeof(uint32_t)},
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
        mesh->triangle_count = o.corner_positions.count / 3;
        mesh->invalid_normals = o.invalid_normals;
        ok = o.has_normals ? build_split_vertices(&o, mesh) : build_shared_vertices(&o, mesh);
    }
    ao_load_free(&o.positions);
    ao_load_free(&o.normals);
    ao_load_free(&o.face);
    ao_load_free(&o.corner_positions);
    ao_load_free(&o.corner_normals);
    return ok;
}
