/* glTF's node tree (see gltf_reader.h): every node's parent recorded and the nodes checked to form trees,
 * the roots of the scene shown found, and each node under them placed by its world matrix (its
 * local matrix, or translation, rotation and scale, after its parent's). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <json.h>

#include "gltf_reader.h"

/* A node's place in the tree. */
enum { NODE_UNSEEN, NODE_WALKING, NODE_CHECKED };

/* n finite numbers of an array member into out; false (reported) when malformed. */
static bool numbers(const struct ao_gltf *g, json_object *obj, const char *key, size_t n,
                    const char *where, double *out)
{
    json_object *array = ao_gltf_member(obj, key);
    if (!json_object_is_type(array, json_type_array) || json_object_array_length(array) != n)
        return ao_gltf_error(g, "%s: '%s' must be an array of %zu numbers", where, key, n);
    for (size_t i = 0; i < n; i++) {
        json_object *item = json_object_array_get_idx(array, i);
        if (!json_object_is_type(item, json_type_int) && !json_object_is_type(item, json_type_double))
            return ao_gltf_error(g, "%s: '%s' must be an array of %zu numbers", where, key, n);
        out[i] = json_object_get_double(item);
        if (!isfinite(out[i]))
            return ao_gltf_error(g, "%s: '%s' holds a non-finite number", where, key);
    }
    return true;
}

/* Column-major 4x4 product out = a b (out may not alias). */
static void multiply(const double a[16], const double b[16], double out[16])
{
    for (int c = 0; c < 4; c++)
        for (int r = 0; r < 4; r++)
            out[4 * c + r] = a[r] * b[4 * c] + a[4 + r] * b[4 * c + 1] + a[8 + r] * b[4 * c + 2] +
                             a[12 + r] * b[4 * c + 3];
}

/* A node's local matrix: its 'matrix', else translation * rotation * scale. */
static bool local_matrix(const struct ao_gltf *g, json_object *node, const char *where, double m[16])
{
    if (ao_gltf_member(node, "matrix"))
        return numbers(g, node, "matrix", 16, where, m);
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    if ((ao_gltf_member(node, "translation") && !numbers(g, node, "translation", 3, where, t)) ||
        (ao_gltf_member(node, "rotation") && !numbers(g, node, "rotation", 4, where, q)) ||
        (ao_gltf_member(node, "scale") && !numbers(g, node, "scale", 3, where, s)))
        return false;
    /* glTF asks for a unit quaternion; any other nonzero one is normalized, divided first by its
     * largest component so that the squares can neither overflow (1e200 would give an infinite
     * length and a silent identity) nor vanish (1e-200, a zero length). */
    double big = fmax(fmax(fabs(q[0]), fabs(q[1])), fmax(fabs(q[2]), fabs(q[3])));
    if (!(big > 0.0))
        return ao_gltf_error(g, "%s: rotation is a zero quaternion", where);
    for (int k = 0; k < 4; k++)
        q[k] /= big;
    double length = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    double x = q[0] / length, y = q[1] / length, z = q[2] / length, w = q[3] / length;
    double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
                   2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                   2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; c++) {
        for (int k = 0; k < 3; k++)
            m[4 * c + k] = r[3 * c + k] * s[c];
        m[4 * c + 3] = 0.0;
    }
    m[12] = t[0];
    m[13] = t[1];
    m[14] = t[2];
    m[15] = 1.0;
    return true;
}

/* Records every node's parent, refusing bad child indices, a node with two parents and cycles. */
static bool check_tree(struct ao_gltf *g, size_t count)
{
    for (size_t i = 0; i < count; i++)
        g->parent[i] = SIZE_MAX;
    for (size_t i = 0; i < count; i++) {
        char where[64];
        snprintf(where, sizeof where, "node %zu", i);
        json_object *children;
        size_t n;
        if (!ao_gltf_array(g, json_object_array_get_idx(g->nodes, i), "children", where, &children, &n))
            return false;
        for (size_t k = 0; k < n; k++) {
            uint64_t child;
            if (!ao_gltf_whole(json_object_array_get_idx(children, k), AO_GLTF_MAX_INTEGER, &child) ||
                child >= count)
                return ao_gltf_error(g, "%s: child %zu is not a node index", where, k);
            if (g->parent[child] != SIZE_MAX)
                return ao_gltf_error(g, "node %llu is a child of nodes %zu and %zu (nodes must form "
                                  "trees)", (unsigned long long)child, g->parent[child], i);
            g->parent[child] = i;
        }
    }
    /* With one parent each, following parents from any node ends at a root or goes round a
     * cycle; each node is walked once (state: unseen, on the current walk, checked). */
    unsigned char *state = calloc(count ? count : 1, 1);
    if (!state)
        return ao_load_out_of_memory(g->path);
    bool ok = true;
    for (size_t i = 0; ok && i < count; i++) {
        size_t n = i;
        while (n != SIZE_MAX && state[n] == NODE_UNSEEN) {
            state[n] = NODE_WALKING;
            n = g->parent[n];
        }
        if (n != SIZE_MAX && state[n] == NODE_WALKING)
            ok = ao_gltf_error(g, "node %zu is its own ancestor (a cycle in the node graph)", n);
        for (n = i; n != SIZE_MAX && state[n] == NODE_WALKING; n = g->parent[n])
            state[n] = NODE_CHECKED;
    }
    free(state);
    return ok;
}

/* The roots: the default scene's nodes, scene 0's, or every node without a parent. Each root is
 * marked in is_root; a root listed twice or with a parent is refused. */
static bool find_roots(struct ao_gltf *g, size_t node_count, bool *is_root)
{
    json_object *scenes, *list;
    size_t scene_count, n;
    if (!ao_gltf_array(g, g->root, "scenes", "file", &scenes, &scene_count))
        return false;
    if (scene_count == 0) {
        for (size_t i = 0; i < node_count; i++)
            is_root[i] = g->parent[i] == SIZE_MAX;
        return true;
    }
    size_t scene = 0;
    if (ao_gltf_member(g->root, "scene") && !ao_gltf_index(g, g->root, "scene", scene_count, "file", &scene))
        return false;
    char where[64];
    snprintf(where, sizeof where, "scene %zu", scene);
    if (!ao_gltf_array(g, json_object_array_get_idx(scenes, scene), "nodes", where, &list, &n))
        return false;
    for (size_t k = 0; k < n; k++) {
        uint64_t node;
        if (!ao_gltf_whole(json_object_array_get_idx(list, k), AO_GLTF_MAX_INTEGER, &node) || node >= node_count)
            return ao_gltf_error(g, "%s: entry %zu is not a node index", where, k);
        if (is_root[node] || g->parent[node] != SIZE_MAX)
            return ao_gltf_error(g, "%s: node %llu is listed twice or is not a root", where,
                              (unsigned long long)node);
        is_root[node] = true;
    }
    return true;
}

/* World matrices of the roots and every node under them, parents first (the nodes form trees, so
 * each is pushed once and the stack never holds more than all of them); marks them placed. A node
 * deeper than AO_GLTF_MAX_NODE_DEPTH is refused. */
static bool place_nodes(struct ao_gltf *g, size_t node_count, const bool *is_root, bool *placed)
{
    static const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    size_t *stack = malloc((node_count ? node_count : 1) * sizeof *stack), top = 0;
    if (!stack)
        return ao_load_out_of_memory(g->path);
    for (size_t i = 0; i < node_count; i++)
        if (is_root[i])
            stack[top++] = i;
    bool ok = true;
    while (ok && top > 0) {
        size_t n = stack[--top];
        json_object *node = json_object_array_get_idx(g->nodes, n);
        char where[64];
        double local[16];
        snprintf(where, sizeof where, "node %zu", n);
        g->depth[n] = is_root[n] ? 1 : g->depth[g->parent[n]] + 1;
        if (g->depth[n] > AO_GLTF_MAX_NODE_DEPTH) {
            ok = ao_gltf_error(g, "%s lies more than %d nodes deep, the deepest node tree aoview reads", where,
                               AO_GLTF_MAX_NODE_DEPTH);
            break;
        }
        ok = local_matrix(g, node, where, local);
        if (ok)
            multiply(is_root[n] ? identity : g->world[g->parent[n]], local, g->world[n]);
        for (int k = 0; ok && k < 16; k++)
            if (!isfinite(g->world[n][k]))
                ok = ao_gltf_error(g, "%s: its transform overflows (an entry of its world matrix is "
                                "not finite)", where);
        placed[n] = true;
        json_object *children = ao_gltf_member(node, "children");
        for (size_t k = 0; ok && k < ao_gltf_length(children); k++) {
            uint64_t child = 0;
            ao_gltf_whole(json_object_array_get_idx(children, k), AO_GLTF_MAX_INTEGER, &child);
            stack[top++] = (size_t)child;   /* checked by check_tree */
        }
    }
    free(stack);
    return ok;
}

bool ao_gltf_place_nodes(struct ao_gltf *g, size_t node_count, bool *is_root, bool *placed)
{
    return check_tree(g, node_count) && find_roots(g, node_count, is_root) &&
           place_nodes(g, node_count, is_root, placed);
}
