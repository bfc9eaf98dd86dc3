/* The mesh interface: dispatch by extension to the loaders of src/load/ (one file per format,
 * each given the file mapped), the normals the file lacks made as its format means them
 * (src/load/finish.c), and a model's placements applied for those who want one mesh. */
#include "mesh.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "file.h"
#include "text.h"
#include "load/loader.h"

bool ao_mesh_compute_normals_on(struct ao_mesh *mesh, int threads)
{
    if (ao_load_normals(mesh, threads))
        return true;
    ao_text_report("out of memory computing mesh normals");
    return false;
}

bool ao_mesh_compute_normals(struct ao_mesh *mesh)
{
    return ao_mesh_compute_normals_on(mesh, 0);
}

/* ------------------------------------------------------------------ entry points */

/* The formats by extension (any case): a loader of one mesh, or of a model (several meshes placed),
 * and whether the normals a file lacks are flat (glTF 2.0: "When normals are not specified, client
 * implementations MUST calculate flat normals") or smooth up to the crease angle. */
static const struct {
    const char *extension;
    ao_load_format *load;
    ao_load_model_format *load_model;
    bool flat;
} formats[] = {
    {".obj", ao_load_obj, NULL, false},
    {".ply", ao_load_ply, NULL, false},
    {".stl", ao_load_stl, NULL, false},
    {".gltf", NULL, ao_load_gltf, true},
    {".glb", NULL, ao_load_gltf, true},
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

/* Appends a printf-formatted note to model->note (ao_load_vnote). */
static void add_note(struct ao_model *model, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    ao_load_vnote(model->note, format, args);
    va_end(args);
}

/* Makes the normals each mesh of the model lacks, flat or up to the crease angle, and notes the
 * given normals that were zero or not finite. */
static bool complete_normals(struct ao_model *model, const char *path, bool flat, double crease,
                             const struct ao_budget *budget)
{
    size_t invalid = 0;
    for (size_t i = 0; i < model->mesh_count; i++) {
        if (!ao_load_complete_normals(&model->meshes[i], path, flat ? 0.0 : crease, budget))
            return false;
        invalid += model->meshes[i].invalid_normals;
    }
    model->invalid_normals = invalid;
    if (invalid)
        add_note(model, "%zu of its normals %s zero or not finite: made as for a file without normals (%s)",
                 invalid, invalid == 1 ? "is" : "are", flat ? "flat" : "smooth up to the crease angle");
    return true;
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

bool ao_model_load_budget(struct ao_model *model, const char *path, struct ao_budget *budget, double crease)
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
    ok = ok && complete_normals(model, path, formats[format].flat, crease, budget);
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
    if (!ao_model_load_budget(&model, path, budget, AO_MESH_CREASE_DEFAULT))
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
    mesh->invalid_normals = model.invalid_normals;
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
