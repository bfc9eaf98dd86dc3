/* Benchmark inputs made at run time (nothing big is committed): a bumpy sphere of a chosen size and
 * a GLB file that places it under many nodes. Header only; for the benchmark programs. */
#ifndef AO_BENCH_MESHES_H
#define AO_BENCH_MESHES_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A closed triangle mesh: float positions (3 a vertex) and uint32 corners (3 a triangle). */
struct bench_mesh {
    float *positions;
    uint32_t *indices;
    size_t vertex_count, triangle_count;
};

/* A unit sphere with bumps of 5 % of its radius, `rings` rings of 2 rings vertices between two
 * poles: 4 rings^2 triangles; exits when memory is short. */
static inline void bench_bumpy_sphere(struct bench_mesh *m, uint32_t rings)
{
    uint32_t around = 2 * rings;
    m->vertex_count = (size_t)(rings - 1) * around + 2;
    m->triangle_count = 2 * (size_t)around * (rings - 1);
    m->positions = malloc(3 * m->vertex_count * sizeof *m->positions);
    m->indices = malloc(3 * m->triangle_count * sizeof *m->indices);
    if (!m->positions || !m->indices) {
        fprintf(stderr, "bench: out of memory making a sphere of %zu triangles\n", m->triangle_count);
        exit(1);
    }
    const double pi = 3.14159265358979323846;
    float *p = m->positions;
    for (uint32_t i = 1; i < rings; i++)
        for (uint32_t j = 0; j < around; j++) {
            double theta = pi * i / rings, phi = 2.0 * pi * j / around;
            double r = 1.0 + 0.05 * sin(12.0 * theta) * sin(12.0 * phi);
            *p++ = (float)(r * sin(theta) * cos(phi));
            *p++ = (float)(r * cos(theta));
            *p++ = (float)(r * sin(theta) * sin(phi));
        }
    uint32_t north = (rings - 1) * around, south = north + 1;
    p[0] = 0.0f, p[1] = 1.0f, p[2] = 0.0f, p[3] = 0.0f, p[4] = -1.0f, p[5] = 0.0f;
    uint32_t *t = m->indices;
    for (uint32_t j = 0; j < around; j++) {   /* the caps: outward (counter-clockwise seen from outside) */
        uint32_t k = (j + 1) % around, last = (rings - 2) * around;
        t[0] = north, t[1] = k, t[2] = j, t += 3;
        t[0] = south, t[1] = last + j, t[2] = last + k, t += 3;
    }
    for (uint32_t i = 0; i + 2 < rings; i++)
        for (uint32_t j = 0; j < around; j++) {
            uint32_t k = (j + 1) % around, a = i * around + j, b = i * around + k;
            uint32_t c = a + around, d = b + around;
            t[0] = a, t[1] = b, t[2] = d, t += 3;
            t[0] = a, t[1] = d, t[2] = c, t += 3;
        }
}

/* Frees the mesh's arrays. */
static inline void bench_mesh_free(struct bench_mesh *m)
{
    free(m->positions);
    free(m->indices);
}

/* Writes m as a GLB whose `copies` nodes place it on a grid of 3 units, `per_row` to a row, rows
 * stacked in layers of per_row rows; false when the file cannot be written. */
static inline bool bench_write_placed_glb(const char *path, const struct bench_mesh *m, size_t copies, size_t per_row)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < m->vertex_count; v++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fminf(lo[a], m->positions[3 * v + (size_t)a]);
            hi[a] = fmaxf(hi[a], m->positions[3 * v + (size_t)a]);
        }
    size_t position_bytes = 12 * m->vertex_count, index_bytes = 12 * m->triangle_count;
    size_t capacity = 1024 + 64 * copies, used = 0;
    char *json = malloc(capacity);
    if (!json)
        return false;
    used += (size_t)snprintf(json + used, capacity - used,
                             "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[");
    for (size_t k = 0; k < copies; k++)
        used += (size_t)snprintf(json + used, capacity - used, "%s%zu", k ? "," : "", k);
    used += (size_t)snprintf(json + used, capacity - used, "]}],\"nodes\":[");
    for (size_t k = 0; k < copies; k++)
        used += (size_t)snprintf(json + used, capacity - used, "%s{\"mesh\":0,\"translation\":[%zu,%zu,%zu]}",
                                 k ? "," : "", 3 * (k % per_row), 3 * (k / per_row / per_row),
                                 3 * (k / per_row % per_row));
    used += (size_t)snprintf(
        json + used, capacity - used,
        "],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":%zu,\"type\":\"VEC3\","
        "\"min\":[%.9g,%.9g,%.9g],\"max\":[%.9g,%.9g,%.9g]},"
        "{\"bufferView\":1,\"componentType\":5125,\"count\":%zu,\"type\":\"SCALAR\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":%zu},{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu}],"
        "\"buffers\":[{\"byteLength\":%zu}]}",
        m->vertex_count, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], 3 * m->triangle_count, position_bytes,
        position_bytes, index_bytes, position_bytes + index_bytes);
    while (used % 4)
        json[used++] = ' ';
    uint32_t bin = (uint32_t)(position_bytes + index_bytes);
    uint32_t header[5] = {0x46546C67u, 2, (uint32_t)(12 + 8 + used + 8 + bin), (uint32_t)used, 0x4E4F534Au};
    uint32_t bin_header[2] = {bin, 0x004E4942u};
    FILE *f = fopen(path, "wb");
    bool ok = f && fwrite(header, sizeof header, 1, f) == 1 && fwrite(json, used, 1, f) == 1 &&
              fwrite(bin_header, sizeof bin_header, 1, f) == 1 &&
              fwrite(m->positions, position_bytes, 1, f) == 1 && fwrite(m->indices, index_bytes, 1, f) == 1;
    ok = f && fclose(f) == 0 && ok;
    free(json);
    return ok;
}

#endif
