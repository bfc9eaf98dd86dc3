/* A mesh's missing normals made (see mesh.h), as its format means them: flat (glTF), or
 * angle-weighted (mesh_normals.c) across the edges flatter than a crease angle (OBJ, PLY, STL), the
 * vertices on sharper edges then split (mesh_creases.c) so that each side keeps its own normal. */
#include "mesh.h"

#include <math.h>
#include <stdlib.h>

#include "mesh_pass.h"

bool ao_mesh_complete_normals(struct ao_mesh *mesh, const char *path, double crease, const struct ao_budget *budget)
{
    size_t missing = mesh->normals ? 0 : mesh->vertex_count;
    for (size_t v = 0; mesh->normals && v < mesh->vertex_count; v++)
        missing += ao_mesh_normal_is_missing(mesh->normals[v]);
    if (missing == 0 || mesh->triangle_count == 0)
        return true;
    if (crease <= 0.0) {   /* flat: a zero normal, which shading replaces by the triangle's own */
        if (!mesh->normals && !(mesh->normals = calloc(mesh->vertex_count, sizeof *mesh->normals)))
            return ao_mesh_out_of_memory(path);
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
        cone.at = calloc(n, sizeof *cone.at);
        cone.marked = malloc(n);
        if (cone.at && cone.marked) {
            ao_mesh_advise_huge(cone.at, n * sizeof *cone.at);
            ao_mesh_advise_huge(cone.marked, n);
        }
    }
    bool ok = smooth && (!creased || (cone.at && cone.marked));
    size_t marked = 0;
    if (ok) {
        ao_mesh_advise_huge(smooth, n * sizeof *smooth);
        marked = ao_mesh_angle_weighted_normals(mesh, smooth, 0, creased ? &cone : NULL);
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
    bool split = ok && (marked == 0 || ao_mesh_split_creases(mesh, path, &cone, marked, cos(crease * degree),
                                                            budget));   /* reports its failures */
    free(cone.at);
    free(cone.marked);
    return split || (!ok && ao_mesh_out_of_memory(path));
}
