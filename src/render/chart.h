/* The data of the viewer's live error chart: RMSE against time on log-log axes, one curve per run
 * (the frames between two restarts), the newest runs kept. Fixed capacity, no allocation, no GL. */
#ifndef AO_CHART_H
#define AO_CHART_H

#include <stdbool.h>
#include <stdint.h>

#include "frame.h"
#include "modes.h"

/* How many runs the chart keeps, and how many points each run keeps. */
#define AO_CHART_CURVES 6
#define AO_CHART_POINTS 128

/* The most ticks an axis gets. */
#define AO_CHART_TICKS 16

/* One frame of a run, in log10 units. */
struct ao_chart_point {
    float x;                 /* log10 of the seconds since the run's restart */
    float y;                 /* log10 of the RMSE */
};

/* One run, points in time order. All but the last point lie at least gap apart in x; the last is
 * always the newest frame. */
struct ao_chart_curve {
    uint64_t restarts;       /* ao_frame_info.restarts of the run's frames */
    enum ao_sampling sampling;
    float gap;               /* least x spacing of kept points; doubles each time the curve fills */
    int count;
    struct ao_chart_point points[AO_CHART_POINTS];
};

/* The kept runs, oldest first; a zeroed struct is an empty chart. Owned by one thread. */
struct ao_chart {
    int count;
    struct ao_chart_curve curves[AO_CHART_CURVES];
};

/* One log axis: its ends and ticks in log10 units, ticks at 1, 2 and 5 times powers of ten
 * (powers of ten alone, or every k-th, over wider ranges); both ends are ticks. */
struct ao_chart_axis {
    float lo, hi;
    int ticks;
    float tick[AO_CHART_TICKS];
};

/* Adds a frame's (seconds, RMSE) to the curve of its run. A frame of a new run starts a curve,
 * dropping the oldest when AO_CHART_CURVES are kept, or replacing the newest curve when that one
 * has only one point; a full curve is thinned to log-spaced points. Frames without a positive,
 * finite RMSE and time are ignored, and those of the normals view (whose RMSE against an AO
 * reference means nothing). Pure. */
void ao_chart_add(struct ao_chart *chart, const struct ao_frame_info *info);

/* Fills *x and *y with axes spanning every point of every curve, each at least one tick step
 * long; false when the chart has no point. Pure. */
bool ao_chart_axes(const struct ao_chart *chart, struct ao_chart_axis *x, struct ao_chart_axis *y);

/* Fills *axis with ticks for log10 values from lo to hi (lo <= hi). Pure. */
void ao_chart_axis(float lo, float hi, struct ao_chart_axis *axis);

#endif
