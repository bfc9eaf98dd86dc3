/* A tile's bookkeeping (see tile.h). */
#include "tile.h"

/* Adaptive sampling works on whole tiles. A tile takes MIN_PASSES passes (two in each half) and
 * MIN_SPP samples per pixel before its error estimate decides anything. Then it joins a pass when
 * the error a sample removes there, variance / spp (the derivative of variance/n), is at least
 * SKIP_BELOW of the largest such value among the tiles: the greedy rule for the least image RMSE
 * per sample, so work goes where the error falls fastest. A tile whose estimate says "no error"
 * is rechecked once the busiest tile has RECHECK times its samples, so that none is left behind on
 * a lucky estimate. */
enum { MIN_PASSES = 4, MIN_SPP = 16, RECHECK = 8 };
static const double SKIP_BELOW = 0.25, ROUNDING = 1e-6;

struct ao_tile ao_tile_rect(int width, int height, int t)
{
    int tiles_x = (width + AO_TILE - 1) / AO_TILE;
    struct ao_tile rect = {.x0 = t % tiles_x * AO_TILE, .y0 = t / tiles_x * AO_TILE};
    rect.x1 = rect.x0 + AO_TILE < width ? rect.x0 + AO_TILE : width;
    rect.y1 = rect.y0 + AO_TILE < height ? rect.y0 + AO_TILE : height;
    return rect;
}

uint32_t ao_tile_spp(const struct ao_tile_state *ts)
{
    return ts->spp[0] + ts->spp[1];
}

bool ao_tile_settled(const struct ao_tile_state *ts)
{
    return ts->passes >= MIN_PASSES && ao_tile_spp(ts) >= MIN_SPP;
}

/* The derivative of variance/n over its pixels (see MIN_PASSES). */
double ao_tile_gain(const struct ao_tile_state *ts, int pixels)
{
    return ts->variance / pixels / ao_tile_spp(ts);
}

bool ao_tile_wanted(const struct ao_tile_state *ts, int pixels, uint32_t target_spp, bool adaptive,
                    uint32_t busiest, double fastest)
{
    uint32_t spp = ao_tile_spp(ts);
    if (spp >= target_spp)
        return false;
    if (!adaptive || !ao_tile_settled(ts))
        return true;
    double gain = ao_tile_gain(ts, pixels);
    return (gain > 0.0 && gain >= SKIP_BELOW * fastest) || (uint64_t)spp * RECHECK < busiest;
}

struct ao_tile_work ao_tile_work_of(const struct ao_tile_state *ts, const struct ao_tile_pass *p)
{
    int half = (int)(ts->passes & 1);
    uint32_t spp = ao_tile_spp(ts), left = p->target_spp - spp;
    int samples = (uint32_t)p->samples < left ? p->samples : (int)left;
    uint32_t start = ts->spp[half]; /* the half's next sample number */
    struct ao_tile_work w = {.half = half, .rounds = 1, .count = samples};
    if (p->per_ray) {
        /* Auto passes: each pass of a half takes as many samples as the half's sequence has given
         * (per_ray at first): 8, 8, 8, 8, 16, 16, 32, ... With Sobol numbers each pass of a half,
         * and each eye ray's per_ray samples within it, is then an aligned block of the half's
         * sequence from its start: a stratified net of directions. (A first pass of one sample,
         * from a sequence of its own, took 3 % more rays to 1 % RMSE: docs/adaptive.md; passes of
         * 1, 1, 1, 1, 2, 2, 4, 4 at first gave many eye rays few AO samples.) A tile rejoining late
         * grows by doubling, its halves balanced. Whole rounds of per_ray samples (the rest in a
         * later pass), or its eye rays would be too few for AA; at least one round however large
         * the image (a 1920x1080 pass of about 2^22 samples would give 2 per eye ray, where the
         * eye rays cost more than the AO rays: docs/estimator.md). */
        int most = p->samples > p->per_ray ? p->samples : p->per_ray; /* at least a round: eye rays cost */
        samples = most < (int)left ? most : (int)left;
        uint32_t grow = start ? start : (uint32_t)p->per_ray;
        samples = (uint32_t)samples <= grow ? samples : (int)grow;
        if (samples > p->per_ray)
            w.rounds = samples / p->per_ray, w.count = p->per_ray;
        else
            w.count = samples;
    }
    /* Random streams are numbered since the restart; Sobol ones within the half (see ao.h). */
    w.first_ray = p->sobol ? ts->rays[half] : ts->rays[0] + ts->rays[1];
    w.first_sample = p->sobol ? start : spp;
    return w;
}

void ao_tile_add(struct ao_tile_state *ts, struct ao_accum *accum, int width, struct ao_tile rect,
                 const struct ao_tile_work *work, const struct ao_vec3 *sums)
{
    uint32_t samples = (uint32_t)(work->rounds * work->count);
    int half = work->half;
    if (ts->passes++ == 0) /* a run clears its sums tile by tile, as each is first traced */
        ao_accum_clear(accum, rect.x0, rect.y0, rect.x1, rect.y1);
    ts->rays[half] += (uint32_t)work->rounds;
    ts->spp[half] += samples;
    /* Every pixel of a tile has the even and odd sample counts n_a and n_b of the tile. */
    double n_a = ts->spp[0], n_b = ts->spp[1], total = 0.0, squares = 0.0;
    for (int j = rect.y0; j < rect.y1; j++)
        for (int i = rect.x0; i < rect.x1; i++) {
            size_t p = (size_t)j * (size_t)width + (size_t)i;
            ao_accum_add(accum, p, sums[(j - rect.y0) * (rect.x1 - rect.x0) + (i - rect.x0)], samples, half);
            double all = accum->sum[3 * p] + accum->sum[3 * p + 1] + accum->sum[3 * p + 2];
            double odd = accum->odd_sum[p], d = (all - odd) * n_b - odd * n_a;
            total += all;
            squares += d * d;
        }
    /* A pixel's halves' means A = even/n_a and B = odd/n_b (of the channel mean) are independent
     * estimates with variances s2/n_a and s2/n_b, so E[(A - B)^2] = s2 (1/n_a + 1/n_b), and the
     * whole average's variance s2/(n_a + n_b) is (A - B)^2 n_a n_b / (n_a + n_b)^2 in expectation;
     * with d = 3 (A - B) n_a n_b that is d^2 / (9 n_a n_b n^2). Passes, not samples, are the
     * independent units (a pass's samples share an eye ray), hence halves made of whole passes.
     * The float sums of a pass round at a few 1e-8 of their value: relative differences below
     * ROUNDING are taken for rounding, not noise (a background pass after pass is exactly 0). */
    double n = n_a + n_b, pixels = (double)((rect.x1 - rect.x0) * (rect.y1 - rect.y0));
    ts->mean = total / (3.0 * n);
    double variance = n_a > 0.0 && n_b > 0.0 ? squares / (9.0 * n_a * n_b * n * n) : 0.0;
    double rounding = ROUNDING * ts->mean / pixels;
    ts->variance = variance > rounding * rounding * pixels ? variance : 0.0;
}
