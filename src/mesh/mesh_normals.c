/* Angle-weighted vertex normals (see mesh.h), on a team of threads (mesh_pass.h) with results that
 * do not depend on their number; with a crease angle, the vertices whose corners do not all lie
 * within its cone are marked for mesh_creases.c. */
#include "mesh.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_pass.h"
#include "text.h"

/* A 64-bit hash of a vertex number (a multiply, shift and multiply, as splitmix64's finalizer
 * mixes). */
static inline uint64_t vertex_hash(uint32_t v)
{
    uint64_t z = ((uint64_t)v + 1) * 0x9E3779B97F4A7C15u;
    return (z ^ (z >> 29)) * 0xBF58476D1CE4E5B9u;
}

/* Adds a corner of angle `angle` at the vertex, whose next neighbour's hash less its previous
 * neighbour's is link, to what the cone gathers there. */
static inline void gather_corner(struct cone_vertex *at, double angle, uint64_t link)
{
    float gap = (float)(4.0 - angle);
    at->four_less_narrowest = gap > at->four_less_narrowest ? gap : at->four_less_narrowest;
    at->angle_sum += (float)angle;
    at->link += link;
}

/* Whether vertex i (gathered at `at`, the sum of its normals' shares `sum` as the pass added it in
 * float) must have its sides found edge by edge, or is one side for certain, as sides_of would
 * find it: where (1) every triangle's unit normal u_j lies within half the crease angle (alpha) of
 * one direction m, every two lie closer than the crease, and sides_of joins every two corners that
 * share an edge; (2) the corners' next and previous neighbours are the same vertices as often
 * (hash sums equal: a 2^-64 chance of being wrong otherwise), so that the corners chain into closed
 * fans, each corner's wedge ending on the edge where another's begins; and (3) the angles sum to
 * less than 4 pi cos alpha, the fans are one: seen along m, each wedge of angle a_j and normal
 * within alpha of m spans at most a_j / cos alpha (its unit sector's shadow, of area
 * cos beta a_j / 2, holds the sector of radius cos beta of the shadow's angle), and each closed fan
 * at least 2 pi.
 * (1) from the sums alone: for m the direction of S = sum a_j u_j and W = sum a_j,
 * sum a_j (1 - u_j . m) = W - |S|, each term at least 0, so 1 - u_j . m <= (W - |S|) / min a_j for
 * every j. The float figures are bounded: min a_j from below by 4 less the float kept for
 * 4 - min a_j, less 2^-21 (the rounding of floats near 4 is at most 2^-23), and marked where that
 * is under 2^-126 (a corner under about 5e-7 radians); with k corners, k + 1 <= K = 1.02 W / min a_j + 2 while
 * K 2^-24 <= 0.01 (else marked); W's float sum lies within a factor 1 + K 2^-23 of W, S's (its
 * shares and sums rounded) within 4 K 2^-24 W of S; 1e-6 covers the dot products' rounding in
 * sides_of. A vertex without triangles is one side; one given a normal is never split. */
static bool needs_sides(const struct cone *cone, size_t i, struct ao_vec3 sum)
{
    const struct cone_vertex *at = &cone->at[i];
    if (at->four_less_narrowest == 0.0f || (cone->given && !ao_mesh_normal_is_missing(cone->given[i])))
        return false;
    const double four_pi = 4.0 * 3.14159265358979323846, unit = 1.0 / 16777216.0;   /* 2^-24 */
    double narrowest = 4.0 - at->four_less_narrowest - 8.0 * unit;   /* at most min a_j */
    if (at->link != 0 || !(narrowest >= FLT_MIN))
        return true;
    double w = at->angle_sum, inverse = 1.0 / narrowest, k = 1.02 * w * inverse + 2.0;
    if (!(k * unit <= 0.01))
        return true;
    double w_up = w * (1.0 + 2.0 * k * unit);
    double length = sqrt((double)sum.x * sum.x + (double)sum.y * sum.y + (double)sum.z * sum.z);
    double least_dot = 1.0 - (w_up * (1.0 + 4.0 * k * unit) - length) * inverse;
    return !(least_dot > cone->cos_half + 1e-6 && w_up < four_pi * cone->cos_half);
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
    uint32_t first = (uint32_t)ao_mesh_part_start(mesh->vertex_count, k, pass->threads);
    uint32_t count = (uint32_t)ao_mesh_part_start(mesh->vertex_count, k + 1, pass->threads) - first;
    memset(out + first, 0, count * sizeof *out);
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *v = mesh->indices + 3 * t;
        bool mine[3] = {v[0] - first < count, v[1] - first < count, v[2] - first < count};
        struct triangle_terms terms;
        if (!(mine[0] | mine[1] | mine[2]) || !ao_mesh_triangle_terms(mesh, v, &terms))
            continue;
        uint64_t h[3] = {0, 0, 0};
        if (cone)
            h[0] = vertex_hash(v[0]), h[1] = vertex_hash(v[1]), h[2] = vertex_hash(v[2]);
        for (int c = 0; c < 3; c++) {
            if (!mine[c])
                continue;
            double angle;
            out[v[c]] = ao_vec3_add(out[v[c]], ao_mesh_corner_share(&terms, c, &angle));
            if (cone)   /* the link: the next neighbour's hash less the previous one's */
                gather_corner(&cone->at[v[c]], angle, h[(c + 1) % 3] - h[(c + 2) % 3]);
        }
    }
    size_t marked = 0;
    for (uint32_t i = first; i < first + count; i++) {
        if (cone)
            marked += cone->marked[i] = needs_sides(cone, i, out[i]);
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

size_t ao_mesh_angle_weighted_normals(const struct ao_mesh *mesh, struct ao_vec3 *out, int threads, struct cone *cone)
{
    struct mesh_pass pass = {.mesh = mesh, .out = out, .threads = threads, .cone = cone};
    ao_mesh_run_parts(normals_part, &pass);
    size_t marked = 0;
    for (int k = 0; k < pass.threads; k++)
        marked += pass.counts[k];
    return marked;
}

/* Angle-weighted normals of every vertex into mesh->normals (allocated when NULL), on so many
 * threads (0: ao_mesh_run_parts's choice); false when memory runs out (not reported). */
static bool compute_normals(struct ao_mesh *mesh, int threads)
{
    if (mesh->vertex_count == 0)
        return true;
    if (!mesh->normals) {
        if (!(mesh->normals = malloc(mesh->vertex_count * sizeof *mesh->normals)))
            return false;
        ao_mesh_advise_huge(mesh->normals, mesh->vertex_count * sizeof *mesh->normals);
    }
    ao_mesh_angle_weighted_normals(mesh, mesh->normals, threads, NULL);
    return true;
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
