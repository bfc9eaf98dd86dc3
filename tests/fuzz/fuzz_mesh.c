/* libFuzzer target for one mesh loader: the input is written to a scratch file whose extension
 * (AO_FUZZ_EXT: ".obj", ".ply", ".stl", ".gltf" or ".glb") picks the loader, since
 * ao_load_model reads a path. A model that loads must be consistent: at least one mesh and
 * one placement, each mesh with indices in range, finite positions, unit or zero normals, each
 * placement naming a mesh through a finite matrix. The scene budget is 256 MiB, a quarter of the 1 GB that tests/fuzz/run.sh lets
 * the fuzzer's process hold: an input the budget allows (a Draco stream decoding to millions of
 * triangles, say) cannot then trip libFuzzer's memory limit under the sanitizers' overhead. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "fuzz.h"
#include "load.h"
#include "mesh.h"

#ifndef AO_FUZZ_EXT
#error "define AO_FUZZ_EXT as a mesh extension such as \".obj\""
#endif

/* A message when a loaded mesh breaks what mesh.h promises, else NULL. */
static const char *check_mesh(const struct ao_mesh *m)
{
    const char *broken = NULL;
    if (m->triangle_count == 0 || m->vertex_count == 0 || !m->positions || !m->normals ||
        !m->indices)
        broken = "empty mesh reported as loaded";
    for (size_t i = 0; !broken && i < 3 * m->triangle_count; i++)
        if (m->indices[i] >= m->vertex_count)
            broken = "index out of range";
    for (size_t i = 0; !broken && i < m->vertex_count; i++) {
        struct ao_vec3 p = m->positions[i], n = m->normals[i];
        double length = sqrt((double)n.x * n.x + (double)n.y * n.y + (double)n.z * n.z);
        if (!isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z))
            broken = "non-finite position";
        else if (!(length == 0.0 || fabs(length - 1.0) < 1e-5))
            broken = "normal neither unit nor zero";
    }
    return broken;
}

/* Aborts with a message when a loaded model breaks what mesh.h promises. */
static void check(const struct ao_model *m)
{
    const char *broken = m->mesh_count == 0 || m->placement_count == 0 ? "empty model reported as loaded" : NULL;
    for (size_t i = 0; !broken && i < m->mesh_count; i++)
        broken = check_mesh(&m->meshes[i]);
    for (size_t i = 0; !broken && i < m->placement_count; i++)
        if (m->placements[i].mesh >= m->mesh_count)
            broken = "placement of a mesh out of range";
        else if (!ao_affine_is_finite(&m->placements[i].to_model))
            broken = "placement by a matrix that is not finite";
    if (broken) {
        fprintf(stderr, "fuzz_mesh: %s\n", broken);
        abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_temp_path("input" AO_FUZZ_EXT);
    fuzz_write_file(path, data, size);
    struct ao_model model;
    struct ao_budget budget = {.limit = (uint64_t)256 << 20};
    if (ao_load_model(&model, path, &budget, AO_MESH_CREASE_DEFAULT))
        check(&model);
    ao_model_finish(&model);
    return 0;
}
