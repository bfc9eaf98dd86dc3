/* A run of the renderer and its passes; see pass.h. */
#include "pass.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "phases.h"
#include "sum.h"
#include "text.h"

/* The normals view's picture is final, and its run done, once its estimated error (its
 * anti-aliasing's: each pass's eye rays are jittered) is below this: an RMSE of a fifth of an 8-bit
 * step at the image's mean, which no further pass changes visibly. Without anti-aliasing the error
 * is 0, and the run ends once its tiles are settled. (The bunny at 640x480: 0.2 s, some 40 eye rays
 * a pixel; docs/views.md.) */
static const double NORMALS_FINAL = 0.002;

/* ---- a run's memory ---- */

bool ao_pass_allocate(struct ao_run *r)
{
    r->tiles_x = (r->width + AO_TILE - 1) / AO_TILE;
    r->tiles_y = (r->height + AO_TILE - 1) / AO_TILE;
    if (!ao_accum_init(&r->accum, r->width, r->height))
        return false;
    size_t tiles = (size_t)r->tiles_x * (size_t)r->tiles_y;
    r->tiles = calloc(tiles, sizeof *r->tiles);
    r->tile_stamps = calloc(tiles, sizeof *r->tile_stamps);
    r->pass.work = calloc(tiles, sizeof *r->pass.work);
    if (!r->tiles || !r->tile_stamps || !r->pass.work) {
        ao_text_report("aoview: out of memory for a %dx%d image", r->width, r->height);
        return false;
    }
    return true;
}

void ao_pass_free(struct ao_run *r)
{
    ao_accum_finish(&r->accum);
    free(r->tiles);
    free(r->tile_stamps);
    free(r->pass.work);
    r->tiles = NULL;
    r->tile_stamps = NULL;
    r->pass.work = NULL;
}

bool ao_pass_restart(struct ao_run *r, int width, int height)
{
    if (width != r->width || height != r->height) {
        ao_pass_free(r);
        r->width = width;
        r->height = height;
        if (!ao_pass_allocate(r))
            return false;
    }
    memset(r->tiles, 0, (size_t)r->tiles_x * (size_t)r->tiles_y * sizeof *r->tiles);
    r->run_stamp = ++r->stamp;
    r->frame = NULL;   /* the frame begun, if any, counts as filled otherwise: its stamp is 0 */
    /* Nothing sampled: every tile short of the target (all of them) joins the first pass. */
    r->busiest = 0;
    r->fastest = 0.0;
    uint64_t pixels = r->config.target_spp ? (uint64_t)r->width * (uint64_t)r->height : 0;
    r->next[0] = r->next[1] = pixels;
    r->next_known[0] = r->next_known[1] = true;
    return r->share->restart(r->share, r->tiles_x * r->tiles_y);
}

/* ---- tiles: run by the render thread and every thread of the team ---- */

bool ao_pass_aborted(const struct ao_run *r)
{
    return atomic_load_explicit(&r->live_stop, memory_order_relaxed) ||
           atomic_load_explicit(&r->live_restarts, memory_order_relaxed) != r->pass.restarts;
}

struct ao_tile ao_pass_tile_rect(const struct ao_run *r, int t)
{
    return ao_tile_rect(r->width, r->height, t);
}

struct ao_tile_work ao_pass_tile_work(const struct ao_run *r, int t)
{
    return ao_tile_work_of(&r->tiles[t], &r->pass.tile_pass);
}

/* Stamps tile t's change and resolves the tile into the frame begun, if any. */
static void changed(struct ao_run *r, int t, struct ao_tile rect)
{
    r->tile_stamps[t] = r->stamp;
    if (r->frame)
        ao_accum_resolve_rect(&r->accum, rect.x0, rect.y0, rect.x1, rect.y1, r->frame->rgb);
}

void ao_pass_add_tile(struct ao_run *r, int t, const struct ao_tile_work *work, const struct ao_vec3 *sums)
{
    struct ao_tile rect = ao_pass_tile_rect(r, t);
    ao_tile_add(&r->tiles[t], &r->accum, r->width, rect, work, sums);
    changed(r, t, rect);
}

void ao_pass_clear_tile(struct ao_run *r, int t)
{
    struct ao_tile rect = ao_pass_tile_rect(r, t);
    ao_accum_clear(&r->accum, rect.x0, rect.y0, rect.x1, rect.y1);
    changed(r, t, rect);
}

void ao_pass_render_tile(struct ao_run *r, int n, uint64_t *eye, uint64_t *shadow)
{
    int t = r->pass.work[n];
    struct ao_tile rect = ao_pass_tile_rect(r, t);
    struct ao_tile_work work = ao_pass_tile_work(r, t);
    struct ao_vec3 sums[AO_TILE_PIXELS];
    double start = ao_phases_clock();
    if (ao_estimate_tile(&r->pass.ctx, &rect, &work, sums, eye, shadow)) { /* else cut: the pass is aborted */
        double traced = ao_phases_clock();
        ao_phases_add(AO_PHASE_TRACE, traced - start);
        ao_pass_add_tile(r, t, &work, sums);
        ao_phases_add(AO_PHASE_ADD, ao_phases_clock() - traced);
    }
}

/* The team's job for a pass of the solo share's: thread `self`'s lane, then what is left of the
 * others'. */
static void render_tiles(void *user, int self)
{
    struct ao_run *r = user;
    int threads = r->config.threads;
    uint64_t eye = 0, shadow = 0;
    ao_phases_enter(self);
    for (int v = 0; v < threads && !ao_pass_aborted(r); v++) {
        struct ao_lane *lane = &r->pass.lanes[(self + v) % threads];
        for (;;) {
            int n = lane->begin + atomic_fetch_add_explicit(&lane->next, 1, memory_order_relaxed);
            if (n >= lane->end || ao_pass_aborted(r))
                break;
            ao_pass_render_tile(r, n, &eye, &shadow);
        }
    }
    atomic_fetch_add_explicit(&r->pass.eye_rays, eye, memory_order_relaxed);
    atomic_fetch_add_explicit(&r->pass.shadow_rays, shadow, memory_order_relaxed);
    ao_phases_leave(self);
}

int ao_pass_begin(struct ao_run *r)
{
    int count = r->pass.lanes[r->config.threads - 1].end;
    for (int k = 0; k < r->config.threads; k++)
        atomic_store(&r->pass.lanes[k].next, 0);
    r->pass.serial++;
    return count;
}

/* Begins the back frame that changes are resolved into as they are made, with a fresh stamp for
 * them (left NULL when memory is short, which ao_pass_resolve then reports). */
static void begin_frame(struct ao_run *r)
{
    r->frame = ao_frames_back_stamped(&r->frames, r->width, r->height, r->tiles_x * r->tiles_y, &r->frame_kept);
    r->stamp++;
}

bool ao_pass_run(struct ao_run *r)
{
    ao_phases_job(ao_phases_clock());
    if (!r->frame)
        begin_frame(r);
    ao_pass_begin(r);
    ao_pool_run(r->pass.pool, render_tiles, r);
    ao_phases_job_end(r->config.threads, ao_phases_clock());
    return !ao_pass_aborted(r);
}

/* ---- planning: run by the render thread between passes ---- */

/* The pixels of tile t (fewer than AO_TILE x AO_TILE at the right and bottom edges). */
static int tile_pixels(const struct ao_run *r, int t)
{
    struct ao_tile rect = ao_pass_tile_rect(r, t);
    return (rect.x1 - rect.x0) * (rect.y1 - rect.y0);
}

/* Fills the work list with the tiles of this process's (every tile with the solo share) that the
 * next pass traces, dealt to the threads' shares by tile row (or in row order: one_list), and
 * returns how many pixels they hold: the tiles ao_tile_wanted picks, with the busiest tile's spp
 * and the largest gain that the last survey found. */
static uint64_t select_tiles(struct ao_run *r, bool adaptive)
{
    int threads = r->config.threads, groups = r->share->one_list ? 1 : threads, tiles = r->tiles_x * r->tiles_y;
    uint32_t target = r->config.target_spp, busiest = r->busiest;
    double fastest = r->fastest;
    uint64_t pixels = 0;
    int n = 0;
    for (int k = 0; k < threads; k++) {
        r->pass.lanes[k].begin = n;
        if (k >= groups) {
            r->pass.lanes[k].end = n;
            continue;
        }
        for (int t = k * r->tiles_x; t < tiles; t++) {
            if (r->share->owns(r->share, t) &&
                ao_tile_wanted(&r->tiles[t], tile_pixels(r, t), target, adaptive, busiest, fastest)) {
                r->pass.work[n++] = t;
                pixels += (uint64_t)tile_pixels(r, t);
            }
            if ((t + 1) % r->tiles_x == 0) /* the end of a row: on to this share's next row */
                t += (groups - 1) * r->tiles_x;
        }
        r->pass.lanes[k].end = n;
    }
    return pixels;
}

/* What the processes add up or maximise after a pass (struct ao_share_tally's slots). */
enum { EXACT_VARIANCE, EXACT_MEAN, EXACT_SQUARES };
enum { TOTAL_EYE, TOTAL_SHADOW, TOTAL_SAMPLES, TOTAL_SHORT };
enum { MOST_SECONDS, MOST_GAVE_UP, MOST_SPPPP, MOST_SPP, MOST_BUSIEST, MOST_FASTEST, MOST_UNHALVED, MOST_UNSETTLED };
_Static_assert((int)EXACT_SQUARES < (int)AO_TALLY_EXACT && (int)TOTAL_SHORT < (int)AO_TALLY_TOTAL &&
                   (int)MOST_UNSETTLED < (int)AO_TALLY_MOST,
               "the tally's slots");

bool ao_pass_has_reference(const struct ao_run *r)
{
    return r->config.reference && r->config.reference_width == r->width &&
           r->config.reference_height == r->height;
}

/* Over the pixels of tile t, the sum of the squared differences of their running average (as
 * ao_accum_resolve makes it) from the reference, in row order. */
static double tile_squares(const struct ao_run *r, int t)
{
    struct ao_tile rect = ao_pass_tile_rect(r, t);
    const struct ao_accum *a = &r->accum;
    double sum = 0.0;
    for (int j = rect.y0; j < rect.y1; j++)
        for (int i = rect.x0; i < rect.x1; i++) {
            size_t p = (size_t)j * (size_t)r->width + (size_t)i;
            double inv = a->count[p] ? 1.0 / a->count[p] : 0.0;
            for (int c = 0; c < 3; c++) {
                double d = (double)(float)(a->sum[3 * p + c] * inv) - (double)r->config.reference[3 * p + c];
                sum += d * d;
            }
        }
    return sum;
}

/* Fills in tally for the tiles this process owns: their per-pixel counts, error estimate, mean and
 * squared error from the reference as exact sums (so that any split of the tiles adds up to the
 * same bits), and what select_tiles and the target error decide on. */
static void tally_tiles(const struct ao_run *r, struct ao_share_tally *tally)
{
    uint32_t target = r->config.target_spp;
    bool reference = ao_pass_has_reference(r);
    for (int t = 0; t < r->tiles_x * r->tiles_y; t++) {
        if (!r->share->owns(r->share, t))
            continue;
        const struct ao_tile_state *ts = &r->tiles[t];
        uint32_t spp = ao_tile_spp(ts);
        double *most = tally->most;
        most[MOST_SPP] = spp > most[MOST_SPP] ? spp : most[MOST_SPP];
        tally->total[TOTAL_SAMPLES] += (uint64_t)spp * (uint64_t)tile_pixels(r, t);
        ao_sum_add(&tally->exact[EXACT_VARIANCE], ts->variance);
        ao_sum_add(&tally->exact[EXACT_MEAN], ts->mean);
        if (reference)
            ao_sum_add(&tally->exact[EXACT_SQUARES], tile_squares(r, t));
        if (ts->passes < 2)
            most[MOST_UNHALVED] = 1.0;
        if (!ao_tile_settled(ts) && spp < target)
            most[MOST_UNSETTLED] = 1.0;
        if (spp < target) {
            tally->total[TOTAL_SHORT] += (uint64_t)tile_pixels(r, t);
            most[MOST_BUSIEST] = spp > most[MOST_BUSIEST] ? spp : most[MOST_BUSIEST];
            double gain = ao_tile_settled(ts) ? ao_tile_gain(ts, tile_pixels(r, t)) : 0.0;
            most[MOST_FASTEST] = gain > most[MOST_FASTEST] ? gain : most[MOST_FASTEST];
        }
    }
    for (int k = 0; k < AO_TALLY_EXACT; k++)
        ao_sum_normalize(&tally->exact[k]);
}

bool ao_pass_plan(struct ao_run *r, bool adaptive, uint64_t *pixels)
{
    if (!r->next_known[adaptive]) {
        uint64_t own = select_tiles(r, adaptive);
        if (!r->share->add_up(r->share, &own, 1))
            return false;
        r->next[adaptive] = own;
        r->next_known[adaptive] = true;
    }
    *pixels = r->next[adaptive];
    return true;
}

bool ao_pass_survey(struct ao_run *r, struct ao_frame_info *info, bool adaptive, const struct ao_pass_result *pass,
                    bool *counts)
{
    struct ao_share_tally tally;
    memset(&tally, 0, sizeof tally);
    tally.total[TOTAL_EYE] = pass->rays[0];
    tally.total[TOTAL_SHADOW] = pass->rays[1];
    tally.most[MOST_SECONDS] = pass->seconds + r->share->waited(r->share);
    tally.most[MOST_GAVE_UP] = pass->finished ? 0.0 : 1.0;
    tally.most[MOST_SPPPP] = pass->spppp;
    if (pass->finished) /* else no process counts the pass, nor uses its tiles' tally */
        tally_tiles(r, &tally);
    if (!r->share->combine(r->share, &tally))
        return false;
    info->eye_rays += tally.total[TOTAL_EYE];
    info->shadow_rays += tally.total[TOTAL_SHADOW];
    info->seconds += tally.most[MOST_SECONDS];
    *counts = tally.most[MOST_GAVE_UP] == 0.0;
    if (!*counts)
        return true;

    double image = (double)r->width * (double)r->height;
    double variance = ao_sum_value(&tally.exact[EXACT_VARIANCE]), mean = ao_sum_value(&tally.exact[EXACT_MEAN]);
    info->pass++;
    info->spppp = (uint32_t)tally.most[MOST_SPPPP];
    info->spp = (uint32_t)tally.most[MOST_SPP];
    info->mean_spp = (double)tally.total[TOTAL_SAMPLES] / image;
    r->image_mean = mean / image;
    /* sqrt(variance / image) / (mean / image), 0 or infinite for a black image */
    info->error = tally.most[MOST_UNHALVED] > 0.0 ? NAN
                  : mean > 0.0                    ? sqrt(variance * image) / mean
                  : variance > 0.0                ? INFINITY
                                                  : 0.0;
    info->rmse = ao_pass_has_reference(r) ? sqrt(ao_sum_value(&tally.exact[EXACT_SQUARES]) / (3.0 * image)) : NAN;

    /* The next pass's plan, and what it says of this one. */
    r->busiest = (uint32_t)tally.most[MOST_BUSIEST];
    r->fastest = tally.most[MOST_FASTEST];
    r->next[0] = tally.total[TOTAL_SHORT];
    r->next_known[0] = true;
    r->next_known[1] = false;
    uint64_t next;
    if (!ao_pass_plan(r, adaptive, &next))
        return false;
    info->converged = adaptive ? 1.0 - (double)next / image : 0.0;
    double target_error = r->pass.ctx.output == AO_OUTPUT_NORMALS ? fmax(r->config.target_error, NORMALS_FINAL)
                                                             : r->config.target_error;
    bool error_reached = target_error > 0.0 && tally.most[MOST_UNSETTLED] == 0.0 && info->error <= target_error;
    bool time_up = r->config.time_limit > 0.0 && info->seconds >= r->config.time_limit;
    info->done = next == 0 || error_reached || time_up;
    return true;
}

/* The AO samples per pixel of the next pass: the setting, or with auto the most a tile may take
 * in a pass of `pixels` pixels (tile_work takes fewer while a tile grows). */
static int pass_samples(const struct ao_settings *s, size_t pixels)
{
    if (s->spppp > 0)
        return s->spppp;
    int cap = 1;
    while ((size_t)cap * 2 * pixels <= AO_AUTO_SAMPLES)
        cap *= 2;
    return cap;
}

/* The most samples per pixel any tile of the work list takes in this pass as the schedule gives
 * them, before the target's cap. */
static uint32_t largest_share(const struct ao_run *r)
{
    uint32_t most = 0;
    struct ao_tile_pass uncapped = r->pass.tile_pass;
    uncapped.target_spp = UINT32_MAX;
    for (int n = 0; n < r->pass.lanes[r->config.threads - 1].end; n++) {
        struct ao_tile_work w = ao_tile_work_of(&r->tiles[r->pass.work[n]], &uncapped);
        uint32_t samples = (uint32_t)(w.rounds * w.count);
        most = samples > most ? samples : most;
    }
    return most;
}

uint32_t ao_pass_prepare(struct ao_run *r, const struct ao_settings *s, uint64_t pixels)
{
    select_tiles(r, s->adaptive);
    r->pass.tile_pass = (struct ao_tile_pass){.target_spp = r->config.target_spp, .samples = pass_samples(s, pixels),
                                         .per_ray = s->spppp > 0 ? 0 : AO_AUTO_PER_RAY,
                                         .sobol = r->pass.ctx.sequence == AO_SEQUENCE_SOBOL};
    return largest_share(r);
}

/* ---- publishing ---- */

float ao_pass_tile_error(const struct ao_run *r, int t)
{
    const struct ao_tile_state *ts = &r->tiles[t];
    if (ts->spp[0] == 0 || ts->spp[1] == 0)
        return NAN;
    return r->image_mean > 0.0 ? (float)(sqrt(ts->variance / tile_pixels(r, t)) / r->image_mean) : 0.0f;
}

void ao_pass_frame_facts(const struct ao_run *r, struct ao_frame *f, const struct ao_frame_info *info)
{
    f->tile = AO_TILE;
    f->tiles_x = r->tiles_x;
    f->tiles_y = r->tiles_y;
    f->block = 1;
    f->image_width = r->width;
    f->image_height = r->height;
    f->info = *info;
}

struct ao_frame *ao_pass_resolve(struct ao_run *r, const struct ao_frame_info *info)
{
    if (!r->frame)
        begin_frame(r);
    struct ao_frame *f = r->frame;
    if (!f)
        return NULL;
    /* The frame's pixels are brought up to date where the sums changed since it was resolved (all
     * of them when it was resolved in another run, or filled otherwise), but for the changes made
     * since it was begun, resolved into it then. */
    uint64_t kept = r->frame_kept;
    for (int t = 0; t < r->tiles_x * r->tiles_y; t++) {
        if (r->tile_stamps[t] != r->stamp && (kept < r->run_stamp || r->tile_stamps[t] > kept)) {
            struct ao_tile rect = ao_pass_tile_rect(r, t);
            ao_accum_resolve_rect(&r->accum, rect.x0, rect.y0, rect.x1, rect.y1, f->rgb);
        }
        f->tile_error[t] = ao_pass_tile_error(r, t);
    }
    ao_frames_stamp_back(&r->frames, r->stamp++);
    r->frame = NULL;
    ao_pass_frame_facts(r, f, info);
    return f;
}

bool ao_pass_publish(struct ao_run *r, const struct ao_frame_info *info)
{
    if (!ao_pass_resolve(r, info))
        return false;
    ao_frames_publish(&r->frames);
    return true;
}
