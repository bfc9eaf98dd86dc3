/* The scene budget; see budget.h. */
#include "budget.h"

#include <assert.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

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

uint64_t ao_budget_mesh(uint64_t triangles, uint64_t vertices)
{
    const uint64_t most = UINT64_MAX / 2;
    if (triangles > most / AO_BUDGET_TRIANGLE || vertices > most / AO_BUDGET_VERTEX)
        return UINT64_MAX;
    return triangles * AO_BUDGET_TRIANGLE + vertices * AO_BUDGET_VERTEX;
}

uint64_t ao_budget_model(uint64_t triangles, uint64_t vertices, uint64_t placements)
{
    uint64_t mesh = ao_budget_mesh(triangles, vertices);
    if (mesh == UINT64_MAX || placements > UINT64_MAX / 4 / AO_BUDGET_INSTANCE)
        return UINT64_MAX;
    return mesh + placements * AO_BUDGET_INSTANCE;
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
