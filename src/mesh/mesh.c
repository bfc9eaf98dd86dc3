/* Meshes (see mesh.h): placement, freeing, zero-area triangles dropped, and the normals a file does
 * not give made, as its format means them: flat (glTF), or angle-weighted across the edges flatter
 * than a crease angle (OBJ, PLY, STL), the vertices on sharper edges split so that each side keeps
 * its own normal. The passes over a big mesh run on one thread per core, with results that do not
 * depend on the number of threads. */
/* Linux's madvise and MADV_HUGEPAGE, which POSIX lacks, for ao_mesh_advise_huge alone. */
#define _DEFAULT_SOURCE
#include "mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "pool.h"
#include "text.h"

/* A vertex position in double precision, for exact-enough normals of float positions. */
static struct ao_dvec3 position(const struct ao_mesh *mesh, uint32_t vertex)
{
    return ao_dvec3_of(mesh->positions[vertex]);
}

/* Twice the area vector of triangle t, (p1 - p0) x (p2 - p0), exact for float positions up
 * to one rounding; zero exactly when the triangle is degenerate. */
static struct ao_dvec3 area_vector(const struct ao_mesh *mesh, size_t t)
{
    const uint32_t *v = mesh->indices + 3 * t;
    struct ao_dvec3 p0 = position(mesh, v[0]);
    return ao_dvec3_cross(ao_dvec3_sub(position(mesh, v[1]), p0), ao_dvec3_sub(position(mesh, v[2]), p0));
}

/* ------------------------------------------------------------------ the mesh */

/* Reports an allocation failure as "path: out of memory"; returns false for the caller to pass on. */
static bool out_of_memory(const char *path)
{
    ao_text_report("%s: out of memory", path);
    return false;
}

bool ao_mesh_fits(const struct ao_budget *budget, uint64_t triangles, uint64_t vertices, const char *path,
                  size_t line)
{
    uint64_t charge = ao_budget_charge(budget, triangles, vertices, 0);
    if (ao_budget_fits(budget, charge))
        return true;
    char why[200], where[32] = "";
    ao_budget_explain(budget, charge, why, sizeof why);
    if (line)
        snprintf(where, sizeof where, ":%zu", line);
    ao_text_report("%s%s: %llu triangles and %llu vertices %s", path, where, (unsigned long long)triangles,
                   (unsigned long long)vertices, why);
    return false;
}

/* Advises the pages that [data, data + size) touches into transparent huge pages, where the system
 * has them (Linux's "madvise" mode) and the array is big enough to gain. The advice covers all of
 * a big block that malloc mapped by itself (from its page-aligned header to its end), so that its
 * mapping stays whole and realloc can still move it without copying; pages shared with other
 * blocks only change how they are backed. */
void ao_mesh_advise_huge(void *data, size_t size)
{
#ifdef MADV_HUGEPAGE
    uintptr_t page = (uintptr_t)sysconf(_SC_PAGESIZE), start = (uintptr_t)data;
    uintptr_t begin = start / page * page, end = (start + size + page - 1) / page * page;
    if (size >= AO_MESH_HUGE_ARRAY)
        madvise((void *)begin, end - begin, MADV_HUGEPAGE);
#else
    (void)data, (void)size;
#endif
}

/* The unit vector along (x, y, z) in single precision, or zero when it is zero or not finite.
 * Divided first by its largest component, so that squares neither overflow nor vanish. */
struct ao_vec3 ao_mesh_unit(double x, double y, double z)
{
    double big = fmax(fabs(x), fmax(fabs(y), fabs(z)));
    if (!(big > 0.0) || !isfinite(x) || !isfinite(y) || !isfinite(z))
        return ao_vec3_make(0.0f, 0.0f, 0.0f);
    x /= big, y /= big, z /= big;
    double length = sqrt(x * x + y * y + z * z);
    return ao_vec3_make((float)(x / length), (float)(y / length), (float)(z / length));
}

struct ao_vec3 ao_mesh_missing_normal(void)
{
    return ao_vec3_make(NAN, NAN, NAN);
}

bool ao_mesh_normal_is_missing(struct ao_vec3 n)
{
    return isnan(n.x);
}

struct ao_vec3 ao_mesh_given_normal(double x, double y, double z, size_t *invalid)
{
    struct ao_vec3 n = ao_mesh_unit(x, y, z);
    if (n.x != 0.0f || n.y != 0.0f || n.z != 0.0f)
        return n;
    ++*invalid;
    return ao_mesh_missing_normal();
}

size_t ao_mesh_place(struct ao_mesh *dst, size_t vertex_base, size_t triangle_base, const struct ao_mesh *src,
                     const struct ao_affine *map)
{
    double n[9];
    bool mirror = ao_affine_normals(map, n) < 0.0;
    size_t bad = src->vertex_count;
    for (size_t v = 0; v < src->vertex_count; v++) {
        struct ao_vec3 a = src->positions[v], b = src->normals[v];
        struct ao_vec3 *o = &dst->positions[vertex_base + v];
        *o = ao_dvec3_narrow(ao_affine_point(map, a.x, a.y, a.z));
        if (bad == src->vertex_count && !ao_vec3_is_finite(*o))
            bad = v;
        dst->normals[vertex_base + v] = ao_mesh_unit(n[0] * b.x + n[3] * b.y + n[6] * b.z,
                                                     n[1] * b.x + n[4] * b.y + n[7] * b.z,
                                                     n[2] * b.x + n[5] * b.y + n[8] * b.z);
    }
    uint32_t base = (uint32_t)vertex_base, *t = dst->indices + 3 * triangle_base;
    for (size_t k = 0; k < src->triangle_count; k++) {
        uint32_t i0 = src->indices[3 * k], i1 = src->indices[3 * k + 1], i2 = src->indices[3 * k + 2];
        t[3 * k] = base + i0;
        t[3 * k + 1] = base + (mirror ? i2 : i1);
        t[3 * k + 2] = base + (mirror ? i1 : i2);
    }
    return bad;
}

void ao_mesh_finish(struct ao_mesh *mesh)
{
    free(mesh->positions);
    free(mesh->normals);
    free(mesh->indices);
    memset(mesh, 0, sizeof *mesh);
}

void ao_model_finish(struct ao_model *model)
{
    for (size_t i = 0; model->meshes && i < model->mesh_count; i++)
        ao_mesh_finish(&model->meshes[i]);
    free(model->meshes);
    free(model->placements);
    memset(model, 0, sizeof *model);
}

/* ------------------------------------------------------------------ passes on a team */

/* The most threads a mesh pass uses, and the fewest triangles worth a second one. */
enum { MAX_THREADS = 64, TRIANGLES_PER_THREAD = 1 << 16 };

/* A pass over a mesh on a team of threads: what each part needs and gives back. */
struct mesh_pass {
    const struct ao_mesh *mesh;
    struct ao_vec3 *out;                /* normals: every vertex's */
    int threads;
    size_t counts[MAX_THREADS];         /* what each part counted: degenerate triangles, marked vertices */
    struct cone *cone;                  /* the crease's check, made by the normals pass when asked */
    struct crease *crease;              /* the crease passes' arrays */
};

/* The start of part k of n in [0, count). */
static size_t part_start(size_t count, int k, int n)
{
    return count / (size_t)n * (size_t)k + count % (size_t)n * (size_t)k / (size_t)n;
}

/* Runs job(pass, k) for every part k in [0, pass->threads) on that many threads (when it is 0 or
 * less: one per core, and one per TRIANGLES_PER_THREAD triangles at most), the caller being one of
 * them; on one thread, part after part, when threads cannot be started (the parts' results
 * do not depend on which thread runs them). */
static void run_parts(ao_pool_job *job, struct mesh_pass *pass)
{
    long online = sysconf(_SC_NPROCESSORS_ONLN);
    size_t wanted = pass->mesh->triangle_count / TRIANGLES_PER_THREAD + 1;
    if (pass->threads <= 0)
        pass->threads = (int)(online < 1 ? 1 : (size_t)online < wanted ? (size_t)online : wanted);
    pass->threads = pass->threads < MAX_THREADS ? pass->threads : MAX_THREADS;
    struct ao_pool *pool = pass->threads > 1 ? ao_pool_create(pass->threads, NULL) : NULL;
    if (pool)
        ao_pool_run(pool, job, pass);
    for (int k = 0; !pool && k < pass->threads; k++)
        job(pass, k);
    ao_pool_destroy(pool);
}

/* ------------------------------------------------------------------ degenerate triangles */

/* Counts the degenerate triangles of part k of the triangles. */
static void count_degenerate(void *user, int k)
{
    struct mesh_pass *pass = user;
    size_t end = part_start(pass->mesh->triangle_count, k + 1, pass->threads);
    pass->counts[k] = 0;
    for (size_t t = part_start(pass->mesh->triangle_count, k, pass->threads); t < end; t++) {
        struct ao_dvec3 n = area_vector(pass->mesh, t);
        pass->counts[k] += ao_dvec3_dot(n, n) == 0.0;
    }
}

/* Found in parallel, then, when there are any, removed in one pass. */
void ao_mesh_drop_degenerate(struct ao_mesh *mesh)
{
    struct mesh_pass pass = {.mesh = mesh};
    size_t found = 0, kept = 0;
    run_parts(count_degenerate, &pass);
    for (int k = 0; k < pass.threads; k++)
        found += pass.counts[k];
    for (size_t t = 0; found && t < mesh->triangle_count; t++) {
        struct ao_dvec3 n = area_vector(mesh, t);
        if (ao_dvec3_dot(n, n) == 0.0)
            continue;
        if (kept != t)
            memcpy(mesh->indices + 3 * kept, mesh->indices + 3 * t, 3 * sizeof *mesh->indices);
        kept++;
    }
    mesh->degenerate_count += found;
    mesh->triangle_count -= found;
}

/* ------------------------------------------------------------------ angle-weighted normals */

/* atan2(y, x) for y > 0 (the interior angle of a corner whose edges a, b have |a x b| = y and
 * a . b = x), within 1e-9 of it and at a few times its speed: reduced to atan t, t in [0, 1]
 * (atan t = pi/2 - atan(1/t); atan(-t) = pi - ...), then to |t| <= tan(pi/12) by
 * atan t = pi/6 + atan((sqrt(3) t - 1) / (t + sqrt(3))), where atan's series to t^13 leaves
 * at most tan(pi/12)^15 / 15 < 3e-10. */
static inline double corner_angle(double y, double x)
{
    const double pi = 3.14159265358979323846, sqrt3 = 1.73205080756887729353;
    double ax = fabs(x);
    bool steep = y > ax;
    double t = steep ? ax / y : y / ax;
    bool shifted = t > 2.0 - sqrt3;
    if (shifted)
        t = (t * sqrt3 - 1.0) / (t + sqrt3);
    double t2 = t * t;
    double a = t * (1.0 + t2 * (-1.0 / 3 + t2 * (1.0 / 5 + t2 * (-1.0 / 7 + t2 * (1.0 / 9 + t2 * (-1.0 / 11 +
                                                                                             t2 / 13))))));
    a += shifted ? pi / 6 : 0.0;
    a = steep ? pi / 2 - a : a;
    return x < 0.0 ? pi - a : a;
}

/* What the normals take from a triangle of corners v: its area vector n (area_vector's, as it
 * computes it), twice its area, and at each corner c the dot product of the corner's two edges. */
struct triangle_terms {
    struct ao_dvec3 n;
    double twice_area, scale, dots[3];   /* scale: 1 / twice_area */
};

/* The terms of the triangle of corners v; false when it is degenerate (no normal to add). */
static inline bool triangle_terms(const struct ao_mesh *mesh, const uint32_t *v, struct triangle_terms *out)
{
    struct ao_dvec3 p[3] = {position(mesh, v[0]), position(mesh, v[1]), position(mesh, v[2])};
    struct ao_dvec3 edge[3] = {ao_dvec3_sub(p[1], p[0]), ao_dvec3_sub(p[2], p[1]), ao_dvec3_sub(p[0], p[2])};
    struct ao_dvec3 b = ao_dvec3_sub(p[2], p[0]);
    out->n = ao_dvec3_cross(edge[0], b);
    out->twice_area = sqrt(ao_dvec3_dot(out->n, out->n));
    if (out->twice_area == 0.0)
        return false;
    out->scale = 1.0 / out->twice_area;
    /* Corner c's edges are edge[c] and -edge[c + 2]; |a x b| = twice the area at every corner, so
     * the angle comes stably from it and a . b. */
    out->dots[0] = ao_dvec3_dot(edge[0], b);
    out->dots[1] = -ao_dvec3_dot(edge[1], edge[0]);
    out->dots[2] = -ao_dvec3_dot(edge[2], edge[1]);
    return true;
}

/* What corner c of a triangle of these terms adds to its vertex's normal: the unit normal times
 * the corner's angle (*angle), in float, as every normals sum adds it. */
static inline struct ao_vec3 corner_share(const struct triangle_terms *t, int c, double *angle)
{
    *angle = corner_angle(t->twice_area, t->dots[c]);
    double weight = *angle * t->scale;
    return ao_vec3_make((float)(t->n.x * weight), (float)(t->n.y * weight), (float)(t->n.z * weight));
}

/* What a normals pass gathers at a vertex for the crease angle: the first of its triangles' unit
 * normals (f), the least dot product of the others with it, the sum of its corners' angles, the
 * sum of a hash of each corner's next neighbour less one of its previous neighbour, and its first
 * and last triangles (32 bits: a mesh with a crease has fewer than 2^32 corners). */
struct cone_vertex {
    float first[3], nearest;
    double angle_sum;
    uint64_t link;
    uint32_t from, to;
};

/* The check a normals pass makes for the crease angle, when asked: per vertex what it gathers, and
 * whether the vertex's sides must be found edge by edge (marked). */
struct cone {
    const struct ao_vec3 *given;    /* NULL, or the mesh's normals: a vertex given one is not marked */
    double cos_half;                /* cos(crease / 2) */
    struct cone_vertex *at;         /* vertex_count, filled by the pass */
    unsigned char *marked;          /* vertex_count: 1 where the vertex's sides must be found */
};

/* A 64-bit hash of a vertex number (a multiply, shift and multiply, as splitmix64's finalizer
 * mixes). */
static inline uint64_t vertex_hash(uint32_t v)
{
    uint64_t z = ((uint64_t)v + 1) * 0x9E3779B97F4A7C15u;
    return (z ^ (z >> 29)) * 0xBF58476D1CE4E5B9u;
}

/* Adds a corner of triangle t, of unit normal u (in float) and angle `angle` at the vertex, whose
 * next neighbour's hash less its previous neighbour's is link, to what the cone gathers there. */
static inline void gather_corner(struct cone_vertex *at, size_t t, struct ao_vec3 u, double angle, uint64_t link)
{
    if (at->angle_sum == 0.0) {
        at->first[0] = u.x, at->first[1] = u.y, at->first[2] = u.z;
        at->from = (uint32_t)t;
    } else {
        float d = u.x * at->first[0] + u.y * at->first[1] + u.z * at->first[2];
        at->nearest = d < at->nearest ? d : at->nearest;
    }
    at->angle_sum += angle;
    at->link += link;
    at->to = (uint32_t)t;
}

/* Whether vertex i (gathered at `at`) must have its sides found edge by edge, or is one side for
 * certain, as sides_of would find it: where (1) every triangle's unit normal u_j lies within half
 * the crease angle (alpha) of the first's, f (dot products in float above cos alpha, with 1e-6
 * for their rounding), every two lie closer than the crease, and sides_of joins
 * every two corners that share an edge; (2) the corners' next and previous neighbours are the same
 * vertices as often (hash sums equal: a 2^-64 chance of being wrong otherwise), so that the corners
 * chain into closed fans, each corner's wedge ending on the edge where another's begins; and (3)
 * the angles sum to less than 4 pi cos alpha, the fans are one: seen along f, each wedge of angle a_j
 * and normal within alpha of f spans at most a_j / cos alpha (its unit sector's shadow, of area
 * cos beta a_j / 2, holds the sector of radius cos beta of the shadow's angle), and each closed fan
 * at least 2 pi. A vertex without triangles is one side; one given a normal is never split. */
static bool needs_sides(const struct cone *cone, size_t i)
{
    const struct cone_vertex *at = &cone->at[i];
    if (at->angle_sum == 0.0 || (cone->given && !ao_mesh_normal_is_missing(cone->given[i])))
        return false;
    const double four_pi = 4.0 * 3.14159265358979323846;
    return !(at->nearest > cone->cos_half + 1e-6 && at->link == 0 && at->angle_sum < four_pi * cone->cos_half);
}

/* Angle-weighted vertex normals (Thürmer and Wüthrich 1998) of part k of the vertices: each
 * triangle adds its unit normal times its interior angle at the vertex, so the result does not
 * depend on how a surface is split into triangles; the sum is then normalized. Every part reads
 * every triangle and adds only at its own vertices, in triangle order: each vertex's sum is the
 * same, bit for bit, whatever the number of parts. Vertices without a nondegenerate triangle get
 * the zero vector. With a cone, also what it gathers and its marks, the marked counted in
 * pass->counts[k]. */
static inline void normals_of(struct mesh_pass *pass, int k, struct cone *cone)
{
    const struct ao_mesh *mesh = pass->mesh;
    struct ao_vec3 *out = pass->out;
    uint32_t first = (uint32_t)part_start(mesh->vertex_count, k, pass->threads);
    uint32_t count = (uint32_t)part_start(mesh->vertex_count, k + 1, pass->threads) - first;
    memset(out + first, 0, count * sizeof *out);
    for (uint32_t i = first; cone && i < first + count; i++)
        cone->at[i] = (struct cone_vertex){.nearest = 1.0f};
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *v = mesh->indices + 3 * t;
        bool mine[3] = {v[0] - first < count, v[1] - first < count, v[2] - first < count};
        struct triangle_terms terms;
        if (!(mine[0] | mine[1] | mine[2]) || !triangle_terms(mesh, v, &terms))
            continue;
        double angles[3];
        for (int c = 0; c < 3; c++)
            if (mine[c])
                out[v[c]] = ao_vec3_add(out[v[c]], corner_share(&terms, c, &angles[c]));
        if (!cone)
            continue;
        struct ao_vec3 u = ao_dvec3_narrow(ao_dvec3_scale(terms.n, terms.scale));
        uint64_t h0 = vertex_hash(v[0]), h1 = vertex_hash(v[1]), h2 = vertex_hash(v[2]);
        uint64_t links[3] = {h1 - h2, h2 - h0, h0 - h1};   /* next less previous, at each corner */
        for (int c = 0; c < 3; c++)
            if (mine[c])
                gather_corner(&cone->at[v[c]], t, u, angles[c], links[c]);
    }
    size_t marked = 0;
    for (uint32_t i = first; i < first + count; i++) {
        if (cone)
            marked += cone->marked[i] = needs_sides(cone, i);
        out[i] = ao_mesh_unit(out[i].x, out[i].y, out[i].z);
    }
    pass->counts[k] = marked;
}

/* normals_of, compiled apart without the cone and with it (pass->cone). */
static void normals_part(void *user, int k)
{
    struct mesh_pass *pass = user;
    if (pass->cone)
        normals_of(pass, k, pass->cone);
    else
        normals_of(pass, k, NULL);
}

/* Writes the angle-weighted normals of all mesh->vertex_count vertices into out, on so many
 * threads (0: run_parts's choice), with cone's check when it is not NULL; returns how many
 * vertices that marks. */
static size_t angle_weighted_normals(const struct ao_mesh *mesh, struct ao_vec3 *out, int threads, struct cone *cone)
{
    struct mesh_pass pass = {.mesh = mesh, .out = out, .threads = threads, .cone = cone};
    run_parts(normals_part, &pass);
    size_t marked = 0;
    for (int k = 0; k < pass.threads; k++)
        marked += pass.counts[k];
    return marked;
}

/* Angle-weighted normals of every vertex into mesh->normals (allocated when NULL), on so many
 * threads (0: run_parts's choice); false when memory runs out (not reported). */
static bool compute_normals(struct ao_mesh *mesh, int threads)
{
    if (mesh->vertex_count == 0)
        return true;
    if (!mesh->normals) {
        if (!(mesh->normals = malloc(mesh->vertex_count * sizeof *mesh->normals)))
            return false;
        ao_mesh_advise_huge(mesh->normals, mesh->vertex_count * sizeof *mesh->normals);
    }
    angle_weighted_normals(mesh, mesh->normals, threads, NULL);
    return true;
}

/* ------------------------------------------------------------------ creases */

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
    const struct cone_vertex *at;   /* vertex_count: what the normals pass gathered */
    size_t count;                   /* marked vertices */
    unsigned char *blocks;          /* per BLOCK triangles: 1 where a marked vertex has a triangle */
    uint32_t *ids;                  /* count: the marked vertices, ascending */
    uint32_t *slot;                 /* vertex_count: each marked vertex's slot (others: not set) */
    struct found found[MAX_THREADS];
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
    struct ao_dvec3 n = area_vector(mesh, t);
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
    return part_start(pass->crease->count, k, pass->threads);
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

/* The listing pass reads the triangles in blocks of so many, only those where a marked vertex has
 * triangles (between its first and its last). */
enum { BLOCK = 4096 };

/* The listing pass over part k of the triangles: the marked vertices' corners found there. */
static void find_part(void *user, int k)
{
    struct mesh_pass *pass = user;
    struct crease *cr = pass->crease;
    struct found *f = &cr->found[k];
    const uint32_t *indices = pass->mesh->indices;
    size_t first = part_start(pass->mesh->triangle_count, k, pass->threads);
    size_t end = part_start(pass->mesh->triangle_count, k + 1, pass->threads);
    for (size_t t = first; t < end; t = (t / BLOCK + 1) * BLOCK) {
        if (!cr->blocks[t / BLOCK])
            continue;
        size_t stop = (t / BLOCK + 1) * BLOCK < end ? (t / BLOCK + 1) * BLOCK : end;
        for (size_t c = 3 * t; c < 3 * stop; c++) {
            if (!cr->marked[indices[c]])
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
            f->pairs[f->count++] = (uint64_t)cr->slot[indices[c]] << 32 | c;
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
    size_t blocks = mesh->triangle_count / BLOCK + 1;
    int32_t *open = calloc(blocks + 1, sizeof *open);   /* marked vertices whose triangles begin, less end */
    cr->blocks = malloc(blocks);
    if (!open || !cr->blocks) {
        free(open);
        return false;
    }
    for (size_t v = 0, m = 0; v < mesh->vertex_count; v++)
        if (cr->marked[v]) {
            cr->slot[v] = (uint32_t)m;
            cr->ids[m++] = (uint32_t)v;
            open[cr->at[v].from / BLOCK]++;
            open[cr->at[v].to / BLOCK + 1]--;
        }
    for (size_t b = 0, inside = 0; b < blocks; b++) {
        inside += (size_t)open[b];
        cr->blocks[b] = inside > 0;
    }
    free(open);
    run_parts(find_part, pass);
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
            if (triangle_terms(pass->mesh, pass->mesh->indices + 3 * (size_t)(c / 3), &terms))
                sums[cr->side[i]] = ao_vec3_add(sums[cr->side[i]], corner_share(&terms, (int)(c % 3), &angle));
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

/* Splits the vertices that cr marks along the edges sharper than the crease (their triangles'
 * normals cos_crease or farther apart): each side of such a vertex but the first gets a new
 * vertex, a copy at the end of the arrays, and each side its own normal (as the normals pass would
 * make it over the split mesh). The mesh's other vertices keep their numbers and normals, so that a
 * mesh without such an edge is left as it was. False (reported) when memory, 32-bit corner numbers
 * or the budget run out. */
static bool split_creases(struct ao_mesh *mesh, const char *path, struct crease *cr, const struct ao_budget *budget)
{
    if (3 * (uint64_t)mesh->triangle_count > UINT32_MAX) {
        ao_text_report("%s: %zu triangles are too many for a crease angle (at most %u); --crease-angle 0 "
                       "or 180 takes any number", path, mesh->triangle_count, UINT32_MAX / 3);
        return false;
    }
    struct mesh_pass pass = {.mesh = mesh, .crease = cr};
    bool ok = list_corners(&pass);
    if (ok) {
        run_parts(sides_part, &pass);
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
            run_parts(side_normals_part, &pass);
            ok = !cr->failed;
        }
        struct ao_vec3 *all = ok && !by_corners ? malloc((size_t)count * sizeof *all) : NULL;
        ok = ok && (by_corners || all);
        if (all)
            ao_mesh_advise_huge(all, (size_t)count * sizeof *all);
        if (ok) {
            run_parts(move_part, &pass);
            mesh->vertex_count = (size_t)count;
            if (all) {   /* the split vertices' normals; the others keep theirs, given or smooth */
                angle_weighted_normals(mesh, all, 0, NULL);
                for (size_t m = 0; m < cr->count; m++)
                    for (uint32_t n = cr->extra[m]; n < cr->extra[m + 1]; n++)
                        mesh->normals[cr->ids[m]] = all[cr->ids[m]], mesh->normals[n] = all[n];
            }
        }
        free(all);
    }
    for (int k = 0; k < MAX_THREADS; k++)
        free(cr->found[k].pairs);
    free(cr->ids);
    free(cr->slot);
    free(cr->blocks);
    free(cr->start);
    free(cr->corners);
    free(cr->side);
    free(cr->extra);
    return ok || reported || out_of_memory(path);
}

bool ao_mesh_complete_normals(struct ao_mesh *mesh, const char *path, double crease, const struct ao_budget *budget)
{
    size_t missing = mesh->normals ? 0 : mesh->vertex_count;
    for (size_t v = 0; mesh->normals && v < mesh->vertex_count; v++)
        missing += ao_mesh_normal_is_missing(mesh->normals[v]);
    if (missing == 0 || mesh->triangle_count == 0)
        return true;
    if (crease <= 0.0) {   /* flat: a zero normal, which shading replaces by the triangle's own */
        if (!mesh->normals && !(mesh->normals = calloc(mesh->vertex_count, sizeof *mesh->normals)))
            return out_of_memory(path);
        for (size_t v = 0; v < mesh->vertex_count; v++)
            if (ao_mesh_normal_is_missing(mesh->normals[v]))
                mesh->normals[v] = ao_vec3_make(0.0f, 0.0f, 0.0f);
        return true;
    }
    /* Every vertex's smooth normal first, what a vertex keeps unless it splits, and below 180
     * degrees the vertices marked whose sides must be found. */
    const double degree = 3.14159265358979323846 / 180.0;
    size_t n = mesh->vertex_count;
    struct ao_vec3 *smooth = malloc(n * sizeof *smooth);
    struct cone cone = {.given = mesh->normals, .cos_half = cos(crease * degree / 2.0)};
    bool creased = crease < 180.0;
    if (creased) {
        cone.at = malloc(n * sizeof *cone.at);
        cone.marked = malloc(n);
        if (cone.at)
            ao_mesh_advise_huge(cone.at, n * sizeof *cone.at);
    }
    bool ok = smooth && (!creased || (cone.at && cone.marked));
    size_t marked = 0;
    if (ok) {
        ao_mesh_advise_huge(smooth, n * sizeof *smooth);
        marked = angle_weighted_normals(mesh, smooth, 0, creased ? &cone : NULL);
        if (mesh->normals) {
            for (size_t v = 0; v < n; v++)
                if (ao_mesh_normal_is_missing(mesh->normals[v]))
                    mesh->normals[v] = smooth[v];
            free(smooth);
        } else {
            mesh->normals = smooth;
        }
        smooth = NULL;
    }
    free(smooth);
    struct crease cr = {.marked = cone.marked, .at = cone.at, .count = marked, .cos_crease = cos(crease * degree)};
    bool split = ok && (marked == 0 || split_creases(mesh, path, &cr, budget));   /* reports its failures */
    free(cone.at);
    free(cone.marked);
    return split || (!ok && out_of_memory(path));
}

bool ao_mesh_compute_normals_on(struct ao_mesh *mesh, int threads)
{
    if (compute_normals(mesh, threads))
        return true;
    ao_text_report("out of memory computing mesh normals");
    return false;
}

bool ao_mesh_compute_normals(struct ao_mesh *mesh)
{
    return ao_mesh_compute_normals_on(mesh, 0);
}
