/* The live error chart's data (see chart.h): a curve per run of (log seconds, log RMSE) points,
 * thinned to log-spaced ones when full, and axes with ticks at 1, 2 and 5 times powers of ten. */
#include "chart.h"

#include <math.h>
#include <string.h>

/* A new curve keeps points 1/256 decade (0.9 % in time) apart until it first fills. */
#define FIRST_GAP (1.0f / 256.0f)

/* Tolerance, in decades, for a value that lies on a tick but went through float rounding. */
#define ON_TICK 1e-4f

/* Doubles the curve's gap and drops every point but the newest that lies closer than the new gap
 * to the point kept before it, so that the kept points are spread evenly over log time. */
static void thin(struct ao_chart_curve *c)
{
    c->gap *= 2.0f;
    int kept = 1;
    for (int i = 1; i < c->count - 1; i++)
        if (c->points[i].x - c->points[kept - 1].x >= c->gap)
            c->points[kept++] = c->points[i];
    c->points[kept++] = c->points[c->count - 1];
    c->count = kept;
}

/* Makes p the newest point: it replaces the previous newest when that one lies closer than the
 * gap to the point before it, else it is appended, thinning a full curve first. */
static void append(struct ao_chart_curve *c, struct ao_chart_point p)
{
    for (;;) {
        int n = c->count;
        if (n >= 2 && c->points[n - 1].x - c->points[n - 2].x < c->gap) {
            c->points[n - 1] = p;
            return;
        }
        if (n < AO_CHART_POINTS) {
            c->points[c->count++] = p;
            return;
        }
        thin(c);
    }
}

/* Opens the curve of the frame's run: in place of a one-point newest curve, else after the others,
 * the oldest dropped when all slots are taken. */
static struct ao_chart_curve *start_curve(struct ao_chart *chart, const struct ao_frame_info *info)
{
    if (chart->count > 0 && chart->curves[chart->count - 1].count < 2) {
        chart->count--;
    } else if (chart->count == AO_CHART_CURVES) {
        memmove(chart->curves, chart->curves + 1, (AO_CHART_CURVES - 1) * sizeof chart->curves[0]);
        chart->count--;
    }
    struct ao_chart_curve *c = &chart->curves[chart->count++];
    c->restarts = info->restarts;
    c->sampling = info->sampling;
    c->gap = FIRST_GAP;
    c->count = 0;
    return c;
}

void ao_chart_add(struct ao_chart *chart, const struct ao_frame_info *info)
{
    if (!(info->rmse > 0) || !isfinite(info->rmse) || !(info->seconds > 0) || !isfinite(info->seconds) ||
        info->output == AO_OUTPUT_NORMALS)
        return;
    struct ao_chart_curve *c = chart->count > 0 ? &chart->curves[chart->count - 1] : NULL;
    if (!c || c->restarts != info->restarts)
        c = start_curve(chart, info);
    append(c, (struct ao_chart_point){(float)log10(info->seconds), (float)log10(info->rmse)});
}

bool ao_chart_axes(const struct ao_chart *chart, struct ao_chart_axis *x, struct ao_chart_axis *y)
{
    float x_lo = INFINITY, x_hi = -INFINITY, y_lo = INFINITY, y_hi = -INFINITY;
    for (int k = 0; k < chart->count; k++)
        for (int i = 0; i < chart->curves[k].count; i++) {
            struct ao_chart_point p = chart->curves[k].points[i];
            x_lo = fminf(x_lo, p.x);
            x_hi = fmaxf(x_hi, p.x);
            y_lo = fminf(y_lo, p.y);
            y_hi = fmaxf(y_hi, p.y);
        }
    if (x_lo > x_hi)
        return false;
    ao_chart_axis(x_lo, x_hi, x);
    ao_chart_axis(y_lo, y_hi, y);
    return true;
}

/* ---- ticks: numbered by integers, per_decade of them in each decade (3: at 1, 2 and 5; 1: at
 * the power of ten) and, with one per decade, every step-th decade only ---- */

/* log10(1), log10(2), log10(5). */
static const float MANTISSA[3] = {0.0f, 0.30103f, 0.69897f};

/* The log10 value of tick i. */
static float tick_value(long i, int per_decade, int step)
{
    if (per_decade == 1)
        return (float)(i * step);
    long decade = i >= 0 ? i / 3 : -((-i + 2) / 3);
    return (float)decade + MANTISSA[i - 3 * decade];
}

/* The last tick at or below v. */
static long tick_below(float v, int per_decade, int step)
{
    if (per_decade == 1)
        return (long)floorf((v + ON_TICK) / (float)step);
    long i = 3 * (long)floorf(v + ON_TICK);
    while (tick_value(i + 1, per_decade, step) <= v + ON_TICK)
        i++;
    return i;
}

/* The first tick at or above v. */
static long tick_above(float v, int per_decade, int step)
{
    long i = tick_below(v, per_decade, step);
    return tick_value(i, per_decade, step) >= v - ON_TICK ? i : i + 1;
}

void ao_chart_axis(float lo, float hi, struct ao_chart_axis *axis)
{
    /* The finest spacing that needs no more ticks than fit: 1-2-5 up to two decades (7 ticks),
     * then decades, then every second, third, ... decade. */
    int per_decade = 3, step = 1;
    long first, last;
    for (;;) {
        first = tick_below(lo, per_decade, step);
        last = tick_above(hi, per_decade, step);
        if (last == first)
            last++;
        if (last - first + 1 <= (per_decade == 3 ? 7 : AO_CHART_TICKS))
            break;
        if (per_decade == 3)
            per_decade = 1;
        else
            step++;
    }
    axis->ticks = (int)(last - first + 1);
    for (int k = 0; k < axis->ticks; k++)
        axis->tick[k] = tick_value(first + k, per_decade, step);
    axis->lo = axis->tick[0];
    axis->hi = axis->tick[axis->ticks - 1];
}
