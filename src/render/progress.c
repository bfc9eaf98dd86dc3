/* How far a run is and its time left; see progress.h. */
#include "progress.h"

#include <math.h>
#include <stdio.h>

void ao_progress_add(struct ao_progress *p, const struct ao_frame_info *info)
{
    if (info->pass == 0)
        return;
    if (p->restarts != info->restarts || info->pass <= p->pass || p->pass == 0)
        *p = (struct ao_progress){.restarts = info->restarts};
    uint64_t rays = info->eye_rays + info->shadow_rays;
    double seconds = info->seconds - p->seconds, samples = (info->mean_spp - p->spp) * (double)info->pixels;
    if (p->pass == 1 && info->pass > 1) /* the first pass's rate stands alone only until a second */
        p->count = 0;
    if (seconds > 0.0 && samples > 0.0) {
        int k = p->count++ % AO_PROGRESS_RECENT;
        p->rays_of[k] = (double)(rays - p->rays);
        p->seconds_of[k] = seconds;
        p->eye_share[k] = (double)(info->eye_rays - p->eye_rays) / samples;
        p->longest = seconds > p->longest ? seconds : p->longest;
    }
    p->pass = info->pass;
    p->spp = info->mean_spp;
    p->seconds = info->seconds;
    p->rays = rays;
    p->eye_rays = info->eye_rays;
}

double ao_progress_left(const struct ao_progress *p, const struct ao_frame_info *info)
{
    if (info->done)
        return 0.0;
    if (info->pass == 0 || p->restarts != info->restarts || p->pass == 0 || p->count == 0)
        return NAN;
    int n = p->count < AO_PROGRESS_RECENT ? p->count : AO_PROGRESS_RECENT;
    double rays = 0.0, seconds = 0.0, eye_share = 0.0;
    for (int k = 0; k < n; k++) {
        rays += p->rays_of[k];
        seconds += p->seconds_of[k];
        eye_share = p->eye_share[k] > eye_share ? p->eye_share[k] : eye_share;
    }
    double slowest = rays / seconds;
    for (int k = 0; k < n; k++)
        if (p->seconds_of[k] * AO_PROGRESS_RECENT >= seconds)
            slowest = fmin(slowest, p->rays_of[k] / p->seconds_of[k]);
    double lack = info->target_spp > info->mean_spp ? info->target_spp - info->mean_spp : 0.0;
    double left = slowest > 0.0 ? lack * (double)info->pixels * (1.0 + eye_share) / slowest : INFINITY;
    if (info->time_limit > 0.0) {
        double rest = info->time_limit > info->seconds ? info->time_limit - info->seconds : 0.0;
        left = fmin(left, rest + p->longest);
    }
    if (info->target_error > 0.0 && isfinite(info->error) && info->error > 0.0) {
        double ratio = info->error / info->target_error, rest = info->seconds * (ratio * ratio - 1.0);
        left = fmin(left, rest > 0.0 ? rest : 0.0);
    }
    return isfinite(left) ? left : NAN;
}

double ao_progress_share(struct ao_progress *p, const struct ao_frame_info *info)
{
    if (info->done)
        return 1.0;
    double left = ao_progress_left(p, info), share = 0.0;
    if (!isnan(left) && info->seconds + left > 0.0)
        share = info->seconds / (info->seconds + left);
    else if (info->target_spp > 0)
        share = info->mean_spp / info->target_spp;
    if (p->restarts == info->restarts)
        share = fmax(share, p->share);
    share = share < 1.0 ? share : nextafter(1.0, 0.0);
    if (p->restarts == info->restarts)
        p->share = share;
    return share;
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

void ao_progress_format_spp(const struct ao_frame_info *info, char *out, size_t size)
{
    if (info->pass == 0)
        snprintf(out, size, "%s", "");
    else
        snprintf(out, size, "mean %.0f spp, up to %u", floor(info->mean_spp), (unsigned)info->target_spp);
}
