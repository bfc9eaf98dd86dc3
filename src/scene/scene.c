/* The scene as the renderer sees it (see scene.h): its arrays grown, freed, and read back a
 * triangle at a time. */
#include "scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "text.h"

/* The elements an array of count elements has room for: at least 16, then the next power of two,
 * so that adding one element at a time copies each element about once (a realloc that grows by
 * one element copies the whole array under a sanitizer's allocator, which cost minutes for a scene
 * of 30,000 mesh lines). */
static size_t room(size_t count)
{
    size_t r = 16;
    while (r < count && r <= SIZE_MAX / 2)
        r *= 2;
    return r < count ? count : r;
}

bool ao_scene_grow(void *array, size_t had, size_t count, size_t size)
{
    void **slot = array;
    if (*slot && count <= room(had))
        return true;
    if (room(count) > SIZE_MAX / size)
        return false;
    void *p = realloc(*slot, room(count) * size);
    if (!p)
        return false;
    *slot = p;
    return true;
}

bool ao_scene_add_albedo(struct ao_scene *s, struct ao_vec3 rho, uint32_t *index)
{
    if (s->albedo_count >= UINT32_MAX ||
        !ao_scene_grow(&s->albedos, s->albedo_count, s->albedo_count + 1, sizeof *s->albedos))
        return false;
    s->albedos[s->albedo_count] = rho;
    *index = (uint32_t)s->albedo_count++;
    return true;
}

void ao_scene_add_note(struct ao_scene *s, const char *path, const char *note)
{
    if (!note[0])
        return;
    const char *slash = strrchr(path, '/');
    size_t used = strlen(s->notes);
    if (used + 4 < sizeof s->notes &&
        snprintf(s->notes + used, sizeof s->notes - used, "%s%s: %s", used ? "; " : "", slash ? slash + 1 : path,
                 note) < 0)
        s->notes[used] = '\0';
}

bool ao_scene_pad(struct ao_mesh *m)
{
    struct ao_vec3 *p = realloc(m->positions, (m->vertex_count + 1) * sizeof *p);
    if (!p)
        return false;
    p[m->vertex_count] = ao_vec3_make(0.0f, 0.0f, 0.0f);
    m->positions = p;
    return true;
}

void ao_scene_finish(struct ao_scene *scene)
{
    for (size_t i = 0; scene->meshes && i < scene->mesh_count; i++)
        ao_mesh_finish(&scene->meshes[i]);
    free(scene->meshes);
    free(scene->instances);
    free(scene->spheres);
    free(scene->albedos);
    memset(scene, 0, sizeof *scene);
}

bool ao_scene_add_flat_mesh(struct ao_scene *scene, struct ao_mesh *mesh, struct ao_vec3 albedo)
{
    uint32_t a;
    bool ok = scene->mesh_count < UINT32_MAX && scene->instance_count < UINT32_MAX && ao_scene_pad(mesh) &&
              ao_scene_grow(&scene->meshes, scene->mesh_count, scene->mesh_count + 1, sizeof *scene->meshes) &&
              ao_scene_grow(&scene->instances, scene->instance_count, scene->instance_count + 1,
                            sizeof *scene->instances) &&
              ao_scene_add_albedo(scene, albedo, &a);
    if (!ok) {
        ao_mesh_finish(mesh);
        return false;
    }
    scene->instances[scene->instance_count++] = (struct ao_instance){
        .mesh = (uint32_t)scene->mesh_count, .albedo = a, .flat = true,
        .to_local = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, .normals = {1, 0, 0, 0, 1, 0, 0, 0, 1}};
    scene->meshes[scene->mesh_count++] = *mesh;
    scene->triangle_count += mesh->triangle_count;
    *mesh = (struct ao_mesh){0};
    return true;
}

void ao_scene_triangle(const struct ao_scene *scene, size_t instance, size_t prim, struct ao_vec3 corners[3])
{
    const struct ao_instance *in = &scene->instances[instance];
    const struct ao_mesh *m = &scene->meshes[in->mesh];
    for (int k = 0; k < 3; k++) {
        struct ao_vec3 p = m->positions[m->indices[3 * prim + (size_t)k]];
        if (in->flat) {
            corners[k] = p;
            continue;
        }
        const float *a = in->to_local;
        double q[3];
        for (int r = 0; r < 3; r++)
            q[r] = (double)a[r] * p.x + (double)a[3 + r] * p.y + (double)a[6 + r] * p.z + (double)a[9 + r];
        corners[k] = ao_vec3_make((float)q[0], (float)q[1], (float)q[2]);
    }
}

void ao_scene_say_notes(const struct ao_scene *s)
{
    const struct {
        size_t count;
        const char *what;
    } parts[] = {{s->degenerate_count, "degenerate triangle"}, {s->point_primitives, "point primitive"},
                 {s->line_primitives, "line primitive"}};
    char line[256];
    size_t used = 0, n = sizeof parts / sizeof parts[0], left = 0;
    for (size_t k = 0; k < n; k++)
        left += parts[k].count > 0;
    for (size_t k = 0; k < n; k++) {
        if (!parts[k].count)
            continue;
        left--;
        used += (size_t)snprintf(line + used, sizeof line - used, "%s%zu %s%s", used ? (left ? ", " : " and ") : "",
                                 parts[k].count, parts[k].what, parts[k].count == 1 ? "" : "s");
    }
    if (used)
        ao_text_note("aoview: skipped %s", line);
    if (s->notes[0])
        ao_text_note("aoview: %s", s->notes);
}
