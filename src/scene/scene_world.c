/* The scene while it is read (see scene_place.h): reports at the reader's line, every element
 * charged to the scene budget, quads, mesh files loaded once each, models and their placements;
 * placing it all into the local frame is scene_place.c's. */
#include "scene_place.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>

#include "load.h"
#include "text.h"

bool ao_cursor_fail(const struct ao_cursor *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ao_text_vreport_at(c->path, (size_t)c->line, fmt, ap);
    va_end(ap);
    return false;
}

bool ao_world_charge(struct ao_cursor *c, struct ao_world *w, uint64_t triangles, uint64_t vertices, const char *what)
{
    uint64_t bytes;
    if (ao_budget_take_mesh(w->budget, triangles, vertices, &bytes))
        return true;
    char why[200];
    ao_budget_explain(w->budget, bytes, why, sizeof why);
    return ao_cursor_fail(c, "%s: %llu triangles and %llu vertices %s", what, (unsigned long long)triangles,
                          (unsigned long long)vertices, why);
}

bool ao_world_take(struct ao_cursor *c, struct ao_world *w, uint64_t bytes, const char *what)
{
    if (ao_budget_take(w->budget, bytes))
        return true;
    char why[200];
    ao_budget_explain(w->budget, bytes, why, sizeof why);
    return ao_cursor_fail(c, "%s %s", what, why);
}

/* Charges a mesh file's unique meshes their structures' cost (AO_BUDGET_MESH each). */
static bool charge_meshes(struct ao_cursor *c, struct ao_world *w, size_t count, const char *path)
{
    char what[4200];
    snprintf(what, sizeof what, "%s: the structures of %zu mesh%s", path, count, count == 1 ? "" : "es");
    return ao_world_take(c, w, (uint64_t)count * AO_BUDGET_MESH, what);
}

bool ao_world_add_quad(struct ao_world *w, const struct ao_dvec3 p[4], struct ao_vec3 n, struct ao_vec3 rho)
{
    if (!ao_scene_grow(&w->quads, w->quad_count, w->quad_count + 1, sizeof *w->quads))
        return false;
    struct ao_world_quad *q = &w->quads[w->quad_count++];
    memcpy(q->p, p, sizeof q->p);
    q->n = n, q->rho = rho;
    return true;
}

/* The slot of file_slots where a file of this identity and crease angle is, or the empty one where
 * it would go. */
static size_t file_slot(const struct ao_world *w, dev_t device, ino_t inode, double crease)
{
    uint64_t bits;
    memcpy(&bits, &crease, sizeof bits);
    uint64_t h = ((uint64_t)device * 0x9E3779B97F4A7C15u) ^ ((uint64_t)inode * 0xC2B2AE3D27D4EB4Fu) ^ bits;
    h ^= h >> 29;
    size_t mask = w->slot_count - 1;
    for (size_t i = (size_t)h & mask;; i = (i + 1) & mask) {
        uint32_t k = w->file_slots[i];
        if (!k || (w->files[k - 1].device == device && w->files[k - 1].inode == inode &&
                   w->files[k - 1].crease == crease))
            return i;
    }
}

/* Enters files[index], identified, into the hash table, doubling it when half full; false when
 * memory is short. */
static bool index_file(struct ao_world *w, size_t index)
{
    if (2 * (index + 1) > w->slot_count) {
        size_t count = w->slot_count ? 2 * w->slot_count : 64;
        uint32_t *slots = calloc(count, sizeof *slots);
        if (!slots)
            return false;
        free(w->file_slots);
        w->file_slots = slots, w->slot_count = count;
        for (size_t i = 0; i < index; i++)
            if (w->files[i].identified)
                w->file_slots[file_slot(w, w->files[i].device, w->files[i].inode, w->files[i].crease)] =
                    (uint32_t)i + 1;
    }
    const struct ao_world_file *f = &w->files[index];
    w->file_slots[file_slot(w, f->device, f->inode, f->crease)] = (uint32_t)index + 1;
    return true;
}

const struct ao_world_file *ao_world_find_file(const struct ao_world *w, const char *path, double crease)
{
    struct stat st;
    if (stat(path, &st) == 0) {
        if (!w->slot_count)
            return NULL;
        uint32_t k = w->file_slots[file_slot(w, st.st_dev, st.st_ino, crease)];
        return k ? &w->files[k - 1] : NULL;
    }
    for (size_t i = 0; i < w->file_count; i++)
        if (w->files[i].crease == crease && strcmp(w->files[i].path, path) == 0)
            return &w->files[i];
    return NULL;
}

const struct ao_world_file *ao_world_load_file(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w,
                                               const char *path, double crease)
{
    struct ao_model model;
    if (!ao_load_model(&model, path, w->budget, crease))
        return NULL;
    return ao_world_add_model(c, s, w, &model, path, crease);
}

const struct ao_world_file *ao_world_add_model(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w,
                                              struct ao_model *taken, const char *path, double crease)
{
    struct ao_model model = *taken;
    *taken = (struct ao_model){0};
    uint64_t triangles = 0, vertices = 0;
    for (size_t i = 0; i < model.mesh_count; i++)
        triangles += model.meshes[i].triangle_count, vertices += model.meshes[i].vertex_count;
    struct stat st;
    char *copy = strdup(path);
    bool ok = ao_world_charge(c, w, triangles, vertices, path) && charge_meshes(c, w, model.mesh_count, path);
    if (ok && (!copy || s->mesh_count + model.mesh_count >= UINT32_MAX ||
               !ao_scene_grow(&s->meshes, s->mesh_count, s->mesh_count + model.mesh_count, sizeof *s->meshes) ||
               !ao_scene_grow(&w->files, w->file_count, w->file_count + 1, sizeof *w->files))) {
        ok = ao_cursor_fail(c, "out of memory adding '%s'", path);
    }
    if (!ok) {
        free(copy);
        ao_model_finish(&model);
        return NULL;
    }
    struct ao_world_file *f = &w->files[w->file_count++];
    *f = (struct ao_world_file){.path = copy, .crease = crease, .first = s->mesh_count, .count = model.mesh_count,
                                .placements = model.placements, .placement_count = model.placement_count};
    if (stat(path, &st) == 0) {
        f->identified = true, f->device = st.st_dev, f->inode = st.st_ino;
        if (!index_file(w, w->file_count - 1)) {
            w->file_count--;
            free(copy);
            ao_model_finish(&model);
            ao_cursor_fail(c, "out of memory adding '%s'", path);
            return NULL;
        }
    }
    memcpy(s->meshes + s->mesh_count, model.meshes, model.mesh_count * sizeof *model.meshes);
    s->mesh_count += model.mesh_count;
    s->degenerate_count += model.degenerate_count;
    s->point_primitives += model.point_primitives;
    s->line_primitives += model.line_primitives;
    ao_scene_add_note(s, path, model.note);
    free(model.meshes);
    return f;
}

bool ao_world_place_model(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w,
                          const struct ao_world_file *f, const struct ao_affine *line, struct ao_vec3 rho,
                          const char *path)
{
    char what[4200];
    snprintf(what, sizeof what, "%s: %zu placements", path, f->placement_count);
    if (!ao_world_take(c, w, (uint64_t)f->placement_count * AO_BUDGET_INSTANCE, what))
        return false;
    uint32_t a;
    if (!ao_scene_add_albedo(s, rho, &a) ||
        !ao_scene_grow(&w->placements, w->placement_count, w->placement_count + f->placement_count,
                       sizeof *w->placements))
        return ao_cursor_fail(c, "out of memory placing '%s'", path);
    for (size_t i = 0; i < f->placement_count; i++)
        w->placements[w->placement_count++] = (struct ao_world_placement){
            (uint32_t)(f->first + f->placements[i].mesh), a, ao_affine_compose(line, &f->placements[i].to_model)};
    return true;
}

void ao_world_finish(struct ao_world *w)
{
    for (size_t i = 0; i < w->file_count; i++) {
        free(w->files[i].path);
        free(w->files[i].placements);
    }
    free(w->files);
    free(w->file_slots);
    free(w->placements);
    free(w->quads);
    free(w->info);
    free(w->sphere_centers);
}

