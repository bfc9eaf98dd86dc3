/* The mesh interface: dispatch by extension to the loaders of src/load/ (one file per format,
 * each given the file mapped), and what every format shares once it has triangles: degenerate
 * triangles dropped and angle-weighted vertex normals computed where the file gives none, both on
 * one thread per core for a big mesh. */
#include "mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "file.h"
#include "load/load.h"
#include "pool.h"

/* A point or direction in double precision, for exact-enough normals of float positions. */
struct dvec {
    double x, y, z;
};

/* ------------------------------------------------------------------ normals */

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

/* The most threads a mesh pass uses, and the fewest triangles worth a second one. */
enum { MAX_THREADS = 64, TRIANGLES_PER_THREAD = 1 << 16 };

/* A pass over a mesh on a team of threads: what each part needs and gives back. */
struct mesh_pass {
    const struct ao_mesh *mesh;
    struct ao_vec3 *out;                /* normals: every vertex's */
    int threads;
    size_t degenerate[MAX_THREADS];     /* degenerate triangles found by each part */
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

/* Counts the degenerate triangles of part k of the triangles. */
static void count_degenerate(void *user, int k)
{
    struct mesh_pass *pass = user;
    size_t end = part_start(pass->mesh->triangle_count, k + 1, pass->threads);
    pass->degenerate[k] = 0;
    for (size_t t = part_start(pass->mesh->triangle_count, k, pass->threads); t < end; t++) {
        struct dvec n = area_vector(pass->mesh, t);
        pass->degenerate[k] += ddot(n, n) == 0.0;
    }
}

/* Removes zero-area triangles (a repeated index included), counting them: found in parallel,
 * then, when there are any, removed in one pass. */
static void drop_degenerate(struct ao_mesh *mesh)
{
    struct mesh_pass pass = {.mesh = mesh};
    size_t found = 0, kept = 0;
    run_parts(count_degenerate, &pass);
    for (int k = 0; k < pass.threads; k++)
        found += pass.degenerate[k];
    for (size_t t = 0; found && t < mesh->triangle_count; t++) {
        struct dvec n = area_vector(mesh, t);
        if (ddot(n, n) == 0.0)
            continue;
        if (kept != t)
            memcpy(mesh->indices + 3 * kept, mesh->indices + 3 * t, 3 * sizeof *mesh->indices);
        kept++;
    }
    mesh->degenerate_count += found;
    mesh->triangle_count -= found;
}

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
        struct dvec p[3] = {position(mesh, v[0]), position(mesh, v[1]), position(mesh, v[2])};
        struct dvec edge[3] = {dsub(p[1], p[0]), dsub(p[2], p[1]), dsub(p[0], p[2])};
        struct dvec b = dsub(p[2], p[0]);
        struct dvec n = {edge[0].y * b.z - edge[0].z * b.y, edge[0].z * b.x - edge[0].x * b.z,
                         edge[0].x * b.y - edge[0].y * b.x};   /* area_vector's, as it computes it */
        double twice_area = sqrt(ddot(n, n));
        if (twice_area == 0.0)
            continue;
        /* Corner c's edges are edge[c] and -edge[c + 2]; |a x b| = twice the area at every corner,
         * so the angle comes stably from it and a . b. */
        double dots[3] = {ddot(edge[0], b), -ddot(edge[1], edge[0]), -ddot(edge[2], edge[1])};
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
        out[i] = ao_load_unit(out[i].x, out[i].y, out[i].z);
}

/* Writes the angle-weighted normals of all mesh->vertex_count vertices into out, on so many
 * threads (0: run_parts's choice). */
static void angle_weighted_normals(const struct ao_mesh *mesh, struct ao_vec3 *out, int threads)
{
    struct mesh_pass pass = {.mesh = mesh, .out = out, .threads = threads};
    run_parts(normals_part, &pass);
}

/* Allocates mesh->normals when missing and fills them all on so many threads (0: run_parts's
 * choice); false when memory runs out. */
static bool compute_all_normals(struct ao_mesh *mesh, int threads)
{
    if (mesh->vertex_count == 0)
        return true;
    if (!mesh->normals) {
        if (!(mesh->normals = malloc(mesh->vertex_count * sizeof *mesh->normals)))
            return false;
        ao_load_advise_huge(mesh->normals, mesh->vertex_count * sizeof *mesh->normals);
    }
    angle_weighted_normals(mesh, mesh->normals, threads);
    return true;
}

bool ao_mesh_compute_normals_on(struct ao_mesh *mesh, int threads)
{
    if (compute_all_normals(mesh, threads))
        return true;
    ao_file_report("out of memory computing mesh normals");
    return false;
}

bool ao_mesh_compute_normals(struct ao_mesh *mesh)
{
    return ao_mesh_compute_normals_on(mesh, 0);
}

/* Gives the vertices flagged in lacking (which the file gave no normal) computed normals. */
static bool fill_lacking_normals(struct ao_mesh *mesh, const bool *lacking, const char *path)
{
    struct ao_vec3 *computed = malloc(mesh->vertex_count * sizeof *computed);
    if (!computed)
        return ao_load_out_of_memory(path);
    ao_load_advise_huge(computed, mesh->vertex_count * sizeof *computed);
    angle_weighted_normals(mesh, computed, 0);
    for (size_t i = 0; i < mesh->vertex_count; i++)
        if (lacking[i])
            mesh->normals[i] = computed[i];
    free(computed);
    return true;
}

bool ao_load_finish_mesh(struct ao_mesh *mesh, const char *path, const bool *lacking)
{
    drop_degenerate(mesh);
    if (mesh->triangle_count == 0)
        return true;
    if (!mesh->normals)
        return compute_all_normals(mesh, 0) || ao_load_out_of_memory(path);
    return lacking ? fill_lacking_normals(mesh, lacking, path) : true;
}

/* Common end of the single-mesh loaders: drops degenerate triangles, refuses a mesh without
 * triangles and computes the normals the file did not give (all when mesh->normals is NULL, else
 * those flagged in lacking, which may be NULL). */
bool ao_load_finish(struct ao_mesh *mesh, const char *path, const bool *lacking)
{
    drop_degenerate(mesh);
    if (mesh->triangle_count == 0) {
        ao_load_report(path, 0, "no triangles (%zu degenerate ones skipped)",
                       mesh->degenerate_count);
        return false;
    }
    return ao_load_finish_mesh(mesh, path, lacking);
}

/* ------------------------------------------------------------------ entry points */

/* The formats by extension (any case): a loader of one mesh, or of a model (several meshes placed). */
static const struct {
    const char *extension;
    ao_load_format *load;
    ao_load_model_format *load_model;
} formats[] = {
    {".obj", ao_load_obj, NULL},
    {".ply", ao_load_ply, NULL},
    {".stl", ao_load_stl, NULL},
    {".gltf", NULL, ao_load_gltf},
    {".glb", NULL, ao_load_gltf},
};

/* The format of path's extension, or -1. */
static int format_of(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (!dot || strchr(dot, '/'))
        return -1;
    for (size_t i = 0; i < sizeof formats / sizeof formats[0]; i++)
        if (strcasecmp(dot, formats[i].extension) == 0)
            return (int)i;
    return -1;
}

bool ao_mesh_is_mesh_path(const char *path)
{
    return format_of(path) >= 0;
}

bool ao_mesh_load(struct ao_mesh *mesh, const char *path)
{
    struct ao_budget budget = {.limit = AO_BUDGET_DEFAULT};
    return ao_mesh_load_budget(mesh, path, &budget);
}

/* One mesh placed once by the identity: what OBJ, PLY and STL files hold, as a model. */
static bool load_single(ao_load_format *load, struct ao_model *model, const char *path, const char *text,
                        size_t size, struct ao_budget *budget)
{
    model->meshes = calloc(1, sizeof *model->meshes);
    model->placements = calloc(1, sizeof *model->placements);
    if (!model->meshes || !model->placements)
        return ao_load_out_of_memory(path);
    model->mesh_count = model->placement_count = 1;
    model->placements[0].to_model = ao_affine_identity();
    if (!load(&model->meshes[0], path, text, size, budget))
        return false;
    model->degenerate_count = model->meshes[0].degenerate_count;
    snprintf(model->note, sizeof model->note, "%s", model->meshes[0].note);
    return true;
}

bool ao_model_load_budget(struct ao_model *model, const char *path, struct ao_budget *budget)
{
    memset(model, 0, sizeof *model);
    int format = format_of(path);
    const char *text;
    size_t size;
    bool mapped;
    if (format < 0) {
        ao_load_report(path, 0, "unknown mesh format; expected .obj, .ply, .stl, .gltf or .glb");
        return false;
    }
    if (!ao_file_map_budget(path, budget, &text, &size, &mapped))
        return false;
    bool ok = formats[format].load_model ? formats[format].load_model(model, path, text, size, budget)
                                         : load_single(formats[format].load, model, path, text, size, budget);
    ao_file_unmap(text, size, mapped);
    ao_budget_give(budget, (uint64_t)size + 1);
    if (!ok)
        ao_model_finish(model);
    return ok;
}

void ao_model_finish(struct ao_model *model)
{
    for (size_t i = 0; model->meshes && i < model->mesh_count; i++)
        ao_mesh_finish(&model->meshes[i]);
    free(model->meshes);
    free(model->placements);
    memset(model, 0, sizeof *model);
}

size_t ao_mesh_place(struct ao_mesh *dst, size_t vertex_base, size_t triangle_base, const struct ao_mesh *src,
                     const struct ao_affine *map)
{
    double n[9], q[3];
    bool mirror = ao_affine_normals(map, n) < 0.0;
    size_t bad = src->vertex_count;
    for (size_t v = 0; v < src->vertex_count; v++) {
        struct ao_vec3 a = src->positions[v], b = src->normals[v];
        ao_affine_point(map, a.x, a.y, a.z, q);
        struct ao_vec3 *o = &dst->positions[vertex_base + v];
        *o = ao_vec3_make((float)q[0], (float)q[1], (float)q[2]);
        if (bad == src->vertex_count && !ao_vec3_is_finite(*o))
            bad = v;
        dst->normals[vertex_base + v] = ao_load_unit(n[0] * b.x + n[3] * b.y + n[6] * b.z,
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

/* Every placement of the model applied, into one mesh (ao_mesh_place). False (reported) when
 * memory or 2^32 vertices run out, or a position leaves float's range. */
static bool flatten(const struct ao_model *model, struct ao_mesh *out, const char *path,
                    const struct ao_budget *budget)
{
    size_t vertices = 0, triangles = 0;
    for (size_t i = 0; i < model->placement_count; i++) {
        const struct ao_mesh *m = &model->meshes[model->placements[i].mesh];
        vertices += m->vertex_count;
        triangles += m->triangle_count;
        if (vertices >= AO_LOAD_NO_INDEX || triangles > SIZE_MAX / 12) {
            ao_load_report(path, 0, "more than %u vertices once its placements are applied", AO_LOAD_NO_INDEX - 1);
            return false;
        }
    }
    if (!ao_load_fits(budget, triangles, vertices, path, 0))
        return false;
    out->positions = malloc((vertices ? vertices : 1) * sizeof *out->positions);
    out->normals = malloc((vertices ? vertices : 1) * sizeof *out->normals);
    out->indices = malloc((triangles ? 3 * triangles : 1) * sizeof *out->indices);
    if (!out->positions || !out->normals || !out->indices)
        return ao_load_out_of_memory(path);
    for (size_t i = 0; i < model->placement_count; i++) {
        const struct ao_placement *p = &model->placements[i];
        const struct ao_mesh *m = &model->meshes[p->mesh];
        size_t bad = ao_mesh_place(out, out->vertex_count, out->triangle_count, m, &p->to_model);
        if (bad < m->vertex_count) {
            ao_load_report(path, 0, "mesh %zu: vertex %zu is not a finite float once placed", p->mesh, bad);
            return false;
        }
        out->vertex_count += m->vertex_count;
        out->triangle_count += m->triangle_count;
    }
    return true;
}

bool ao_mesh_load_budget(struct ao_mesh *mesh, const char *path, struct ao_budget *budget)
{
    memset(mesh, 0, sizeof *mesh);
    struct ao_model model;
    if (!ao_model_load_budget(&model, path, budget))
        return false;
    bool ok;
    if (model.mesh_count == 1 && model.placement_count == 1 && ao_affine_is_identity(&model.placements[0].to_model)) {
        *mesh = model.meshes[0];   /* taken whole */
        model.meshes[0] = (struct ao_mesh){0};
        ok = true;
    } else {
        ok = flatten(&model, mesh, path, budget);
    }
    mesh->degenerate_count = model.degenerate_count;
    mesh->point_primitives = model.point_primitives;
    mesh->line_primitives = model.line_primitives;
    snprintf(mesh->note, sizeof mesh->note, "%s", model.note);
    ao_model_finish(&model);
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
