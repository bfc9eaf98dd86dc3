/* Loading a mesh file (see load.h): the format table, dispatch by extension to the loaders of this
 * folder (one file per format, each given the file mapped), the common end of a load (degenerate
 * triangles dropped, the normals a file lacks made as its format means them: mesh.c), and a
 * model's placements applied for those who want one mesh. */
#include "load.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <sys/stat.h>

#include "file.h"
#include "loader.h"
#include "text.h"

/* ------------------------------------------------------------------ entry points */

/* The formats by extension (any case): a loader of one mesh, or of a model (several meshes placed),
 * whether the normals a file lacks are flat (glTF 2.0: "When normals are not specified, client
 * implementations MUST calculate flat normals") or smooth up to the crease angle, and the largest
 * file it can read (0: no limit; a .gltf is JSON, which json-c parses up to 2^31 - 1 bytes),
 * refused before it is read. */
static const struct {
    const char *extension;
    ao_load_format *load;
    ao_load_model_format *load_model;
    bool flat;
    uint64_t largest;
} formats[] = {
    {".obj", ao_load_obj, NULL, false, 0},
    {".ply", ao_load_ply, NULL, false, 0},
    {".stl", ao_load_stl, NULL, false, 0},
    {".gltf", NULL, ao_load_gltf, true, INT32_MAX},
    {".glb", NULL, ao_load_gltf, true, 0},
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

bool ao_load_is_mesh(const char *path)
{
    return format_of(path) >= 0;
}

void ao_load_extensions(char *out, size_t size)
{
    size_t n = sizeof formats / sizeof formats[0], used = 0;
    out[0] = '\0';
    for (size_t i = 0; i < n && used < size; i++)
        used += (size_t)snprintf(out + used, size - used, "%s%s", i == 0 ? "" : i + 1 < n ? ", " : " or ",
                                 formats[i].extension);
}

bool ao_load_finish(struct ao_mesh *mesh, const char *path)
{
    ao_mesh_drop_degenerate(mesh);
    if (mesh->triangle_count > 0)
        return true;
    ao_text_report_at(path, 0, "no triangles (%zu degenerate ones skipped)", mesh->degenerate_count);
    return false;
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
        if (!ao_mesh_complete_normals(&model->meshes[i], path, flat ? 0.0 : crease, budget))
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

bool ao_load_model(struct ao_model *model, const char *path, struct ao_budget *budget, double crease)
{
    memset(model, 0, sizeof *model);
    struct ao_budget defaults = {.limit = ao_budget_default()};
    budget = budget ? budget : &defaults;
    int format = format_of(path);
    const char *text;
    size_t size;
    bool mapped;
    if (format < 0) {
        char extensions[64];
        ao_load_extensions(extensions, sizeof extensions);
        ao_text_report_at(path, 0, "unknown mesh format; expected %s", extensions);
        return false;
    }
    struct stat st;
    if (formats[format].largest && stat(path, &st) == 0 && (uint64_t)st.st_size > formats[format].largest) {
        ao_text_report_at(path, 0, "%llu bytes of JSON, more than the %llu its parser reads", (unsigned long long)st.st_size,
                       (unsigned long long)formats[format].largest);
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
        if (vertices >= AO_MESH_INDEX_LIMIT || triangles > SIZE_MAX / 12) {
            ao_text_report_at(path, 0, "more than %u vertices once its placements are applied", AO_MESH_INDEX_LIMIT - 1);
            return false;
        }
    }
    if (!ao_mesh_fits(budget, triangles, vertices, path, 0))
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
            ao_text_report_at(path, 0, "mesh %zu: vertex %zu is not a finite float once placed", p->mesh, bad);
            return false;
        }
        out->vertex_count += m->vertex_count;
        out->triangle_count += m->triangle_count;
    }
    return true;
}

bool ao_load_mesh(struct ao_mesh *mesh, const char *path, struct ao_budget *budget)
{
    memset(mesh, 0, sizeof *mesh);
    struct ao_budget defaults = {.limit = ao_budget_default()};
    budget = budget ? budget : &defaults;
    struct ao_model model;
    if (!ao_load_model(&model, path, budget, AO_MESH_CREASE_DEFAULT))
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

/* As an OBJ file with normals makes its vertices (one per position and normal pair, in the order
 * the faces first name them), keeps the vertices the triangles use, in that order; false when
 * memory is short. */
static bool keep_used_vertices(struct ao_mesh *m)
{
    uint32_t *made = malloc((m->vertex_count + 1) * sizeof *made);
    struct ao_vec3 *positions = malloc((m->vertex_count + 1) * sizeof *positions);
    struct ao_vec3 *normals = malloc((m->vertex_count + 1) * sizeof *normals);
    if (!made || !positions || !normals) {
        free(made), free(positions), free(normals);
        return false;
    }
    memset(made, 0xff, (m->vertex_count + 1) * sizeof *made);
    uint32_t count = 0;
    for (size_t i = 0; i < 3 * m->triangle_count; i++) {
        uint32_t v = m->indices[i];
        if (made[v] == UINT32_MAX) {
            made[v] = count;
            positions[count] = m->positions[v];
            normals[count++] = m->normals[v];
        }
        m->indices[i] = made[v];
    }
    free(made), free(m->positions), free(m->normals);
    m->positions = positions, m->normals = normals, m->vertex_count = count;
    return true;
}

bool ao_load_model_arrays(struct ao_model *model, const char *name, const float *positions, size_t vertex_count,
                          const uint32_t *indices, size_t triangle_count, const float *normals,
                          struct ao_budget *budget, double crease)
{
    memset(model, 0, sizeof *model);
    struct ao_budget defaults = {.limit = ao_budget_default()};
    budget = budget ? budget : &defaults;
    if (vertex_count >= AO_MESH_INDEX_LIMIT || triangle_count > SIZE_MAX / 12) {
        ao_text_report_at(name, 0, "too many vertices for 32-bit indices");
        return false;
    }
    for (size_t i = 0; i < 3 * triangle_count; i++)
        if (indices[i] >= vertex_count) {
            ao_text_report_at(name, 0, "triangle %zu: vertex index %u out of range (%zu vertices)", i / 3, indices[i],
                           vertex_count);
            return false;
        }
    for (size_t i = 0; i < 3 * vertex_count; i++)
        if (!isfinite(positions[i])) {
            ao_text_report_at(name, 0, "vertex %zu: position not finite", i / 3);
            return false;
        }
    if (!ao_mesh_fits(budget, triangle_count, normals ? 2 * vertex_count : vertex_count, name, 0))
        return false;
    model->meshes = calloc(1, sizeof *model->meshes);
    model->placements = calloc(1, sizeof *model->placements);
    struct ao_mesh *m = model->meshes;
    bool ok = m && model->placements && (m->positions = malloc((vertex_count + 1) * sizeof *m->positions)) &&
              (m->indices = malloc((3 * triangle_count + 1) * sizeof *m->indices)) &&
              (!normals || (m->normals = malloc((vertex_count + 1) * sizeof *m->normals)));
    if (!ok) {
        ao_model_finish(model);
        return ao_load_out_of_memory(name);
    }
    model->mesh_count = model->placement_count = 1;
    model->placements[0].to_model = ao_affine_identity();
    m->vertex_count = vertex_count;
    m->triangle_count = triangle_count;
    for (size_t i = 0; i < vertex_count; i++) {
        m->positions[i] = ao_vec3_make(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]);
        if (normals)
            m->normals[i] = ao_mesh_given_normal(normals[3 * i], normals[3 * i + 1], normals[3 * i + 2],
                                                 &m->invalid_normals);
    }
    memcpy(m->indices, indices, 3 * triangle_count * sizeof *indices);
    if (normals && !keep_used_vertices(m))
        ok = ao_load_out_of_memory(name);
    ok = ok && ao_load_finish(m, name) && complete_normals(model, name, false, crease, budget);
    model->degenerate_count = m->degenerate_count;
    if (!ok)
        ao_model_finish(model);
    return ok;
}
