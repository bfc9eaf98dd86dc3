/* One tile's bookkeeping for the renderer: what it has taken since a restart, the part of its
 * pixels' streams it traces in a pass, the error estimate of its sums, and adaptive sampling's
 * rule for whether it joins the next pass. No threads and no I/O: pass.c calls these for the
 * tiles it owns. */
#ifndef AO_TILE_H
#define AO_TILE_H

#include <stdbool.h>
#include <stdint.h>

#include "accum.h"
#include "vec3.h"

/* Tiles are AO_TILE x AO_TILE pixels, numbered row by row; AO_TILE_PIXELS of them. */
enum { AO_TILE = 16, AO_TILE_PIXELS = AO_TILE * AO_TILE };

/* A rectangle of pixels [x0, x1) x [y0, y1) holding at most AO_TILE_PIXELS. */
struct ao_tile {
    int x0, y0, x1, y1;
};

/* Which part of its pixels' random streams a tile traces in one pass: `rounds` eye rays per pixel
 * (numbered from first_ray), each with `count` AO samples (numbered on from first_sample). `half`
 * is the pass's half of the accumulation (0 even, 1 odd); with Sobol numbers each half has streams
 * of its own, numbered within the half, so that the halves are independent estimates. */
struct ao_tile_work {
    uint64_t first_ray, first_sample;
    int rounds, count, half;
};

/* What a tile has taken since the last restart; written by the thread that traces it. */
struct ao_tile_state {
    uint32_t passes;
    uint32_t rays[2], spp[2];            /* eye rays and AO samples per pixel, even and odd passes */
    double variance;                     /* over its pixels, the sum of their estimated variances */
    double mean;                         /* over its pixels, the sum of their averages */
};

/* What a pass gives its tiles: at most `samples` AO samples a pixel, none past target_spp; with
 * per_ray > 0 (auto passes) rounds of per_ray samples on one eye ray, at least one round a pass
 * however few `samples` are, growing by doubling; whether the numbers are Sobol's (streams
 * numbered within each half). */
struct ao_tile_pass {
    uint32_t target_spp;
    int samples, per_ray;
    bool sobol;
};

/* Tile t of a width x height image, clipped to it. */
struct ao_tile ao_tile_rect(int width, int height, int t);

/* The AO samples per pixel tile ts has taken, both halves. */
uint32_t ao_tile_spp(const struct ao_tile_state *ts);

/* True once adaptive sampling may leave tile ts out of a pass. */
bool ao_tile_settled(const struct ao_tile_state *ts);

/* The image variance one more sample per pixel removes from tile ts of `pixels` pixels, per pixel. */
double ao_tile_gain(const struct ao_tile_state *ts, int pixels);

/* Whether tile ts of `pixels` pixels joins the next pass: short of target_spp and, with adaptive
 * sampling, not settled or picked by the rule against the busiest tile's spp and the largest gain. */
bool ao_tile_wanted(const struct ao_tile_state *ts, int pixels, uint32_t target_spp, bool adaptive,
                    uint32_t busiest, double fastest);

/* The part of its pixels' streams tile ts traces in pass p. */
struct ao_tile_work ao_tile_work_of(const struct ao_tile_state *ts, const struct ao_tile_pass *p);

/* Adds the sums of one pass over tile ts at rect (the work it was given) to accum, an image
 * `width` pixels wide, and updates its error estimate. */
void ao_tile_add(struct ao_tile_state *ts, struct ao_accum *accum, int width, struct ao_tile rect,
                 const struct ao_tile_work *work, const struct ao_vec3 *sums);

#endif
