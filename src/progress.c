/* Time-left estimates; see progress.h. */
#include "progress.h"

#include <math.h>
#include <stdio.h>

/* The weight of the newest pass in the smoothed rate: recent enough to follow --spppp auto's
 * growing passes, smooth enough not to jump with one slow pass. */
static const double NEWEST = 0.5;

void ao_progress_add(struct ao_progress *p, const struct ao_frame_info *info)
{
    if (info->pass == 0)
        return;
    double spp = info->mean_spp, seconds = info->seconds;
    bool fresh = p->restarts != info->restarts || p->seconds <= 0.0 || spp < p->spp;
    if (fresh || !(p->rate > 0.0)) {
        p->rate = seconds > 0.0 ? spp / seconds : 0.0;
    } else if (seconds > p->seconds) {
        double rate = (spp - p->spp) / (seconds - p->seconds);
        p->rate = NEWEST * rate + (1.0 - NEWEST) * p->rate;
    }
    p->restarts = info->restarts;
    p->spp = spp;
    p->seconds = seconds;
}

double ao_progress_left(const struct ao_progress *p, const struct ao_frame_info *info)
{
    if (info->done)
        return 0.0;
    if (info->pass == 0 || p->restarts != info->restarts || !(p->seconds > 0.0))
        return NAN;
    double left = p->rate > 0.0 && isfinite(info->spp_left) ? info->spp_left / p->rate : NAN;
    if (info->time_limit > 0.0) {
        double rest = info->time_limit > info->seconds ? info->time_limit - info->seconds : 0.0;
        left = isnan(left) || rest < left ? rest : left;
    }
    if (info->target_error > 0.0 && isfinite(info->error) && info->error > 0.0) {
        double ratio = info->error / info->target_error, rest = info->seconds * (ratio * ratio - 1.0);
        rest = rest > 0.0 ? rest : 0.0;
        left = isnan(left) || rest < left ? rest : left;
    }
    return left;
}

double ao_progress_share(const struct ao_progress *p, const struct ao_frame_info *info)
{
    if (info->done)
        return 1.0;
    double left = ao_progress_left(p, info), share;
    if (!isnan(left) && info->seconds + left > 0.0)
        share = info->seconds / (info->seconds + left);
    else if (info->mean_spp + info->spp_left > 0.0)
        share = info->mean_spp / (info->mean_spp + info->spp_left);
    else
        share = 0.0;
    return share < 1.0 ? share : nextafter(1.0, 0.0);
}

void ao_progress_format(double left, char *out, size_t size)
{
    if (isnan(left))
        snprintf(out, size, "%s", "");
    else if (left > 0.0 && left < 0.05) /* not "~0.0": that is the end */
        snprintf(out, size, "%s", "<0.1 s left");
    else
        snprintf(out, size, left < 10.0 ? "~%.1f s left" : "~%.0f s left", left);
}
