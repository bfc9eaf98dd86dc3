/* The scene budget: how much memory loading a scene may make aoview allocate. One budget covers
 * the whole scene (every mesh line, every glTF node, every file read); the scene, mesh and file
 * readers charge it before they allocate, so a small file cannot demand gigabytes. */
#ifndef AO_BUDGET_H
#define AO_BUDGET_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* The default budget in bytes, 1 GiB: about 6 million triangles of an indexed mesh; every small
 * file that asked for gigabytes is refused (docs/reliability.md). */
#define AO_BUDGET_DEFAULT ((uint64_t)1 << 30)

/* What each element is charged, in bytes: peak memory per triangle and per vertex through loading,
 * the scene's arrays and Embree's BVH (measured: 114 and 55, docs/reliability.md); per glTF node
 * (its world matrix, parent, depth, flags and stack slot: 150; charged with its JSON object); per
 * placement of a mesh that the scene instances (the placement, the scene's instance and Embree's
 * instance geometry and its share of the top-level BVH: measured in docs/reliability.md). */
enum { AO_BUDGET_TRIANGLE = 120, AO_BUDGET_VERTEX = 60, AO_BUDGET_NODE = 160, AO_BUDGET_INSTANCE = 512 };

/* A budget: its limit and what is charged now (never more than the limit). The caller owns it. */
struct ao_budget {
    uint64_t limit, used;
};

/* True when bytes more fit in the budget. Any thread (one budget per loading thread). */
bool ao_budget_fits(const struct ao_budget *budget, uint64_t bytes);

/* Charges bytes when they fit and returns true; else charges nothing and returns false. */
bool ao_budget_take(struct ao_budget *budget, uint64_t bytes);

/* Gives back bytes taken for a while (a file's text, a parser's tree) once they are freed. */
void ao_budget_give(struct ao_budget *budget, uint64_t bytes);

/* The charge for a mesh of so many triangles and vertices; UINT64_MAX where it overflows. */
uint64_t ao_budget_mesh(uint64_t triangles, uint64_t vertices);

/* The charge for unique meshes of so many triangles and vertices placed so many times in all;
 * UINT64_MAX where it overflows. */
uint64_t ao_budget_model(uint64_t triangles, uint64_t vertices, uint64_t placements);

/* Writes why bytes do not fit, for a one-line message: "need about 4.9 GiB, more than the 1.0 GiB
 * left of the scene budget (raise it with --scene-budget)"; exact byte counts where the two would
 * read alike. */
void ao_budget_explain(const struct ao_budget *budget, uint64_t bytes, char *out, size_t size);

#endif
