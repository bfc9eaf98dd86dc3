/* libFuzzer target for the scene parser. The input is the scene text, parsed as if read from a
 * file in a scratch directory that holds three small meshes (tri.obj, quad.ply, bin.ply), so
 * `mesh` lines exercise loading, transforms and merging without reaching outside it (absolute
 * paths aside). A scene that parses must be consistent: indices in range, finite positions and eye
 * within the range scene.c accepts, unit or zero normals. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "scene.h"

/* Writes the meshes that seed scenes refer to; once per process. */
static void write_meshes(void)
{
    static const char tri[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n";
    static const char quad[] = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                               "property float y\nproperty float z\nelement face 1\n"
                               "property list uchar int vertex_indices\nend_header\n"
                               "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
    static const char header[] = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                                 "property float x\nproperty float y\nproperty float z\n"
                                 "element face 1\nproperty list uchar uint8 vertex_indices\n"
                                 "end_header\n";
    /* Three little-endian float vertices (0 0 0, 1 0 0, 0 0 1), then the face 3 0 1 2. */
    static const unsigned char body[] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
                                         0, 0, 0x80, 0x3f, 0, 0, 0, 0, 0, 0, 0, 0,
                                         0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x80, 0x3f,
                                         3, 0, 1, 2};
    unsigned char binary[sizeof header - 1 + sizeof body];
    memcpy(binary, header, sizeof header - 1);
    memcpy(binary + sizeof header - 1, body, sizeof body);
    fuzz_write_file(fuzz_temp_path("tri.obj"), tri, sizeof tri - 1);
    fuzz_write_file(fuzz_temp_path("quad.ply"), quad, sizeof quad - 1);
    fuzz_write_file(fuzz_temp_path("bin.ply"), binary, sizeof binary);
}

/* Aborts with a message when a parsed scene breaks what scene.h promises. */
static void check(const struct ao_scene *s)
{
    const char *broken = NULL;
    for (size_t i = 0; !broken && i < 3 * s->triangle_count; i++)
        if (s->indices[i] >= s->vertex_count)
            broken = "index out of range";
    for (size_t i = 0; !broken && i < s->triangle_count; i++)
        if (s->triangle_albedo[i] >= s->albedo_count)
            broken = "albedo index out of range";
    for (size_t i = 0; !broken && i < s->sphere_count; i++)
        if (!(s->spheres[i].radius > 0.0f))
            broken = "sphere without a positive radius";
    for (size_t i = 0; !broken && i < s->vertex_count; i++) {
        struct ao_vec3 p = s->positions[i], n = s->normals[i];
        double length = sqrt((double)n.x * n.x + (double)n.y * n.y + (double)n.z * n.z);
        if (!ao_vec3_is_finite(p))
            broken = "non-finite position";
        else if (fmaxf(fabsf(p.x), fmaxf(fabsf(p.y), fabsf(p.z))) > AO_SCENE_MAX_EXTENT)
            broken = "position beyond the range scene.c accepts";
        else if (!(length == 0.0 || fabs(length - 1.0) < 1e-5))
            broken = "normal neither unit nor zero";
    }
    struct ao_vec3 eye = s->camera.eye;
    if (!broken && !(fmaxf(fabsf(eye.x), fmaxf(fabsf(eye.y), fabsf(eye.z))) <= AO_SCENE_MAX_EXTENT))
        broken = "eye beyond the range scene.c accepts";
    if (!broken && !(s->ao_distance > 0.0f))
        broken = "ao-distance not positive";
    if (!broken && (s->width < 0 || s->height < 0))
        broken = "negative image size";
    if (broken) {
        fprintf(stderr, "fuzz_scene: %s\n", broken);
        abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char *path;
    if (!path) {
        write_meshes();
        path = fuzz_temp_path("input.scene");
    }
    /* ao_scene_parse takes NUL-terminated text; a NUL in the input just ends it early. */
    char *text = malloc(size + 1);
    if (!text)
        return 0;
    memcpy(text, data, size);
    text[size] = '\0';
    struct ao_scene scene;
    if (ao_scene_parse(&scene, text, path))
        check(&scene);
    ao_scene_finish(&scene);
    free(text);
    return 0;
}
