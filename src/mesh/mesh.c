/* Meshes (see mesh.h): placement, freeing, unit and missing normals, zero-area triangles dropped,
 * and the team of threads that the passes over a big mesh run on (mesh_pass.h), with results that
 * do not depend on the number of threads. The normals a file does not give are made in
 * mesh_normals.c, the vertices on edges sharper than the crease angle split in mesh_creases.c. */
/* Linux's madvise and MADV_HUGEPAGE, which POSIX lacks, for ao_mesh_advise_huge alone. */
#define _DEFAULT_SOURCE
#include "mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "mesh_pass.h"
#include "pool.h"
#include "text.h"

/* ------------------------------------------------------------------ the mesh */

bool ao_mesh_out_of_memory(const char *path)
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

/* The fewest triangles worth a second thread in a mesh pass. */
enum { TRIANGLES_PER_THREAD = 1 << 16 };

void ao_mesh_run_parts(ao_pool_job *job, struct mesh_pass *pass)
{
    long online = sysconf(_SC_NPROCESSORS_ONLN);
    size_t wanted = pass->mesh->triangle_count / TRIANGLES_PER_THREAD + 1;
    if (pass->threads <= 0)
        pass->threads = (int)(online < 1 ? 1 : (size_t)online < wanted ? (size_t)online : wanted);
    pass->threads = pass->threads < AO_MESH_PASS_THREADS ? pass->threads : AO_MESH_PASS_THREADS;
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
    size_t end = ao_mesh_part_start(pass->mesh->triangle_count, k + 1, pass->threads);
    pass->counts[k] = 0;
    for (size_t t = ao_mesh_part_start(pass->mesh->triangle_count, k, pass->threads); t < end; t++) {
        struct ao_dvec3 n = ao_mesh_area_vector(pass->mesh, t);
        pass->counts[k] += ao_dvec3_dot(n, n) == 0.0;
    }
}

/* Found in parallel, then, when there are any, removed in one pass. */
void ao_mesh_drop_degenerate(struct ao_mesh *mesh)
{
    struct mesh_pass pass = {.mesh = mesh};
    size_t found = 0, kept = 0;
    ao_mesh_run_parts(count_degenerate, &pass);
    for (int k = 0; k < pass.threads; k++)
        found += pass.counts[k];
    for (size_t t = 0; found && t < mesh->triangle_count; t++) {
        struct ao_dvec3 n = ao_mesh_area_vector(mesh, t);
        if (ao_dvec3_dot(n, n) == 0.0)
            continue;
        if (kept != t)
            memcpy(mesh->indices + 3 * kept, mesh->indices + 3 * t, 3 * sizeof *mesh->indices);
        kept++;
    }
    mesh->degenerate_count += found;
    mesh->triangle_count -= found;
}
