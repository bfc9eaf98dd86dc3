/* The mesh interface: dispatch by extension to the loaders of src/load/ (one file per format),
 * and what every format shares once it has triangles: degenerate triangles dropped and
 * angle-weighted vertex normals computed where the file gives none. */
#include "mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "file.h"
#include "load/load.h"

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
        out[i] = ao_load_unit(out[i].x, out[i].y, out[i].z);
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
    ao_file_report("out of memory computing mesh normals");
    return false;
}

/* Gives the vertices flagged in lacking (which the file gave no normal) computed normals. */
static bool fill_lacking_normals(struct ao_mesh *mesh, const bool *lacking, const char *path)
{
    struct ao_vec3 *computed = malloc(mesh->vertex_count * sizeof *computed);
    if (!computed)
        return ao_load_out_of_memory(path);
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
bool ao_load_finish(struct ao_mesh *mesh, const char *path, const bool *lacking)
{
    drop_degenerate(mesh);
    if (mesh->triangle_count == 0) {
        ao_load_report(path, 0, "no triangles (%zu degenerate ones skipped)",
                       mesh->degenerate_count);
        return false;
    }
    if (!mesh->normals)
        return compute_all_normals(mesh) || ao_load_out_of_memory(path);
    return lacking ? fill_lacking_normals(mesh, lacking, path) : true;
}

/* ------------------------------------------------------------------ entry points */

/* The formats by extension (any case). */
static const struct {
    const char *extension;
    ao_load_format *load;
} formats[] = {
    {".obj", ao_load_obj},
    {".ply", ao_load_ply},
    {".stl", ao_load_stl},
    {".gltf", ao_load_gltf},
    {".glb", ao_load_gltf},
};

/* The loader for path's extension, or NULL. */
static ao_load_format *loader_for(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (!dot || strchr(dot, '/'))
        return NULL;
    for (size_t i = 0; i < sizeof formats / sizeof formats[0]; i++)
        if (strcasecmp(dot, formats[i].extension) == 0)
            return formats[i].load;
    return NULL;
}

bool ao_mesh_is_mesh_path(const char *path)
{
    return loader_for(path) != NULL;
}

bool ao_mesh_load(struct ao_mesh *mesh, const char *path)
{
    struct ao_budget budget = {AO_BUDGET_DEFAULT, 0};
    return ao_mesh_load_budget(mesh, path, &budget);
}

bool ao_mesh_load_budget(struct ao_mesh *mesh, const char *path, struct ao_budget *budget)
{
    memset(mesh, 0, sizeof *mesh);
    ao_load_format *load = loader_for(path);
    char *text;
    size_t size;
    if (!load) {
        ao_load_report(path, 0, "unknown mesh format; expected .obj, .ply, .stl, .gltf or .glb");
        return false;
    }
    if (!ao_file_read_budget(path, budget, &text, &size))
        return false;
    bool ok = load(mesh, path, text, size, budget);
    free(text);
    ao_budget_give(budget, (uint64_t)size + 1);
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
