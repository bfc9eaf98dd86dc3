/* glTF 2.0: .gltf (JSON, buffers in external files or data URIs) and .glb (binary container). The
 * JSON is parsed by json-c; this file, its node tree gltf_nodes.c and its data layer gltf_data.c
 * (JSON access, containers, buffers, bufferViews, accessors; gltf_reader.h) read what aoview needs from
 * it: the default scene's nodes (or scene 0's, or every root node when there is no scene), their
 * transforms (matrix, or translation/rotation/scale; nested), and their meshes' primitives of
 * triangles, triangle strips and fans (modes 4, 5, 6; indexed by any unsigned type or not indexed)
 * with VEC3 POSITION and NORMAL of float or (KHR_mesh_quantization) 8- and 16-bit integers, sparse
 * or not, from bufferViews that may be compressed (EXT_meshopt_compression: meshopt.c) or from
 * Draco data (KHR_draco_mesh_compression: draco.cc); points and lines are skipped and counted.
 * Required extensions that change only how surfaces look are noted (materials, textures, lights are
 * ignored); others are refused unless read here.
 *
 * Every range a file gives is checked before it is read: a GLB's chunk lengths against the file,
 * a bufferView against its buffer, an accessor's last element against its bufferView, indices
 * (sparse ones too) against their count. Integers are read only up to 2^53, so that sums of three
 * of them and products of one with a stride (at most 252) stay far below 2^64. Nodes must form
 * trees: a node with two parents, or a cycle, is refused before anything is traversed, and so is a
 * node deeper than AO_GLTF_MAX_NODE_DEPTH. Each glTF mesh that placed nodes name is read once, in
 * its own frame, and placed by every such node (mesh.h's ao_model): nothing is flattened. Whatever
 * the load holds is charged to the scene budget before it is allocated: the JSON tree json-c will
 * build and the per-node arrays (both estimated from the text, json_cost), each buffer, each
 * accessor gathered into memory of its own, and the meshes with their placements, counted in a
 * first pass, so that a small file cannot demand gigabytes. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <json.h>

#include "gltf_reader.h"
#include "text.h"

/* JSON nesting depth accepted (glTF needs 6 or so; deep nesting is an attack on the parser). */
#define MAX_DEPTH 64

/* A mesh_size's model index once the mesh is built and found to hold no triangle. */
#define DROPPED (SIZE_MAX - 1)

/* ------------------------------------------------------------------ meshes */

/* The glTF primitive modes aoview draws as triangles. */
enum { MODE_TRIANGLES = 4, MODE_TRIANGLE_STRIP = 5, MODE_TRIANGLE_FAN = 6 };

/* How many triangles a primitive of mode makes of n corners (vertices, or indices when indexed). */
static size_t triangles_of(uint64_t mode, size_t n)
{
    return mode == MODE_TRIANGLES ? n / 3 : n >= 3 ? n - 2 : 0;
}

/* The corners of triangle k of a primitive of mode, as positions in its corner sequence, in the
 * winding glTF gives: a list's (3k, 3k + 1, 3k + 2); a strip's (k, k + 1, k + 2) for even k and
 * (k, k + 2, k + 1) for odd k, so that every triangle of the strip faces the same way; a fan's
 * (k + 1, k + 2, 0). */
static void triangle_corners(uint64_t mode, size_t k, size_t out[3])
{
    if (mode == MODE_TRIANGLES) {
        out[0] = 3 * k, out[1] = 3 * k + 1, out[2] = 3 * k + 2;
    } else if (mode == MODE_TRIANGLE_STRIP) {
        out[0] = k, out[1] = k + 1 + k % 2, out[2] = k + 2 - k % 2;
    } else {
        out[0] = k + 1, out[1] = k + 2, out[2] = 0;
    }
}

/* Appends a primitive's vertices to the mesh being built, in the mesh's own frame: positions as
 * the file gives them, normals made unit, or missing (the marker; flat once the mesh is made) when
 * normals is NULL or one is zero or not finite (counted). The normals are kept from the mesh's first
 * primitive with normals on (missing before it): a mesh without any has none to hold. */
static bool add_vertices(struct ao_gltf *g, const struct ao_gltf_elements *positions,
                         const struct ao_gltf_elements *normals, const char *where)
{
    if (g->positions.count + positions->count >= AO_LOAD_NO_INDEX)
        return ao_gltf_error(g, "%s: more than %u vertices in one mesh", where, AO_LOAD_NO_INDEX - 1);
    size_t earlier = g->positions.count - g->normals.count;
    bool keep = normals || g->normals.count > 0;
    struct ao_vec3 *p = ao_load_append(&g->positions, positions->count);
    struct ao_vec3 *n = keep ? ao_load_append(&g->normals, earlier + positions->count) : NULL;
    if (!p || (keep && !n))
        return ao_load_out_of_memory(g->path);
    for (size_t i = 0; keep && i < earlier; i++)
        *n++ = ao_mesh_missing_normal();
    for (size_t i = 0; i < positions->count; i++) {
        p[i] = ao_gltf_position(positions, i);
        if (!ao_vec3_is_finite(p[i]))
            return ao_gltf_error(g, "%s: vertex %zu is not a finite float", where, i);
        if (keep)
            n[i] = normals ? ao_mesh_given_normal(ao_gltf_value(normals, i, 0), ao_gltf_value(normals, i, 1),
                                                  ao_gltf_value(normals, i, 2), &g->invalid_normals)
                           : ao_mesh_missing_normal();
    }
    return true;
}

/* Appends the triangles of a primitive of `mode` over `corners` corners: the indices' (NULL: the
 * vertices' in order), each checked once below vertex_count (a strip's and a fan's corners serve
 * several; a list's in one pass), offset by base. */
static bool add_triangles(struct ao_gltf *g, uint64_t mode, const struct ao_gltf_elements *indices, size_t corners,
                          uint32_t base, size_t vertex_count, const char *where)
{
    size_t triangles = triangles_of(mode, corners);
    size_t bad;
    uint32_t *list = indices && mode == MODE_TRIANGLES ? ao_load_append(&g->indices, corners) : NULL;
    if (indices && mode == MODE_TRIANGLES && !list && corners)
        return ao_load_out_of_memory(g->path);
    if (list && !ao_gltf_list_indices(indices, base, vertex_count, list, &bad))
        return ao_gltf_error(g, "%s: index %u at %zu is out of range (%zu vertices)", where,
                             ao_gltf_index_at(indices, bad), bad, vertex_count);
    g->triangles += list ? triangles : 0;
    if (list)
        return true;
    for (size_t i = 0; indices && i < corners; i++) {
        uint32_t v = ao_gltf_index_at(indices, i);
        if (v >= vertex_count)
            return ao_gltf_error(g, "%s: index %u at %zu is out of range (%zu vertices)", where, v, i,
                                 vertex_count);
    }
    uint32_t *t = ao_load_append(&g->indices, 3 * triangles);
    if (!t && triangles)
        return ao_load_out_of_memory(g->path);
    for (size_t k = 0; k < triangles; k++) {
        size_t c[3];
        triangle_corners(mode, k, c);
        for (int j = 0; j < 3; j++)
            t[3 * k + j] = base + (indices ? ao_gltf_index_at(indices, c[j]) : (uint32_t)c[j]);
    }
    g->triangles += triangles;
    return true;
}

/* Appends one primitive of triangles (mode 4), a strip (5) or a fan (6) to the mesh being built:
 * its vertices (or those of an earlier primitive of the same mesh), its triangles offset. With
 * count_only, adds its size to the totals. */
static bool add_primitive(struct ao_gltf *g, json_object *primitive, uint64_t mode, const char *where,
                          bool count_only)
{
    json_object *attributes = ao_gltf_member(primitive, "attributes");
    json_object *draco = ao_gltf_member(ao_gltf_member(primitive, "extensions"), "KHR_draco_mesh_compression");
    size_t count = ao_gltf_length(g->accessors), position_index = 0, normal_index = 0, index_index = 0;
    struct ao_gltf_elements positions, normals = {0}, indices = {0}, decoded[3];
    bool has_normals = ao_gltf_member(attributes, "NORMAL") != NULL;
    bool indexed = ao_gltf_member(primitive, "indices") != NULL;
    if (!ao_gltf_member(attributes, "POSITION"))
        return ao_gltf_error(g, "%s: no POSITION attribute", where);
    if (draco && mode != MODE_TRIANGLES)
        return ao_gltf_error(g, "%s: mode %llu; with KHR_draco_mesh_compression aoview reads triangles (mode 4) only",
                             where, (unsigned long long)mode);
    if (draco) {
        if (!ao_gltf_draco(g, primitive, draco, has_normals, where, decoded))
            return false;
        positions = decoded[0], normals = decoded[1], indices = decoded[2];
        indexed = true;
    } else if (!ao_gltf_index(g, attributes, "POSITION", count, where, &position_index) ||
               !ao_gltf_accessor(g, position_index, true, "POSITION", &positions) ||
               (has_normals && (!ao_gltf_index(g, attributes, "NORMAL", count, where, &normal_index) ||
                                !ao_gltf_accessor(g, normal_index, true, "NORMAL", &normals))) ||
               (indexed && (!ao_gltf_index(g, primitive, "indices", count, where, &index_index) ||
                            !ao_gltf_accessor(g, index_index, false, "indices", &indices)))) {
        return false;
    }
    if (has_normals && normals.count != positions.count)
        return ao_gltf_error(g, "%s: %zu normals for %zu positions", where, normals.count,
                          positions.count);
    size_t corners = indexed ? indices.count : positions.count, triangles = triangles_of(mode, corners);
    if (mode == MODE_TRIANGLES && corners % 3)
        return ao_gltf_error(g, "%s: %zu %s, not a whole number of triangles", where, corners,
                          indexed ? "indices" : "vertices");

    /* Primitives of one mesh that name the same POSITION and NORMAL accessors share their
     * vertices, as the file means (normals computed across them are then smooth, and a mesh split
     * into thousands of fans does not copy its vertices thousands of times): the first adds them,
     * the others reuse them. */
    struct shared *shared = draco ? NULL : &g->shared[position_index];
    size_t normal_key = has_normals ? normal_index : SIZE_MAX;
    bool reuse = shared && shared->instance == g->instance && shared->normals == normal_key;
    if (count_only) {
        g->triangles += triangles;
        g->vertices += reuse ? 0 : positions.count;
        if (shared)
            *shared = (struct shared){g->instance, normal_key, 0};
        return true;
    }
    uint32_t base = reuse ? shared->base : (uint32_t)g->positions.count;
    if (!reuse && !add_vertices(g, &positions, has_normals ? &normals : NULL, where))
        return false;
    if (shared)
        *shared = (struct shared){g->instance, normal_key, base};

    return add_triangles(g, mode, indexed ? &indices : NULL, corners, base, positions.count, where);
}

/* Walks the primitives of mesh: with count_only, adds the size of its triangle primitives (lists,
 * strips, fans) to the totals and notes the modes found and its primitives of points and lines
 * (sizes[mesh] then holds them); else appends its triangles to the mesh being built. */
static bool walk_mesh(struct ao_gltf *g, size_t mesh, bool count_only)
{
    char where[96];
    json_object *primitives;
    size_t primitive_count;
    struct mesh_size *size = &g->sizes[mesh];
    g->instance++;   /* a new walk: vertices are shared among this mesh's primitives only */
    snprintf(where, sizeof where, "mesh %zu", mesh);
    if (!ao_gltf_array(g, json_object_array_get_idx(g->meshes, mesh), "primitives", where, &primitives,
                       &primitive_count))
        return false;
    for (size_t k = 0; k < primitive_count; k++) {
        json_object *primitive = json_object_array_get_idx(primitives, k);
        uint64_t mode;
        snprintf(where, sizeof where, "mesh %zu primitive %zu", mesh, k);
        if (!ao_gltf_integer(g, primitive, "mode", false, 4, 6, where, &mode))
            return false;
        g->modes_found |= 1u << mode;
        if (mode < MODE_TRIANGLES) {
            size->points += count_only && mode == 0;
            size->lines += count_only && mode != 0;
        } else if (!add_primitive(g, primitive, mode, where, count_only)) {
            return false;
        }
    }
    return true;
}

/* Builds glTF mesh `mesh` into the model's next mesh, in its own frame; a mesh left without
 * triangles (all degenerate) is dropped, its placements with it. */
static bool build_mesh(struct ao_gltf *g, size_t mesh, struct ao_load_array *meshes)
{
    g->invalid_normals = 0;
    if (!walk_mesh(g, mesh, false))
        return false;
    struct ao_mesh m = {0};
    m.vertex_count = g->positions.count;
    m.positions = ao_load_take(&g->positions);
    m.triangle_count = g->indices.count / 3;
    m.indices = ao_load_take(&g->indices);
    m.normals = ao_load_take(&g->normals);
    m.invalid_normals = g->invalid_normals;
    ao_mesh_drop_degenerate(&m);
    g->degenerate_count += m.degenerate_count;
    struct ao_mesh *slot = m.triangle_count ? ao_load_append(meshes, 1) : NULL;
    bool ok = !m.triangle_count || slot || ao_load_out_of_memory(g->path);
    g->sizes[mesh].model = slot ? meshes->count - 1 : DROPPED;
    if (slot)
        *slot = m;
    else
        ao_mesh_finish(&m);
    return ok;
}

/* ------------------------------------------------------------------ the file */

/* An upper estimate of json-c's memory for text, and of the loader's per-node arrays: each '{'
 * makes an object with a 16-entry hash table (measured: 780 bytes) and may be a node, for which
 * read_scene keeps AO_BUDGET_NODE bytes more; each '[' an array (150 bytes), and every other
 * value, which follows a ',' or ':', 70 to 110 bytes; a string's bytes are gathered in a buffer
 * grown by doubling (less than twice their length) and then copied into the string (once more):
 * 3 bytes per byte (measured: 1.9 for a 200 MB string). Charged before parsing, it keeps a few
 * megabytes of "{}," from taking gigabytes, a 1 GB string 3 GB, and a million nodes from being
 * parsed only to be refused. */
static uint64_t json_cost(const char *text, size_t size)
{
    uint64_t cost = 0;
    bool in_string = false;
    for (size_t i = 0; i < size; i++) {
        char c = text[i];
        if (in_string) {
            i += c == '\\';   /* an escaped character, '"' too, stays in the string */
            in_string = c != '"';
            cost += 3;
        } else {
            in_string = c == '"';
            cost += c == '{' ? 800 + AO_BUDGET_NODE : c == '[' ? 160 : c == ',' || c == ':' ? 112 : 0;
        }
    }
    return cost;
}

/* Parses the JSON text into g->root; errors name the line. */
static bool parse_json(struct ao_gltf *g, const char *text, size_t size)
{
    if (!ao_gltf_take(g, json_cost(text, size), "parsing its JSON"))
        return false;
    struct json_tokener *tokener = json_tokener_new_ex(MAX_DEPTH);
    if (!tokener)
        return ao_load_out_of_memory(g->path);
    g->root = size > INT32_MAX ? NULL : json_tokener_parse_ex(tokener, text, (int)size);
    enum json_tokener_error error = json_tokener_get_error(tokener);
    size_t end = json_tokener_get_parse_end(tokener);
    json_tokener_free(tokener);
    size_t line = 1;
    for (size_t i = 0; i < end && i < size; i++)
        line += text[i] == '\n';
    if (size > INT32_MAX)
        return ao_gltf_error(g, "JSON of %zu bytes is too large", size);
    if (!g->root || error != json_tokener_success) {
        ao_text_report_at(g->path, line, "JSON: %s", error == json_tokener_continue
                                                      ? "unexpected end of text"
                                                      : json_tokener_error_desc(error));
        return false;
    }
    for (; end < size; end++)
        if (text[end] != ' ' && text[end] != '\t' && text[end] != '\r' && text[end] != '\n') {
            ao_text_report_at(g->path, line, "JSON: text after the top-level value");
            return false;
        }
    if (!json_object_is_type(g->root, json_type_object))
        return ao_gltf_error(g, "the JSON top level is not an object");
    return true;
}

/* Required extensions that change only how surfaces look (materials, textures, lights) or what
 * aoview ignores anyway (animation, metadata): a file that requires them loads, with a note. By
 * name prefix, then whole names. */
static const char *const LOOKS_PREFIXES[] = {"KHR_materials_", "KHR_texture_", "EXT_texture_", "MSFT_texture_",
                                             "MSFT_packing_", "ADOBE_materials_", "KHR_techniques_", NULL};
static const char *const LOOKS[] = {"KHR_lights_punctual", "EXT_lights_image_based", "EXT_lights_ies",
                                    "KHR_xmp_json_ld", "KHR_xmp", "KHR_animation_pointer",
                                    "KHR_technique_webgl", NULL};
/* Required extensions that change the geometry and that aoview reads. */
static const char *const GEOMETRY[] = {"KHR_mesh_quantization", "EXT_meshopt_compression",
                                       "KHR_draco_mesh_compression", NULL};
/* Required extensions known to change the geometry that aoview does not read, and how. */
static const struct {
    const char *name, *what;
} UNREAD[] = {{"EXT_mesh_gpu_instancing", "places meshes many times"},
              {"MSFT_lod", "chooses among meshes by distance"}};

/* True when name is in the NULL-terminated list, or starts with one of prefixes (may be NULL). */
static bool listed(const char *name, const char *const *names, const char *const *prefixes)
{
    for (; names && *names; names++)
        if (strcmp(name, *names) == 0)
            return true;
    for (; prefixes && *prefixes; prefixes++)
        if (strncmp(name, *prefixes, strlen(*prefixes)) == 0)
            return true;
    return false;
}

/* The asset version and required extensions: those that change only how surfaces look load, and
 * are noted once in g->note; those that change the geometry load when aoview reads them; any other
 * is refused, as it may change what is drawn. */
static bool check_asset(struct ao_gltf *g)
{
    json_object *version = ao_gltf_member(ao_gltf_member(g->root, "asset"), "version"), *required;
    size_t n;
    if (!json_object_is_type(version, json_type_string))
        return ao_gltf_error(g, "no asset.version (not a glTF file?)");
    if (strncmp(json_object_get_string(version), "2.", 2) != 0)
        return ao_gltf_error(g, "glTF version '%.20s'; only 2.x is supported",
                          json_object_get_string(version));
    if (!ao_gltf_array(g, g->root, "extensionsRequired", "file", &required, &n))
        return false;
    char looks[160] = "";
    size_t used = 0;
    for (size_t i = 0; i < n; i++) {
        json_object *item = json_object_array_get_idx(required, i);
        if (!json_object_is_type(item, json_type_string))
            return ao_gltf_error(g, "extensionsRequired: entry %zu is not a string", i);
        const char *name = json_object_get_string(item);
        if (listed(name, GEOMETRY, NULL))
            continue;
        for (size_t k = 0; k < sizeof UNREAD / sizeof UNREAD[0]; k++)
            if (strcmp(name, UNREAD[k].name) == 0)
                return ao_gltf_error(g, "requires extension '%s', which %s and which aoview does not read",
                                     name, UNREAD[k].what);
        if (!listed(name, LOOKS, LOOKS_PREFIXES))
            return ao_gltf_error(g, "requires extension '%.60s', which aoview does not know (it may change "
                                 "the geometry)", name);
        if (used < sizeof looks)
            used += (size_t)snprintf(looks + used, sizeof looks - used, "%s%.60s", used ? ", " : "", name);
    }
    if (used)
        ao_gltf_note(g, "materials, textures and lights are ignored (it requires %s%s)", looks,
                     used >= sizeof looks ? "..." : "");
    return true;
}

/* Refuses a file whose primitives make no triangle because they are points and lines: one line
 * naming the modes found. */
static bool only_points_and_lines(const struct ao_gltf *g)
{
    static const char *const names[7] = {"0 (points)", "1 (lines)", "2 (line loop)", "3 (line strip)",
                                         "4 (triangles)", "5 (triangle strip)", "6 (triangle fan)"};
    char list[160] = "";
    size_t used = 0;
    for (int mode = 0; mode < 7; mode++)
        if (g->modes_found & 1u << mode)
            used += (size_t)snprintf(list + used, sizeof list - used, "%s%s", used ? ", " : "", names[mode]);
    return ao_gltf_error(g, "no triangles to render: its primitives have the modes %s, and aoview draws "
                         "only triangles", list);
}

/* Refuses a file whose nodes place no mesh, naming why: no meshes, no nodes, or nodes of the scene
 * read that name none (the file's other nodes and scenes are not drawn). */
static bool no_mesh_placed(const struct ao_gltf *g, size_t mesh_count, size_t node_count)
{
    json_object *scenes = ao_gltf_member(g->root, "scenes");
    size_t scene = 0;
    uint64_t chosen = 0;
    if (ao_gltf_member(g->root, "scene") && ao_gltf_whole(ao_gltf_member(g->root, "scene"), AO_GLTF_MAX_INTEGER,
                                                          &chosen))
        scene = (size_t)chosen;
    if (mesh_count == 0)
        return ao_gltf_error(g, "no triangles: the file has no meshes");
    if (node_count == 0)
        return ao_gltf_error(g, "no triangles: the file has %zu mesh%s but no nodes to place them", mesh_count,
                             mesh_count == 1 ? "" : "es");
    if (ao_gltf_length(scenes) > 0)
        return ao_gltf_error(g, "no triangles: no node of scene %zu (the one shown) places a mesh", scene);
    return ao_gltf_error(g, "no triangles: no node places a mesh");
}

/* A placement of glTF mesh `mesh` by node `node`, found in the counting pass. */
struct found {
    size_t node, mesh;
};

/* The placed nodes that name a mesh, in node order, into *found (malloc'd, *count of them); each
 * mesh counted once (validating its accessors), its primitives of points and lines once per
 * placement. */
static bool find_placements(struct ao_gltf *g, size_t node_count, const bool *placed, struct found **found,
                            size_t *count)
{
    *count = 0;
    for (size_t i = 0; i < node_count; i++)
        *count += placed[i] && ao_gltf_member(json_object_array_get_idx(g->nodes, i), "mesh");
    if (!(*found = malloc((*count ? *count : 1) * sizeof **found)))
        return ao_load_out_of_memory(g->path);
    size_t n = 0;
    for (size_t i = 0; i < node_count; i++) {
        json_object *node = json_object_array_get_idx(g->nodes, i);
        char where[64];
        size_t mesh;
        if (!placed[i] || !ao_gltf_member(node, "mesh"))
            continue;
        snprintf(where, sizeof where, "node %zu", i);
        if (!ao_gltf_index(g, node, "mesh", ao_gltf_length(g->meshes), where, &mesh))
            return false;
        struct mesh_size *size = &g->sizes[mesh];
        if (!size->known) {
            uint64_t triangles = g->triangles, vertices = g->vertices;
            if (!walk_mesh(g, mesh, true))
                return false;
            size->triangles = g->triangles - triangles;
            size->vertices = g->vertices - vertices;
            size->model = SIZE_MAX;
            size->known = true;
        }
        g->point_primitives += size->points;
        g->line_primitives += size->lines;
        (*found)[n++] = (struct found){i, mesh};
    }
    return true;
}

/* The placement of model mesh `mesh` by a node of world matrix w (column-major 4x4). */
static struct ao_placement placement(size_t mesh, const double w[16])
{
    struct ao_placement p = {.mesh = mesh};
    for (int c = 0; c < 4; c++)
        for (int k = 0; k < 3; k++)
            p.to_model.m[3 * c + k] = w[4 * c + k];
    return p;
}

/* Everything after the JSON is parsed: arrays, buffers, the node tree, the meshes and their
 * placements into model. */
static bool read_scene(struct ao_gltf *g, struct ao_model *model)
{
    size_t node_count, mesh_count, count;
    if (!check_asset(g) || !ao_gltf_array(g, g->root, "accessors", "file", &g->accessors, &count) ||
        !ao_gltf_array(g, g->root, "bufferViews", "file", &g->views, &count) ||
        !ao_gltf_array(g, g->root, "meshes", "file", &g->meshes, &mesh_count) ||
        !ao_gltf_array(g, g->root, "nodes", "file", &g->nodes, &node_count) ||
        !ao_gltf_array(g, g->root, "buffers", "file", &g->buffer_json, &g->buffer_count))
        return false;
    /* The per-node, per-buffer and per-mesh arrays: each of those is a JSON object, whose charge
     * (json_cost) covers them. */
    g->parent = malloc((node_count ? node_count : 1) * sizeof *g->parent);
    g->world = malloc((node_count ? node_count : 1) * sizeof *g->world);
    g->depth = malloc((node_count ? node_count : 1) * sizeof *g->depth);
    bool *flags = calloc(node_count ? 2 * node_count : 1, sizeof *flags);
    g->sizes = calloc(mesh_count ? mesh_count : 1, sizeof *g->sizes);
    g->shared = calloc(ao_gltf_length(g->accessors) + 1, sizeof *g->shared);
    bool ok = ((g->parent && g->world && g->depth && flags && g->sizes && g->shared) ||
               ao_load_out_of_memory(g->path)) &&
              ao_gltf_begin_data(g);
    bool *is_root = flags, *placed = flags + node_count;
    ok = ok && ao_gltf_place_nodes(g, node_count, is_root, placed);

    /* First count the meshes the nodes place, each once (validating every accessor), and refuse
     * them with their placements when they do not fit in the budget beside what the load holds
     * already. Then build each mesh once, in its own frame, and place it. */
    struct found *found = NULL;
    size_t placements = 0;
    ok = ok && find_placements(g, node_count, placed, &found, &placements);
    ok = ok && (placements > 0 || no_mesh_placed(g, mesh_count, node_count));
    ok = ok && (g->triangles > 0 || !(g->modes_found & 0xf) || only_points_and_lines(g));
    ok = ok && ao_load_fits_model(g->budget, g->triangles, g->vertices, placements, g->path);
    struct ao_load_array meshes = {.size = sizeof(struct ao_mesh)}, list = {.size = sizeof(struct ao_placement)};
    struct ao_placement *slot = ok ? ao_load_append(&list, placements) : NULL;
    ok = ok && (slot || placements == 0 || ao_load_out_of_memory(g->path));
    size_t kept = 0;
    for (size_t i = 0; ok && i < placements; i++) {
        struct mesh_size *size = &g->sizes[found[i].mesh];
        if (size->model == SIZE_MAX)
            ok = build_mesh(g, found[i].mesh, &meshes);
        if (ok && size->model != DROPPED)
            slot[kept++] = placement(size->model, g->world[found[i].node]);
    }
    free(found);
    free(flags);
    list.count = kept;
    model->mesh_count = meshes.count;
    model->meshes = ao_load_take(&meshes);
    model->placement_count = list.count;
    model->placements = ao_load_take(&list);
    if (ok && model->mesh_count == 0)
        ok = g->degenerate_count ? ao_gltf_error(g, "no triangles (%zu degenerate ones skipped)", g->degenerate_count)
                                 : ao_gltf_error(g, "no triangles: the meshes its nodes place have no primitives");
    if (ok && g->recounted)
        ao_gltf_note(g, "%s: read as decoded%s", g->recount,
                     g->recounted > 1 ? ", as are more such primitives" : "");
    if (ok && g->unaligned[0])
        ao_gltf_note(g, "%s, off glTF's alignment: read as it lies%s", g->unaligned,
                     g->unaligned_more ? ", as are more" : "");
    return ok;
}

bool ao_load_gltf(struct ao_model *model, const char *path, const char *text, size_t size, struct ao_budget *budget)
{
    struct ao_gltf g = {
        .path = path,
        .budget = budget,
        .positions = {.size = sizeof(struct ao_vec3)},
        .normals = {.size = sizeof(struct ao_vec3)},
        .indices = {.size = sizeof(uint32_t)},
    };
    const unsigned char *json = (const unsigned char *)text;
    size_t json_size = size;
    bool glb = size >= 4 && memcmp(text, "glTF", 4) == 0;
    bool ok = (!glb || ao_gltf_parse_glb(&g, (const unsigned char *)text, size, &json, &json_size)) &&
              parse_json(&g, (const char *)json, json_size) && read_scene(&g, model);
    model->degenerate_count = g.degenerate_count;
    model->point_primitives = g.point_primitives;
    model->line_primitives = g.line_primitives;
    snprintf(model->note, sizeof model->note, "%s", g.note);
    ao_gltf_free_data(&g);
    free(g.parent);
    free(g.world);
    free(g.depth);
    free(g.sizes);
    free(g.shared);
    json_object_put(g.root);
    ao_load_free(&g.positions);
    ao_load_free(&g.normals);
    ao_load_free(&g.indices);
    ao_budget_give(budget, g.taken);
    return ok;
}
