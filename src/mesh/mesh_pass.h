/* Private to the mesh module's files (mesh.c, mesh_normals.c, mesh_creases.c): a pass over a mesh
 * on a team of threads, and what the normals pass and the crease passes share. */
#ifndef AO_MESH_PASS_H
#define AO_MESH_PASS_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "pool.h"

struct crease;

/* A vertex position in double precision, for exact-enough normals of float positions. */
static inline struct ao_dvec3 ao_mesh_position(const struct ao_mesh *mesh, uint32_t vertex)
{
    return ao_dvec3_of(mesh->positions[vertex]);
}

/* Twice the area vector of triangle t, (p1 - p0) x (p2 - p0), exact for float positions up
 * to one rounding; zero exactly when the triangle is degenerate. */
static inline struct ao_dvec3 ao_mesh_area_vector(const struct ao_mesh *mesh, size_t t)
{
    const uint32_t *v = mesh->indices + 3 * t;
    struct ao_dvec3 p0 = ao_mesh_position(mesh, v[0]);
    return ao_dvec3_cross(ao_dvec3_sub(ao_mesh_position(mesh, v[1]), p0),
                          ao_dvec3_sub(ao_mesh_position(mesh, v[2]), p0));
}

/* The start of part k of n in [0, count). */
static inline size_t ao_mesh_part_start(size_t count, int k, int n)
{
    return count / (size_t)n * (size_t)k + count % (size_t)n * (size_t)k / (size_t)n;
}

/* The most threads a mesh pass uses. */
enum { AO_MESH_PASS_THREADS = 64 };

/* A pass over a mesh on a team of threads: what each part needs and gives back. */
struct mesh_pass {
    const struct ao_mesh *mesh;
    struct ao_vec3 *out;                /* normals: every vertex's */
    int threads;
    size_t counts[AO_MESH_PASS_THREADS];   /* what each part counted: degenerate triangles, marked vertices */
    struct cone *cone;                  /* the crease's check, made by the normals pass when asked */
    struct crease *crease;              /* the crease passes' arrays */
};

/* What a normals pass gathers at a vertex for the crease angle, in 16 bytes (allocated zero): the
 * sum of its corners' angles (W); 4 less the least of them (0 until a corner comes: 4 > pi, so
 * that the least is a maximum, kept without a branch); and the sum of a hash of each corner's next
 * neighbour less one of its previous neighbour. */
struct cone_vertex {
    float angle_sum, four_less_narrowest;
    uint64_t link;
};

/* The check a normals pass makes for the crease angle, when asked: per vertex what it gathers, and
 * whether the vertex's sides must be found edge by edge (marked). */
struct cone {
    const struct ao_vec3 *given;    /* NULL, or the mesh's normals: a vertex given one is not marked */
    double cos_half;                /* cos(crease / 2) */
    struct cone_vertex *at;         /* vertex_count, filled by the pass */
    unsigned char *marked;          /* vertex_count: 1 where the vertex's sides must be found */
};

/* atan2(y, x) for y > 0 (the interior angle of a corner whose edges a, b have |a x b| = y and
 * a . b = x), within 1e-9 of it and at a few times its speed: reduced to atan t, t in [0, 1]
 * (atan t = pi/2 - atan(1/t); atan(-t) = pi - ...), then to |t| <= tan(pi/12) by
 * atan t = pi/6 + atan((sqrt(3) t - 1) / (t + sqrt(3))), where atan's series to t^13 leaves
 * at most tan(pi/12)^15 / 15 < 3e-10. */
static inline double ao_mesh_corner_angle(double y, double x)
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

/* What the normals take from a triangle of corners v: its area vector n (ao_mesh_area_vector's, as it
 * computes it), twice its area, and at each corner c the dot product of the corner's two edges. */
struct triangle_terms {
    struct ao_dvec3 n;
    double twice_area, scale, dots[3];   /* scale: 1 / twice_area */
};

/* The terms of the triangle of corners v; false when it is degenerate (no normal to add). */
static inline bool ao_mesh_triangle_terms(const struct ao_mesh *mesh, const uint32_t *v, struct triangle_terms *out)
{
    struct ao_dvec3 p[3] = {ao_mesh_position(mesh, v[0]), ao_mesh_position(mesh, v[1]), ao_mesh_position(mesh, v[2])};
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
static inline struct ao_vec3 ao_mesh_corner_share(const struct triangle_terms *t, int c, double *angle)
{
    *angle = ao_mesh_corner_angle(t->twice_area, t->dots[c]);
    double weight = *angle * t->scale;
    return ao_vec3_make((float)(t->n.x * weight), (float)(t->n.y * weight), (float)(t->n.z * weight));
}

/* Reports an allocation failure as "path: out of memory"; returns false for the caller to pass on. */
bool ao_mesh_out_of_memory(const char *path);

/* Runs job(pass, k) for every part k in [0, pass->threads) on that many threads (when it is 0 or
 * less: one per core, and one per 65536 triangles at most), the caller being one of them; on one
 * thread, part after part, when threads cannot be started (the parts' results do not depend on
 * which thread runs them). */
void ao_mesh_run_parts(ao_pool_job *job, struct mesh_pass *pass);

/* Writes the angle-weighted normals of all mesh->vertex_count vertices into out, on so many
 * threads (0: ao_mesh_run_parts's choice), with cone's check when it is not NULL; returns how many
 * vertices that marks (mesh_normals.c). */
size_t ao_mesh_angle_weighted_normals(const struct ao_mesh *mesh, struct ao_vec3 *out, int threads, struct cone *cone);

/* Splits the vertices that the cone marked (marked of them) along the edges sharper than the
 * crease (their triangles' normals cos_crease or farther apart), as mesh_creases.c says. False
 * (reported) when memory, 32-bit corner numbers or the budget run out. */
bool ao_mesh_split_creases(struct ao_mesh *mesh, const char *path, const struct cone *cone, size_t marked,
                           double cos_crease, const struct ao_budget *budget);

#endif
