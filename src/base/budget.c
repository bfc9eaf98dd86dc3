/* The scene budget; see budget.h. */
#include "budget.h"

#include <assert.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

uint64_t ao_budget_machine_memory(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    return pages > 0 && size > 0 && (uint64_t)pages <= UINT64_MAX / (uint64_t)size ? (uint64_t)pages * (uint64_t)size
                                                                                  : 0;
}

uint64_t ao_budget_default_for(uint64_t memory)
{
    return memory / 4 > AO_BUDGET_LEAST ? memory / 4 : AO_BUDGET_LEAST;
}

uint64_t ao_budget_default(void)
{
    return ao_budget_default_for(ao_budget_machine_memory());
}

bool ao_budget_fits(const struct ao_budget *budget, uint64_t bytes)
{
    return bytes <= budget->limit - budget->used;
}

bool ao_budget_take(struct ao_budget *budget, uint64_t bytes)
{
    if (!ao_budget_fits(budget, bytes))
        return false;
    budget->used += bytes;
    return true;
}

void ao_budget_give(struct ao_budget *budget, uint64_t bytes)
{
    assert(bytes <= budget->used);
    budget->used -= bytes;
}

/* The charge at per_triangle bytes a triangle; UINT64_MAX where it overflows. */
static uint64_t charge_at(uint64_t per_triangle, uint64_t triangles, uint64_t vertices, uint64_t placements)
{
    const uint64_t most = UINT64_MAX / 4;
    if (triangles > most / per_triangle || vertices > most / AO_BUDGET_VERTEX || placements > most / AO_BUDGET_INSTANCE)
        return UINT64_MAX;
    return triangles * per_triangle + vertices * AO_BUDGET_VERTEX + placements * AO_BUDGET_INSTANCE;
}

uint64_t ao_budget_charge(const struct ao_budget *budget, uint64_t triangles, uint64_t vertices, uint64_t placements)
{
    bool compact = budget->bvh != AO_BVH_MEDIUM;
    return charge_at(compact ? AO_BUDGET_TRIANGLE_COMPACT : AO_BUDGET_TRIANGLE, triangles, vertices, placements);
}

bool ao_budget_take_mesh(struct ao_budget *budget, uint64_t triangles, uint64_t vertices, uint64_t *charge)
{
    *charge = ao_budget_charge(budget, triangles, vertices, 0);
    if (!ao_budget_take(budget, *charge))
        return false;
    if (budget->bvh == AO_BVH_AUTO || budget->bvh == AO_BVH_LOW) {   /* saturating: past UINT64_MAX, MEDIUM fits
                                                                        no budget anyway */
        const uint64_t per_triangle = AO_BUDGET_TRIANGLE - AO_BUDGET_TRIANGLE_COMPACT;
        uint64_t more = triangles <= UINT64_MAX / per_triangle ? triangles * per_triangle : UINT64_MAX;
        budget->surplus = more <= UINT64_MAX - budget->surplus ? budget->surplus + more : UINT64_MAX;
    }
    return true;
}

enum ao_bvh ao_budget_bvh(const struct ao_budget *budget)
{
    bool full = ao_budget_fits(budget, budget->surplus);
    if (budget->bvh == AO_BVH_AUTO)
        return full ? AO_BVH_MEDIUM : AO_BVH_COMPACT;
    if (budget->bvh == AO_BVH_LOW)
        return full ? AO_BVH_LOW : AO_BVH_LOW_COMPACT;
    return budget->bvh;
}

/* bytes in binary units with one decimal, "512.0 MiB", "4.9 GiB"; below 1 KiB, exact. */
static void format_size(uint64_t bytes, char *out, size_t size)
{
    static const char *const units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    double value = (double)bytes;
    int unit = 0;
    while (value >= 1023.95 && unit < 6) {   /* what would print as 1024.0 is the next unit's 1.0 */
        value /= 1024.0;
        unit++;
    }
    if (unit == 0)
        snprintf(out, size, "%llu bytes", (unsigned long long)bytes);
    else
        snprintf(out, size, "%.1f %s", value, units[unit]);
}

void ao_budget_explain(const struct ao_budget *budget, uint64_t bytes, char *out, size_t size)
{
    char need[64], left[64];
    uint64_t rest = budget->limit - budget->used;
    format_size(bytes, need, sizeof need);
    format_size(rest, left, sizeof left);
    bool exact = strcmp(need, left) == 0 || bytes < 1024;
    if (exact) {   /* too close to tell apart at one decimal: the counts */
        snprintf(need, sizeof need, "%llu bytes", (unsigned long long)bytes);
        snprintf(left, sizeof left, "%llu bytes", (unsigned long long)rest);
    }
    if (bytes == UINT64_MAX)
        snprintf(need, sizeof need, "more than 8 EiB");
    snprintf(out, size, "need%s %s, more than the %s left of the scene budget (raise it with --scene-budget)",
             exact || bytes == UINT64_MAX ? "" : " about", need, left);
}
