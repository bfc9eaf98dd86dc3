/* The scene budget: how much memory loading a scene may make aoview allocate. One budget covers
 * the whole scene (every mesh line, every glTF node, every file read); the scene, mesh and file
 * readers charge it before they allocate, so a small file cannot demand gigabytes. */
#ifndef AO_BUDGET_H
#define AO_BUDGET_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "modes.h"

/* The least default budget in bytes, 1 GiB: about 6 million triangles of an indexed mesh with the
 * MEDIUM BVH, 10 million of a binary one with the COMPACT BVH (docs/reliability.md). */
#define AO_BUDGET_LEAST ((uint64_t)1 << 30)

/* The machine's physical memory in bytes, as the system reports it (sysconf's _SC_PHYS_PAGES times
 * the page size), or 0 where it does not. The only place aoview asks. Any thread. */
uint64_t ao_budget_machine_memory(void);

/* The default budget for a machine of so much memory: a quarter of it, at least AO_BUDGET_LEAST
 * (chosen by the measurements of docs/reliability.md, "The default"). Pure. */
uint64_t ao_budget_default_for(uint64_t memory);

/* The default budget of this machine: ao_budget_default_for(ao_budget_machine_memory()). Any
 * thread. */
uint64_t ao_budget_default(void);

/* What each element is charged, in bytes: peak memory per triangle and per vertex through loading,
 * the scene's arrays and Embree's BVH (measured: 114 and 55, docs/reliability.md); per glTF node
 * (its world matrix, parent, depth, flags and stack slot: 150; charged with its JSON object); per
 * placement of a mesh that the scene instances (the placement, the scene's instance and Embree's
 * instance geometry and its share of the top-level BVH: measured in docs/reliability.md). */
enum { AO_BUDGET_TRIANGLE = 120, AO_BUDGET_VERTEX = 60, AO_BUDGET_NODE = 160, AO_BUDGET_INSTANCE = 512 };

/* What a scene's other elements are charged: per unique mesh, beside its triangles, vertices and
 * placements (its structs in the model and the scene, its file's entry, the tracer's geometry:
 * measured 1.1 KB more than those, docs/reliability.md); per pixel of the image a scene file's
 * `image` line sizes (the accumulation, the frames and, for a PNG, OSMesa's buffers: measured 72 to
 * 75 bytes; 48 for a PFM or EXR alone). */
enum { AO_BUDGET_MESH = 1280, AO_BUDGET_PIXEL = 76 };

/* What a flattened copy of a mesh (a placement the scene does not instance but copies: scene.h) is
 * charged beside its triangles and vertices and its placement's AO_BUDGET_INSTANCE: its mesh struct,
 * its arrays' allocations and the tracer's geometry of its own (measured: 1141 bytes a flattened
 * placement of a one-triangle mesh, 519-532 an instanced one; docs/reliability.md). */
enum { AO_BUDGET_COPY = 448 };

/* A triangle's charge when the BVHs are built compact: AO_BUDGET_TRIANGLE less the 64 bytes a
 * triangle by which Embree's compact BVH lowers the peak of a 10M-triangle GLB or binary PLY
 * (docs/reliability.md). */
enum { AO_BUDGET_TRIANGLE_COMPACT = 56 };

/* A budget: its limit, what is charged now (never more than the limit), the BVH whose rates it
 * charges (AUTO and LOW charge COMPACT's) and, for AUTO and LOW, what MEDIUM's rates (LOW's own)
 * would charge more. The caller owns it. */
struct ao_budget {
    uint64_t limit, used;
    enum ao_bvh bvh;
    uint64_t surplus;
};

/* True when bytes more fit in the budget. Any thread (one budget per loading thread). */
bool ao_budget_fits(const struct ao_budget *budget, uint64_t bytes);

/* Charges bytes when they fit and returns true; else charges nothing and returns false. */
bool ao_budget_take(struct ao_budget *budget, uint64_t bytes);

/* Gives back bytes taken for a while (a file's text, a parser's tree) once they are freed. */
void ao_budget_give(struct ao_budget *budget, uint64_t bytes);

/* The charge for unique meshes of so many triangles and vertices placed so many times at the rates
 * of budget's BVH (a triangle AO_BUDGET_TRIANGLE_COMPACT for COMPACT, AUTO and LOW,
 * AO_BUDGET_TRIANGLE for MEDIUM); UINT64_MAX where it overflows. */
uint64_t ao_budget_charge(const struct ao_budget *budget, uint64_t triangles, uint64_t vertices, uint64_t placements);

/* Charges a mesh of so many triangles and vertices (ao_budget_charge) when it fits, and for AUTO
 * and LOW counts what MEDIUM would charge more; false, charging nothing, when it does not fit.
 * *charge: the charge. */
bool ao_budget_take_mesh(struct ao_budget *budget, uint64_t triangles, uint64_t vertices, uint64_t *charge);

/* The BVH a scene loaded within budget gets: AUTO's is MEDIUM when MEDIUM's charges would have fit
 * too, else COMPACT; LOW's is LOW when those would have fit, else LOW_COMPACT (peak memory within
 * COMPACT's charges: docs/formats.md), so that LOW loads whatever AUTO loads; any other, as asked. */
enum ao_bvh ao_budget_bvh(const struct ao_budget *budget);

/* Writes why bytes do not fit, for a one-line message: "need about 4.9 GiB, more than the 1.0 GiB
 * left of the scene budget (raise it with --scene-budget)"; exact byte counts where the two would
 * read alike. */
void ao_budget_explain(const struct ao_budget *budget, uint64_t bytes, char *out, size_t size);

#endif
