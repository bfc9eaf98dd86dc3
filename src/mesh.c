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
    size_t degenerate[MAX_THREADS];     /* degenerate triangles found by each part */
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
    pass->degenerate[k] = 0;
    for (size_t t = part_start(pass->mesh->triangle_count, k, pass->threads); t < end; t++) {
        struct ao_dvec3 n = area_vector(pass->mesh, t);
        pass->degenerate[k] += ao_dvec3_dot(n, n) == 0.0;
    }
}

/* Found in parallel, then, when there are any, removed in one pass. */
void ao_mesh_drop_degenerate(struct ao_mesh *mesh)
{
    struct mesh_pass pass = {.mesh = mesh};
    size_t found = 0, kept = 0;
    run_parts(count_degenerate, &pass);
    for (int k = 0; k < pass.threads; k++)
        found += pass.degenerate[k];
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
static double corner_angle(double y, double x)
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

/* Angle-weighted vertex normals (Thürmer and Wüthrich 1998) of part k of the vertices: each
 * triangle adds its unit normal times its interior angle at the vertex, so the result does not
 * depend on how a surface is split into triangles; the sum is then normalized. Every part reads
 * every triangle and adds only at its own vertices, in triangle order: each vertex's sum is the
 * same, bit for bit, whatever the number of parts. Vertices without a nondegenerate triangle get
 * the zero vector. */
static void normals_part(void *user, int k)
{
    const struct mesh_pass *pass = user;
    const struct ao_mesh *mesh = pass->mesh;
    struct ao_vec3 *out = pass->out;
    uint32_t first = (uint32_t)part_start(mesh->vertex_count, k, pass->threads);
    uint32_t count = (uint32_t)part_start(mesh->vertex_count, k + 1, pass->threads) - first;
    memset(out + first, 0, count * sizeof *out);
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *v = mesh->indices + 3 * t;
        bool mine[3] = {v[0] - first < count, v[1] - first < count, v[2] - first < count};
        if (!(mine[0] | mine[1] | mine[2]))
            continue;
        struct ao_dvec3 p[3] = {position(mesh, v[0]), position(mesh, v[1]), position(mesh, v[2])};
        struct ao_dvec3 edge[3] = {ao_dvec3_sub(p[1], p[0]), ao_dvec3_sub(p[2], p[1]), ao_dvec3_sub(p[0], p[2])};
        struct ao_dvec3 b = ao_dvec3_sub(p[2], p[0]);
        struct ao_dvec3 n = ao_dvec3_cross(edge[0], b);   /* area_vector's, as it computes it */
        double twice_area = sqrt(ao_dvec3_dot(n, n));
        if (twice_area == 0.0)
            continue;
        /* Corner c's edges are edge[c] and -edge[c + 2]; |a x b| = twice the area at every corner,
         * so the angle comes stably from it and a . b. */
        double dots[3] = {ao_dvec3_dot(edge[0], b), -ao_dvec3_dot(edge[1], edge[0]), -ao_dvec3_dot(edge[2], edge[1])};
        double scale = 1.0 / twice_area;
        for (int c = 0; c < 3; c++) {
            if (!mine[c])
                continue;
            double weight = corner_angle(twice_area, dots[c]) * scale;
            struct ao_vec3 add = ao_vec3_make((float)(n.x * weight), (float)(n.y * weight),
                                              (float)(n.z * weight));
            out[v[c]] = ao_vec3_add(out[v[c]], add);
        }
    }
    for (uint32_t i = first; i < first + count; i++)
        out[i] = ao_mesh_unit(out[i].x, out[i].y, out[i].z);
}

/* Writes the angle-weighted normals of all mesh->vertex_count vertices into out, on so many
 * threads (0: run_parts's choice). */
static void angle_weighted_normals(const struct ao_mesh *mesh, struct ao_vec3 *out, int threads)
{
    struct mesh_pass pass = {.mesh = mesh, .out = out, .threads = threads};
    run_parts(normals_part, &pass);
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
    angle_weighted_normals(mesh, mesh->normals, threads);
    return true;
}

/* Gives the vertices whose normal is missing the angle-weighted normals of their triangles. */
static bool fill_missing_normals(struct ao_mesh *mesh, const char *path)
{
    struct ao_vec3 *computed = malloc(mesh->vertex_count * sizeof *computed);
    if (!computed)
        return out_of_memory(path);
    ao_mesh_advise_huge(computed, mesh->vertex_count * sizeof *computed);
    angle_weighted_normals(mesh, computed, 0);
    for (size_t i = 0; i < mesh->vertex_count; i++)
        if (ao_mesh_normal_is_missing(mesh->normals[i]))
            mesh->normals[i] = computed[i];
    free(computed);
    return true;
}

/* ------------------------------------------------------------------ creases */

/* The arrays of the crease passes: each vertex's corners (a corner c is triangle c / 3's
 * (c % 3)th), listed vertex by vertex; and for each listed corner, its side of the vertex (0 for
 * the side of the vertex's first corner; 1, 2, ... for the others, in the order of their first
 * corners); each vertex's extra sides, then the first new vertex of each. */
struct crease {
    const uint32_t *start;    /* vertex_count + 1: where each vertex's corners begin in corners */
    const uint32_t *corners;  /* 3 * triangle_count */
    uint32_t *side;           /* 3 * triangle_count, by listing */
    uint32_t *extra;          /* vertex_count: sides - 1, then the first new vertex of the sides */
    double cos_crease;        /* two triangles of normals n, m are smoothed together when n.m > this */
    bool failed;              /* a part ran out of memory */
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

/* The first crease pass over part k of the vertices: the sides of each vertex whose normal is
 * missing (others keep one side). */
static void sides_part(void *user, int k)
{
    struct mesh_pass *pass = user;
    struct crease *cr = pass->crease;
    const struct ao_mesh *mesh = pass->mesh;
    size_t first = part_start(mesh->vertex_count, k, pass->threads);
    size_t end = part_start(mesh->vertex_count, k + 1, pass->threads);
    uint32_t most = 0;
    for (size_t v = first; v < end; v++)
        most = cr->start[v + 1] - cr->start[v] > most ? cr->start[v + 1] - cr->start[v] : most;
    uint32_t *parent = malloc((most ? most : 1) * sizeof *parent);
    uint64_t *keys = malloc((most ? 2 * (size_t)most : 1) * sizeof *keys);
    struct ao_dvec3 *normals = malloc((most ? most : 1) * sizeof *normals);
    if (!parent || !keys || !normals) {
        cr->failed = true;
    } else {
        for (size_t v = first; v < end; v++) {
            uint32_t begin = cr->start[v], count = cr->start[v + 1] - begin;
            bool missing = !mesh->normals || ao_mesh_normal_is_missing(mesh->normals[v]);
            if (!missing || count == 0) {
                memset(cr->side + begin, 0, count * sizeof *cr->side);
                cr->extra[v] = 0;
                continue;
            }
            cr->extra[v] = sides_of(mesh, cr->corners + begin, count, cr->cos_crease, cr->side + begin,
                                    parent, keys, normals) - 1;
        }
    }
    free(parent);
    free(keys);
    free(normals);
}

/* The second crease pass over part k of the vertices: each corner on a side but the first is moved
 * to that side's new vertex. */
static void move_part(void *user, int k)
{
    struct mesh_pass *pass = user;
    struct crease *cr = pass->crease;
    const struct ao_mesh *mesh = pass->mesh;
    size_t end = part_start(mesh->vertex_count, k + 1, pass->threads);
    for (size_t v = part_start(mesh->vertex_count, k, pass->threads); v < end; v++)
        for (uint32_t i = cr->start[v]; i < cr->start[v + 1]; i++)
            if (cr->side[i])
                mesh->indices[cr->corners[i]] = cr->extra[v] + cr->side[i] - 1;
}

/* Lists each vertex's corners (counting sort of the corners by vertex, in corner order) into
 * *start and *corners (malloc'd); false when memory runs out. */
static bool list_corners(const struct ao_mesh *mesh, uint32_t **start, uint32_t **corners)
{
    size_t n = 3 * mesh->triangle_count;
    *start = calloc(mesh->vertex_count + 1, sizeof **start);
    *corners = malloc((n ? n : 1) * sizeof **corners);
    if (!*start || !*corners)
        return false;
    ao_mesh_advise_huge(*corners, n * sizeof **corners);
    for (size_t c = 0; c < n; c++)
        (*start)[mesh->indices[c] + 1]++;
    for (size_t v = 0; v < mesh->vertex_count; v++)
        (*start)[v + 1] += (*start)[v];
    for (size_t c = 0; c < n; c++)   /* start[v] walks through v's slots; shifted back below */
        (*corners)[(*start)[mesh->indices[c]]++] = (uint32_t)c;
    for (size_t v = mesh->vertex_count; v > 0; v--)
        (*start)[v] = (*start)[v - 1];
    (*start)[0] = 0;
    return true;
}

/* Grows the vertex arrays to count vertices and fills the new ones (from mesh->vertex_count on,
 * numbered in cr->extra): each a copy of the vertex it splits from, its normal missing. */
static bool add_split_vertices(struct ao_mesh *mesh, const struct crease *cr, size_t count)
{
    struct ao_vec3 *positions = realloc(mesh->positions, count * sizeof *positions);
    if (!positions)
        return false;
    mesh->positions = positions;
    if (mesh->normals) {
        struct ao_vec3 *normals = realloc(mesh->normals, count * sizeof *normals);
        if (!normals)
            return false;
        mesh->normals = normals;
    }
    for (size_t v = 0; v < mesh->vertex_count; v++)
        for (uint32_t n = cr->extra[v]; n < cr->extra[v + 1]; n++) {
            positions[n] = positions[v];
            if (mesh->normals)
                mesh->normals[n] = ao_mesh_missing_normal();
        }
    return true;
}

/* Splits the vertices whose normal is missing along the edges sharper than the crease (their
 * triangles' normals cos_crease or farther apart): each side of such a vertex but the first gets a
 * new vertex, a copy at the end of the arrays, its normal missing. The mesh's other vertices keep
 * their numbers, so that a mesh without such an edge is left as it was. False (reported) when
 * memory, 32-bit corner numbers or the budget run out. */
static bool split_creases(struct ao_mesh *mesh, const char *path, double cos_crease, const struct ao_budget *budget)
{
    if (3 * (uint64_t)mesh->triangle_count > UINT32_MAX) {
        ao_text_report("%s: %zu triangles are too many for a crease angle (at most %u); --crease-angle 0 "
                       "or 180 takes any number", path, mesh->triangle_count, UINT32_MAX / 3);
        return false;
    }
    uint32_t *start = NULL, *corners = NULL;
    struct crease cr = {.cos_crease = cos_crease};
    bool ok = list_corners(mesh, &start, &corners);
    cr.start = start;
    cr.corners = corners;
    cr.side = ok ? malloc((3 * mesh->triangle_count + 1) * sizeof *cr.side) : NULL;
    cr.extra = ok ? malloc((mesh->vertex_count + 1) * sizeof *cr.extra) : NULL;
    ok = ok && cr.side && cr.extra;
    struct mesh_pass pass = {.mesh = mesh, .crease = &cr};
    if (ok) {
        ao_mesh_advise_huge(cr.side, 3 * mesh->triangle_count * sizeof *cr.side);
        run_parts(sides_part, &pass);
        ok = !cr.failed;
    }
    bool reported = false;
    uint64_t count = mesh->vertex_count;
    for (size_t v = 0; ok && v <= mesh->vertex_count; v++) {   /* the new vertices' numbers */
        uint32_t more = v < mesh->vertex_count ? cr.extra[v] : 0;
        cr.extra[v] = (uint32_t)count;
        if ((count += more) >= AO_MESH_INDEX_LIMIT) {
            ao_text_report("%s: more than %u vertices once split along its creases", path, AO_MESH_INDEX_LIMIT - 1);
            ok = false;
            reported = true;
        }
    }
    if (ok && count > mesh->vertex_count) {
        reported = !ao_mesh_fits(budget, mesh->triangle_count, count, path, 0);
        ok = !reported && add_split_vertices(mesh, &cr, (size_t)count);
        if (ok) {
            pass.threads = 0;
            run_parts(move_part, &pass);
            mesh->vertex_count = (size_t)count;
        }
    }
    free(start);
    free(corners);
    free(cr.side);
    free(cr.extra);
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
    if (crease < 180.0 && !split_creases(mesh, path, cos(crease * (3.14159265358979323846 / 180.0)), budget))
        return false;
    if (!mesh->normals)
        return compute_normals(mesh, 0) || out_of_memory(path);
    return fill_missing_normals(mesh, path);
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
