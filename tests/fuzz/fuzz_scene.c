/* libFuzzer target for the scene parser. The input is the scene text, parsed as if read from a
 * file in a scratch directory that holds four small meshes (tri.obj, quad.ply, bin.ply, and
 * nodes.gltf, which places one mesh under three nodes, one of them mirroring), so `mesh` lines
 * exercise loading, sharing, transforms, flattening and instancing without reaching outside it
 * (absolute paths aside); each input is parsed twice, instancing as AUTO decides and instancing
 * every mesh file's mesh. A scene that parses must be consistent: indices, meshes and albedos in
 * range, finite positions and eye within the range scene_place.c accepts (an instance's triangles mapped
 * into the local frame too), unit or zero normals, finite instance maps and slack. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "scene.h"
#include "scene_load.h"

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
    /* The triangle (0 0 0, 1 0 0, 0 1 0) as glTF mesh 0 under three nodes. */
    static const char gltf[] =
        "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 0}, {\"mesh\": 0, \"translation\": [2, 0, 0]},"
        " {\"mesh\": 0, \"scale\": [-1, 2, 1], \"rotation\": [0, 0.6, 0, 0.8]}],"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}],"
        " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"}],"
        " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}],"
        " \"buffers\": [{\"byteLength\": 36, \"uri\": \"data:application/gltf-buffer;base64,"
        "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}]}";
    fuzz_write_file(fuzz_temp_path("nodes.gltf"), gltf, sizeof gltf - 1);
}

/* The largest of p's coordinates in magnitude (NaN when one is). */
static float largest_coordinate(struct ao_vec3 p)
{
    return ao_vec3_is_finite(p) ? fmaxf(fabsf(p.x), fmaxf(fabsf(p.y), fabsf(p.z))) : NAN;
}

/* A message when a point of the local frame lies beyond what scene_place.c accepts, else NULL. */
static const char *check_point(struct ao_vec3 p)
{
    if (!ao_vec3_is_finite(p))
        return "non-finite position";
    if (largest_coordinate(p) > AO_SCENE_MAX_EXTENT)
        return "position beyond the range scene_place.c accepts";
    return NULL;
}

/* Aborts with a message when a parsed scene breaks what scene.h promises. */
static void check(const struct ao_scene *s)
{
    const char *broken = NULL;
    for (size_t m = 0; !broken && m < s->mesh_count; m++) {
        const struct ao_mesh *mesh = &s->meshes[m];
        for (size_t i = 0; !broken && i < 3 * mesh->triangle_count; i++)
            if (mesh->indices[i] >= mesh->vertex_count)
                broken = "index out of range";
        for (size_t i = 0; !broken && i < mesh->vertex_count; i++) {
            struct ao_vec3 p = mesh->positions[i], n = mesh->normals[i];
            double length = sqrt((double)n.x * n.x + (double)n.y * n.y + (double)n.z * n.z);
            if (!ao_vec3_is_finite(p))
                broken = "non-finite position";
            else if (!(length == 0.0 || fabs(length - 1.0) < 1e-5))
                broken = "normal neither unit nor zero";
        }
    }
    size_t triangles = 0;
    for (size_t i = 0; !broken && i < s->instance_count; i++) {
        const struct ao_instance *in = &s->instances[i];
        if (in->mesh >= s->mesh_count)
            broken = "instance of a mesh out of range";
        else if (in->albedo >= s->albedo_count)
            broken = "albedo index out of range";
        for (int k = 0; !broken && k < 12; k++)
            if (!isfinite(in->to_local[k]))
                broken = "instance map not finite";
        if (!broken && !(in->slack[0] >= 0.0f && in->slack[0] <= 0x1p-8f && isfinite(in->slack[1])))
            broken = "instance slack out of range";
        size_t count = broken ? 0 : s->meshes[in->mesh].triangle_count;
        triangles += count;
        for (size_t t = 0; !broken && t < count; t++) {
            struct ao_vec3 c[3];
            ao_scene_triangle(s, i, t, c);
            for (int k = 0; !broken && k < 3; k++)
                broken = check_point(c[k]);
        }
    }
    if (!broken && triangles != s->triangle_count)
        broken = "triangle count is not the instances' sum";
    for (size_t i = 0; !broken && i < s->sphere_count; i++)
        if (!(s->spheres[i].radius > 0.0f))
            broken = "sphere without a positive radius";
    /* A camera line's eye and target lie in the scene's range (scene_place.c's check_range). The
     * camera framing a scene without one stands 3.22 half-diagonals (each at most sqrt(3) / 2 of
     * AO_SCENE_MAX_EXTENT) from the box's centre, itself at most half AO_SCENE_MAX_EXTENT from the
     * origin: its eye within 3.3 AO_SCENE_MAX_EXTENT, its target (the centre) in range. */
    if (!broken && !(largest_coordinate(s->camera.eye) <= 4.0f * AO_SCENE_MAX_EXTENT))
        broken = "eye beyond where scene_place.c puts it";
    if (!broken && !(largest_coordinate(s->camera.target) <= AO_SCENE_MAX_EXTENT))
        broken = "target beyond the range scene_place.c accepts";
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
    for (int pass = 0; pass < 2; pass++) {
        struct ao_scene scene;
        struct ao_scene_options options = {.budget = AO_BUDGET_LEAST,
                                           .instancing = pass ? AO_INSTANCING_ALWAYS : AO_INSTANCING_AUTO};
        if (ao_scene_parse(&scene, text, path, &options))
            check(&scene);
        ao_scene_finish(&scene);
    }
    free(text);
    return 0;
}
