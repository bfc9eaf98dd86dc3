/* The crease angle's passes over a mesh (see mesh.h): the vertices that the normals pass marked
 * (mesh_normals.c) are split along the edges sharper than the crease, each side of such a vertex
 * a vertex of its own with its own normal, on a team of threads (mesh_pass.h) with results that do
 * not depend on their number. */
#include "mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_pass.h"
#include "text.h"

/* What a part of the listing pass found: the marked vertices' corners in its triangles, as
 * (slot << 32 | corner) pairs in corner order (a corner c is triangle c / 3's (c % 3)th). */
struct found {
    uint64_t *pairs;
    size_t count, capacity;
};

/* The crease passes' data: the vertices the normals pass marked (struct cone), numbered 0, 1, ...
 * in vertex order (their slots); their corners, listed slot by slot in corner order; for each
 * listed corner its side of the vertex (0 for the side of the vertex's first corner; 1, 2, ... for
 * the others, in the order of their first corners); each marked vertex's extra sides, then the
 * first new vertex of each. */
struct crease {
    const unsigned char *marked;    /* vertex_count: 1 where the vertex's sides must be found */
    size_t count;                   /* marked vertices */
    uint32_t *ids;                  /* count: the marked vertices, ascending */
    uint32_t *slot;                 /* vertex_count: each marked vertex's slot (others: not set) */
    struct found found[AO_MESH_PASS_THREADS];
    uint32_t *start;                /* count + 1: where each slot's corners begin in corners */
    uint32_t *corners;              /* the marked vertices' corners */
    uint32_t *side;                 /* the side of each listed corner */
    uint32_t *extra;                /* count + 1: sides - 1, then the first new vertex of the sides */
    double cos_crease;              /* two triangles of normals n, m are smoothed together when n.m > this */
    bool failed;                    /* a part ran out of memory */
};

/* The unit normal of triangle t. */
static struct ao_dvec3 unit_normal(const struct ao_mesh *mesh, size_t t)
{
    struct ao_dvec3 n = ao_mesh_area_vector(mesh, t);
    double length = sqrt(ao_dvec3_dot(n, n));
    return ao_dvec3_make(n.x / length, n.y / length, n.z / length);
}

/* The root of i in a forest of parent links, halving the path on the way. */
static uint32_t root_of(uint32_t *parent, uint32_t i)
{
    while (parent[i] != i)
        i = parent[i] = parent[parent[i]];
    return i;
}

/* Sorts n keys ascending: insertion for the few a vertex usually has, else the C library's. */
static int compare_keys(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

static void sort_keys(uint64_t *keys, size_t n)
{
    if (n > 32) {
        qsort(keys, n, sizeof *keys, compare_keys);
        return;
    }
    for (size_t i = 1; i < n; i++) {
        uint64_t key = keys[i];
        size_t j = i;
        for (; j > 0 && keys[j - 1] > key; j--)
            keys[j] = keys[j - 1];
        keys[j] = key;
    }
}

/* A run of triangles meeting at one edge of a vertex: joined pairwise when their normals are closer
 * than the crease; a run longer than this (an edge of many triangles, which no real surface has)
 * joins its neighbours in the run only, so that the work stays linear. */
enum { PAIRWISE_RUN = 8 };

/* The sides of one vertex (its corners in list[0, k)): the corners of two triangles that share an
 * edge at v, whose normals lie closer than the crease, are on one side, and so on through the
 * fan. Writes each corner's side into side and returns the number of sides. Scratch: parent (k),
 * keys (2k), normals (k). */
static uint32_t sides_of(const struct ao_mesh *mesh, const uint32_t *list, uint32_t k, double cos_crease,
                         uint32_t *side, uint32_t *parent, uint64_t *keys, struct ao_dvec3 *normals)
{
    /* Each corner names its two neighbours at v: an edge (v, w) that two corners both name is
     * shared by their triangles. */
    for (uint32_t i = 0; i < k; i++) {
        uint32_t c = list[i], t = c / 3, j = c % 3;
        const uint32_t *tri = mesh->indices + 3 * (size_t)t;
        parent[i] = i;
        normals[i] = unit_normal(mesh, t);
        keys[2 * i] = (uint64_t)tri[(j + 1) % 3] << 32 | i;
        keys[2 * i + 1] = (uint64_t)tri[(j + 2) % 3] << 32 | i;
    }
    sort_keys(keys, 2 * (size_t)k);
    for (size_t a = 0; a < 2 * (size_t)k;) {
        size_t b = a + 1;
        while (b < 2 * (size_t)k && keys[b] >> 32 == keys[a] >> 32)
            b++;
        for (size_t x = a; x < b; x++)
            for (size_t y = x + 1; y < b && (b - a <= PAIRWISE_RUN || y == x + 1); y++) {
                uint32_t p = (uint32_t)keys[x], q = (uint32_t)keys[y];
                if (ao_dvec3_dot(normals[p], normals[q]) > cos_crease) {
                    uint32_t rp = root_of(parent, p), rq = root_of(parent, q);
                    parent[rp < rq ? rq : rp] = rp < rq ? rp : rq;
                }
            }
        a = b;
    }
    /* Sides numbered by their first corners: a root is always its side's first corner. */
    uint32_t sides = 0;
    for (uint32_t i = 0; i < k; i++) {
        uint32_t r = root_of(parent, i);
        side[i] = r == i ? sides++ : side[r];
    }
    return sides;
}

/* The first slot of part k of the marked vertices. */
static size_t slot_start(const struct mesh_pass *pass, int k)
{
    return ao_mesh_part_start(pass->crease->count, k, pass->threads);
}

/* The most corners a marked vertex of part k has. */
static uint32_t most_corners(const struct mesh_pass *pass, int k)
{
    const struct crease *cr = pass->crease;
    uint32_t most = 0;
    for (size_t m = slot_start(pass, k); m < slot_start(pass, k + 1); m++)
        most = cr->start[m + 1] - cr->start[m] > most ? cr->start[m + 1] - cr->start[m] : most;
    return most;
}

/* The listing pass over part k of the triangles: the marked vertices' corners found there. */
static void find_part(void *user, int k)
{
    struct mesh_pass *pass = user;
    struct crease *cr = pass->crease;
    struct found *f = &cr->found[k];
    const uint32_t *indices = pass->mesh->indices;
    size_t first = ao_mesh_part_start(pass->mesh->triangle_count, k, pass->threads);
    size_t end = ao_mesh_part_start(pass->mesh->triangle_count, k + 1, pass->threads);
    const unsigned char *marked = cr->marked;
    for (size_t t = first; t < end; t++) {
        const uint32_t *v = indices + 3 * t;
        if (!(marked[v[0]] | marked[v[1]] | marked[v[2]]))
            continue;
        for (int j = 0; j < 3; j++) {
            if (!marked[v[j]])
                continue;
            if (f->count == f->capacity) {
                size_t capacity = f->capacity ? 2 * f->capacity : 1024;
                uint64_t *pairs = realloc(f->pairs, capacity * sizeof *pairs);
                if (!pairs) {
                    cr->failed = true;
                    return;
                }
                f->pairs = pairs, f->capacity = capacity;
                ao_mesh_advise_huge(pairs, capacity * sizeof *pairs);
            }
            f->pairs[f->count++] = (uint64_t)cr->slot[v[j]] << 32 | (3 * t + (size_t)j);
        }
    }
}

/* Lists the marked vertices' corners (cr->start, cr->corners: counting sort by slot of what the
 * listing pass found, in corner order) and allocates the arrays of the passes after it; false when
 * memory runs out. */
static bool list_corners(struct mesh_pass *pass)
{
    struct crease *cr = pass->crease;
    const struct ao_mesh *mesh = pass->mesh;
    cr->ids = malloc((cr->count + 1) * sizeof *cr->ids);
    cr->slot = malloc(mesh->vertex_count * sizeof *cr->slot);
    if (!cr->ids || !cr->slot)
        return false;
    ao_mesh_advise_huge(cr->ids, cr->count * sizeof *cr->ids);
    ao_mesh_advise_huge(cr->slot, mesh->vertex_count * sizeof *cr->slot);
    for (size_t v = 0, m = 0; v < mesh->vertex_count; v++) {
        uint64_t eight;
        if (v % 8 == 0 && v + 8 <= mesh->vertex_count && (memcpy(&eight, cr->marked + v, 8), eight == 0)) {
            v += 7;   /* eight unmarked vertices at one test */
            continue;
        }
        if (cr->marked[v]) {
            cr->slot[v] = (uint32_t)m;
            cr->ids[m++] = (uint32_t)v;
        }
    }
    ao_mesh_run_parts(find_part, pass);
    size_t listed = 0;
    for (int k = 0; k < pass->threads; k++)
        listed += cr->found[k].count;
    cr->start = calloc(cr->count + 1, sizeof *cr->start);
    cr->corners = malloc((listed + 1) * sizeof *cr->corners);
    cr->side = malloc((listed + 1) * sizeof *cr->side);
    cr->extra = malloc((cr->count + 1) * sizeof *cr->extra);
    if (cr->failed || !cr->start || !cr->corners || !cr->side || !cr->extra)
        return false;
    ao_mesh_advise_huge(cr->start, cr->count * sizeof *cr->start);
    ao_mesh_advise_huge(cr->corners, listed * sizeof *cr->corners);
    ao_mesh_advise_huge(cr->side, listed * sizeof *cr->side);
    ao_mesh_advise_huge(cr->extra, cr->count * sizeof *cr->extra);
    for (int k = 0; k < pass->threads; k++)
        for (size_t i = 0; i < cr->found[k].count; i++)
            cr->start[(cr->found[k].pairs[i] >> 32) + 1]++;
    for (size_t m = 0; m < cr->count; m++)
        cr->start[m + 1] += cr->start[m];
    for (int k = 0; k < pass->threads; k++) {   /* start[m] walks through m's slots; shifted back below */
        for (size_t i = 0; i < cr->found[k].count; i++)
            cr->corners[cr->start[cr->found[k].pairs[i] >> 32]++] = (uint32_t)cr->found[k].pairs[i];
        free(cr->found[k].pairs);
        cr->found[k] = (struct found){0};
    }
    for (size_t m = cr->count; m > 0; m--)
        cr->start[m] = cr->start[m - 1];
    cr->start[0] = 0;
    return true;
}

/* The sides pass over part k of the marked vertices: the sides of each. */
static void sides_part(void *user, int k)
{
    struct mesh_pass *pass = user;
    struct crease *cr = pass->crease;
    uint32_t most = most_corners(pass, k);
    uint32_t *parent = malloc((most ? most : 1) * sizeof *parent);
    uint64_t *keys = malloc((most ? 2 * (size_t)most : 1) * sizeof *keys);
    struct ao_dvec3 *normals = malloc((most ? most : 1) * sizeof *normals);
    if (!parent || !keys || !normals) {
        cr->failed = true;
    } else {
        ao_mesh_advise_huge(parent, most * sizeof *parent);
        ao_mesh_advise_huge(keys, 2 * (size_t)most * sizeof *keys);
        ao_mesh_advise_huge(normals, most * sizeof *normals);
        for (size_t m = slot_start(pass, k); m < slot_start(pass, k + 1); m++) {
            uint32_t begin = cr->start[m], count = cr->start[m + 1] - begin;
            cr->extra[m] = sides_of(pass->mesh, cr->corners + begin, count, cr->cos_crease, cr->side + begin, parent,
                                    keys, normals) - 1;
        }
    }
    free(parent);
    free(keys);
    free(normals);
}

/* The normals pass over the split vertices of part k of the marked ones: each side's normal (its
 * corners' shares, in triangle order, as normals_part adds them) into the vertex (side 0) and its
 * new vertices. Reads the triangles as they were before the split (move_part comes after). */
static void side_normals_part(void *user, int k)
{
    struct mesh_pass *pass = user;
    struct crease *cr = pass->crease;
    uint32_t most = most_corners(pass, k);
    struct ao_vec3 *sums = malloc((most ? most : 1) * sizeof *sums);
    if (!sums) {
        cr->failed = true;
        return;
    }
    for (size_t m = slot_start(pass, k); m < slot_start(pass, k + 1); m++) {
        uint32_t more = cr->extra[m + 1] - cr->extra[m];
        if (more == 0)
            continue;
        memset(sums, 0, (more + 1) * sizeof *sums);
        for (uint32_t i = cr->start[m]; i < cr->start[m + 1]; i++) {
            struct triangle_terms terms;
            uint32_t c = cr->corners[i];
            double angle;
            if (ao_mesh_triangle_terms(pass->mesh, pass->mesh->indices + 3 * (size_t)(c / 3), &terms))
                sums[cr->side[i]] = ao_vec3_add(sums[cr->side[i]], ao_mesh_corner_share(&terms, (int)(c % 3), &angle));
        }
        for (uint32_t s = 0; s <= more; s++)
            pass->out[s ? cr->extra[m] + s - 1 : cr->ids[m]] = ao_mesh_unit(sums[s].x, sums[s].y, sums[s].z);
    }
    free(sums);
}

/* The last crease pass over part k of the marked vertices: each corner on a side but the first is
 * moved to that side's new vertex. */
static void move_part(void *user, int k)
{
    struct mesh_pass *pass = user;
    struct crease *cr = pass->crease;
    for (size_t m = slot_start(pass, k); m < slot_start(pass, k + 1); m++)
        for (uint32_t i = cr->start[m]; cr->extra[m + 1] > cr->extra[m] && i < cr->start[m + 1]; i++)
            if (cr->side[i])
                pass->mesh->indices[cr->corners[i]] = cr->extra[m] + cr->side[i] - 1;
}

/* Grows the vertex arrays to count vertices and fills the new ones' positions (from
 * mesh->vertex_count on, numbered in cr->extra): each a copy of the vertex it splits from. */
static bool add_split_vertices(struct ao_mesh *mesh, const struct crease *cr, size_t count)
{
    struct ao_vec3 *positions = realloc(mesh->positions, count * sizeof *positions);
    if (!positions)
        return false;
    mesh->positions = positions;
    struct ao_vec3 *normals = realloc(mesh->normals, count * sizeof *normals);
    if (!normals)
        return false;
    mesh->normals = normals;
    for (size_t m = 0; m < cr->count; m++)
        for (uint32_t n = cr->extra[m]; n < cr->extra[m + 1]; n++)
            positions[n] = positions[cr->ids[m]];
    return true;
}

/* Splits the vertices that the cone marks along the edges sharper than the crease (their triangles'
 * normals cos_crease or farther apart): each side of such a vertex but the first gets a new
 * vertex, a copy at the end of the arrays, and each side its own normal (as the normals pass would
 * make it over the split mesh). The mesh's other vertices keep their numbers and normals, so that a
 * mesh without such an edge is left as it was. False (reported) when memory, 32-bit corner numbers
 * or the budget run out. */
bool ao_mesh_split_creases(struct ao_mesh *mesh, const char *path, const struct cone *cone, size_t marked,
                           double cos_crease, const struct ao_budget *budget)
{
    struct crease crease = {.marked = cone->marked, .count = marked, .cos_crease = cos_crease};
    struct crease *cr = &crease;
    if (3 * (uint64_t)mesh->triangle_count > UINT32_MAX) {
        ao_text_report("%s: %zu triangles are too many for a crease angle (at most %u); --crease-angle 0 "
                       "or 180 takes any number", path, mesh->triangle_count, UINT32_MAX / 3);
        return false;
    }
    struct mesh_pass pass = {.mesh = mesh, .crease = cr};
    bool ok = list_corners(&pass);
    if (ok) {
        ao_mesh_run_parts(sides_part, &pass);
        ok = !cr->failed;
    }
    bool reported = false;
    uint64_t count = mesh->vertex_count;
    for (size_t m = 0; ok && m <= cr->count; m++) {   /* the new vertices' numbers */
        uint32_t more = m < cr->count ? cr->extra[m] : 0;
        cr->extra[m] = (uint32_t)count;
        if ((count += more) >= AO_MESH_INDEX_LIMIT) {
            ao_text_report("%s: more than %u vertices once split along its creases", path, AO_MESH_INDEX_LIMIT - 1);
            ok = false;
            reported = true;
        }
    }
    if (ok && count > mesh->vertex_count) {
        reported = !ao_mesh_fits(budget, mesh->triangle_count, count, path, 0);
        ok = !reported && add_split_vertices(mesh, cr, (size_t)count);
        /* Each side's normal: by the marked vertices' corners where they are fewer than the
         * triangles, else by the normals pass over the split mesh (the same bits either way). */
        size_t listed = ok ? cr->start[cr->count] : 0;
        bool by_corners = listed < mesh->triangle_count;
        if (ok && by_corners) {
            pass.out = mesh->normals;
            ao_mesh_run_parts(side_normals_part, &pass);
            ok = !cr->failed;
        }
        struct ao_vec3 *all = ok && !by_corners ? malloc((size_t)count * sizeof *all) : NULL;
        ok = ok && (by_corners || all);
        if (all)
            ao_mesh_advise_huge(all, (size_t)count * sizeof *all);
        if (ok) {
            ao_mesh_run_parts(move_part, &pass);
            mesh->vertex_count = (size_t)count;
            if (all) {   /* the split vertices' normals; the others keep theirs, given or smooth */
                ao_mesh_angle_weighted_normals(mesh, all, 0, NULL);
                for (size_t m = 0; m < cr->count; m++)
                    for (uint32_t n = cr->extra[m]; n < cr->extra[m + 1]; n++)
                        mesh->normals[cr->ids[m]] = all[cr->ids[m]], mesh->normals[n] = all[n];
            }
        }
        free(all);
    }
    for (int k = 0; k < AO_MESH_PASS_THREADS; k++)
        free(cr->found[k].pairs);
    free(cr->ids);
    free(cr->slot);
    free(cr->start);
    free(cr->corners);
    free(cr->side);
    free(cr->extra);
    return ok || reported || ao_mesh_out_of_memory(path);
}
