/* The render thread and its workers; see render.h and DESIGN.md's "Threads". */
#include "render.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "accum.h"
#include "ao.h"
#include "frames.h"
#include "pool.h"
#include "preview.h"
#include "scene.h"
#include "share.h"
#include "tile.h"
#include "tracer.h"

/* --spppp auto: the first pass after a restart takes one sample per pixel, so that the first
 * frame comes at once; then each pass of a half (even, odd) takes AUTO_PER_RAY samples, then
 * doubles what that half's sequence has given (ao_tile_work_of), up to about AUTO_SAMPLES samples
 * over the pixels it traces (8 spp a pass at 640x480, 128 at 160x120), in rounds of one eye ray
 * with AUTO_PER_RAY AO samples; both chosen by time to 1 % and 0.5 % RMSE
 * (docs/adaptive.md). The schedule depends on samples, not on seconds, so that the image stays a
 * function of the seed and settings alone. */
enum { AUTO_SAMPLES = 1 << 22, AUTO_PER_RAY = 8 };

/* One tile of the image as a gather moves it (struct ao_render_share's gather): its running average
 * (its pixels row by row, clipped to the image), its error estimate (as struct ao_frame's), the
 * most samples a pixel of it has and their sum over its pixels. */
struct tile_record {
    float rgb[3 * AO_TILE * AO_TILE];
    float error;
    uint32_t most;
    uint64_t samples;
};

/* The next pass as planned: the pixels it traces, and the AO samples its tiles lack of the
 * target (the work that remains while adaptive sampling keeps them). */
struct next_pass {
    uint64_t pixels, lack;
};

/* A thread's share of a pass: the tiles of the pass's work list in tile rows k, k + threads,
 * k + 2 threads, ... for thread k, taken in order from `next`. Each thread keeps the same pixels
 * pass after pass, so their sums stay in its own cache (handed round between threads, they crossed
 * caches on every pass); a thread that has finished its share helps with the others'. */
struct share {
    _Alignas(64) atomic_int next;        /* a line of its own: the other threads take from it too */
    int begin, end;                      /* its tiles in the work list */
};

struct ao_render {
    struct ao_render_config config;
    int width, height;                   /* of the accumulation: the size of the current run */
    struct ao_accum accum;               /* render thread (and its workers, pixel-disjoint) only */

    struct ao_frames frames;             /* to the consumer */

    /* Settings and control, under `lock`. */
    pthread_mutex_t lock;
    pthread_cond_t wake;                 /* render thread: settings changed, resume, stop */
    pthread_cond_t finished;             /* ao_render_wait: target reached or stopped */
    struct ao_settings settings;
    uint64_t restarts;
    bool done, stop;
    atomic_uint_fast64_t live_restarts;  /* copies of restarts and stop for the tile loop */
    atomic_bool live_stop;

    /* The pass in flight: written by the render thread before the pool runs it. */
    struct ao_pool *pool;
    uint64_t pass_serial;                /* numbers the passes */
    struct ao_context ctx;
    uint64_t pass_restarts;
    struct ao_tile_pass tile_pass;       /* what the pass gives each tile */
    int tiles_x, tiles_y;
    struct ao_tile_state *tiles;         /* tiles_x * tiles_y, row by row */
    double image_mean;                   /* of the running average, as of the last survey */
    int *work;                           /* the pass's tiles, grouped by share */
    struct share *shares;                /* one per thread, the render thread's first */
    atomic_uint_fast64_t eye_rays, shadow_rays;

    /* What the last survey planned (or a restart: nothing sampled yet), for select_tiles and the
     * next pass's size: the busiest tile's spp and the largest gain among the tiles short of the
     * target, and the pixels the next pass traces without and with adaptive sampling and the
     * samples its tiles lack of the target (known[k]: counted; with adaptive sampling off the
     * survey counts only the first). */
    uint32_t busiest;
    double fastest;
    struct next_pass next[2];
    bool next_known[2];

    /* With a share (aoview-mpi): the tiles this process owns; its work list as one span of entries
     * [front, back) (front in the low half) that its threads take from the front and the share
     * lends from the back; the lent entries' sums (AO_TILE x AO_TILE an entry); whether the share
     * gave the pass up; the records of a gather (this process's tiles', and the leader's of every
     * tile); the leader's passes not gathered yet; seconds in the share's waits since the last
     * pass, which count in the next. */
    unsigned char *mine;                 /* per tile; every tile without a share */
    atomic_uint_fast64_t span;
    struct ao_vec3 *pass_sums;
    atomic_bool given_up;
    struct ao_share_pass share_pass;
    struct tile_record *records, *all_records;
    bool ungathered;
    double share_seconds;
    struct ao_preview preview;           /* the preview in flight */

    pthread_t thread;
    bool started;
    struct ao_frame_info last_info;      /* the render thread's facts when it stopped */
};

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static bool aborted(struct ao_render *r)
{
    return atomic_load_explicit(&r->live_stop, memory_order_relaxed) ||
           atomic_load_explicit(&r->live_restarts, memory_order_relaxed) != r->pass_restarts;
}

/* ---- tiles: run by the render thread and every worker ---- */

/* The pixels of tile t, clipped to the image. */
static struct ao_tile tile_rect(const struct ao_render *r, int t)
{
    return ao_tile_rect(r->width, r->height, t);
}

/* The part of its pixels' streams tile t traces in this pass; *next (unless NULL) gets the half's
 * next sample number after it. */
static struct ao_tile_work tile_work(const struct ao_render *r, int t, uint32_t *next)
{
    return ao_tile_work_of(&r->tiles[t], &r->tile_pass, next);
}

/* Adds tile t's sums of one pass (the work it was given, after which its half's next sample is
 * `next`) to the accumulation and brings its state up to date. */
static void add_tile(struct ao_render *r, int t, const struct ao_tile_work *work, uint32_t next,
                     const struct ao_vec3 *sums)
{
    ao_tile_add(&r->tiles[t], &r->accum, r->width, tile_rect(r, t), work, next, sums);
}

/* Traces entry n of the work list and adds its sums. */
static void render_tile(struct ao_render *r, int n, uint64_t *eye, uint64_t *shadow)
{
    int t = r->work[n];
    struct ao_tile rect = tile_rect(r, t);
    uint32_t next;
    struct ao_tile_work work = tile_work(r, t, &next);
    struct ao_vec3 sums[AO_TILE_PIXELS];
    ao_estimate_tile(&r->ctx, &rect, &work, sums, eye, shadow);
    add_tile(r, t, &work, next, sums);
}

/* With a share: adds entries [begin, end) of the work list, which another process traced for this
 * one, from the pass's sums. */
static void add_entries(struct ao_render *r, int begin, int end)
{
    for (int n = begin; n < end; n++) {
        int t = r->work[n];
        uint32_t next;
        struct ao_tile_work work = tile_work(r, t, &next);
        add_tile(r, t, &work, next, r->pass_sums + (size_t)n * AO_TILE * AO_TILE);
    }
}

/* With a share: the next entry of this process's list for its threads, or -1 when none is left. */
static int take_entry(struct ao_render *r)
{
    uint_fast64_t span = atomic_load_explicit(&r->span, memory_order_relaxed);
    for (;;) {
        uint32_t front = (uint32_t)span, back = (uint32_t)(span >> 32);
        if (front >= back)
            return -1;
        if (atomic_compare_exchange_weak_explicit(&r->span, &span, span + 1, memory_order_relaxed,
                                                  memory_order_relaxed))
            return (int)front;
    }
}

/* struct ao_share_pass's left: the entries not begun. */
static int entries_left(void *renderer)
{
    uint_fast64_t span = atomic_load_explicit(&((struct ao_render *)renderer)->span, memory_order_relaxed);
    uint32_t front = (uint32_t)span, back = (uint32_t)(span >> 32);
    return back > front ? (int)(back - front) : 0;
}

/* struct ao_share_pass's lend: up to `most` entries not begun, from the end of the list, for
 * another process. */
static int lend_entries(void *renderer, int most, int *first, int *tiles, struct ao_tile_work *works)
{
    struct ao_render *r = renderer;
    uint_fast64_t span = atomic_load_explicit(&r->span, memory_order_relaxed);
    uint32_t back, count;
    do {
        uint32_t front = (uint32_t)span;
        back = (uint32_t)(span >> 32);
        count = back > front ? back - front : 0;
        count = count < (uint32_t)most ? count : (uint32_t)most;
        if (count == 0)
            return 0;
    } while (!atomic_compare_exchange_weak_explicit(&r->span, &span, span - ((uint_fast64_t)count << 32),
                                                    memory_order_relaxed, memory_order_relaxed));
    *first = (int)(back - count);
    for (uint32_t k = 0; k < count; k++) {
        tiles[k] = r->work[*first + (int)k];
        works[k] = tile_work(r, tiles[k], NULL);
    }
    return (int)count;
}

/* Thread `self`'s part of a pass: its own share, then what is left of the others'. */
static void render_tiles(struct ao_render *r, int self)
{
    int threads = r->config.threads;
    uint64_t eye = 0, shadow = 0;
    for (int v = 0; v < threads && !aborted(r); v++) {
        struct share *sh = &r->shares[(self + v) % threads];
        for (;;) {
            int n = sh->begin + atomic_fetch_add_explicit(&sh->next, 1, memory_order_relaxed);
            if (n >= sh->end || aborted(r))
                break;
            render_tile(r, n, &eye, &shadow);
        }
    }
    atomic_fetch_add_explicit(&r->eye_rays, eye, memory_order_relaxed);
    atomic_fetch_add_explicit(&r->shadow_rays, shadow, memory_order_relaxed);
}

/* With a share, any thread's part of a pass: the entries of this process's list, adding those that
 * other processes traced for it as their sums come, then tiles borrowed from other processes. */
static void render_shared(struct ao_render *r)
{
    const struct ao_render_share *share = r->config.share;
    const struct ao_share_pass *pass = &r->share_pass;
    uint64_t eye = 0, shadow = 0;
    while (!aborted(r)) {
        int arrived[2] = {0, 0};
        bool going = share->poll(share->user, pass, arrived);
        add_entries(r, arrived[0], arrived[1]);
        if (!going) {
            atomic_store(&r->given_up, true);
            break;
        }
        int n = take_entry(r);
        if (n >= 0) {
            render_tile(r, n, &eye, &shadow);
            continue;
        }
        struct ao_share_loan loan;
        if (!share->borrow(share->user, pass, &loan))
            break;
        struct ao_tile rect = tile_rect(r, loan.tile);
        ao_estimate_tile(&r->ctx, &rect, &loan.work, loan.sums, &eye, &shadow);
        share->repay(share->user, pass, &loan);
    }
    atomic_fetch_add_explicit(&r->eye_rays, eye, memory_order_relaxed);
    atomic_fetch_add_explicit(&r->shadow_rays, shadow, memory_order_relaxed);
}

/* The pool's job for a pass: render_tiles (or render_shared) on every thread. */
static void pass_job(void *user, int self)
{
    struct ao_render *r = user;
    if (r->config.share)
        render_shared(r);
    else
        render_tiles(r, self);
}

/* Runs one pass on all threads; false when it was aborted by a restart or stop, or given up by the
 * share. With a share, the entries this process lent are added once their sums are back. */
static bool run_pass(struct ao_render *r)
{
    int count = r->shares[r->config.threads - 1].end;
    for (int k = 0; k < r->config.threads; k++)
        atomic_store(&r->shares[k].next, 0);
    atomic_store(&r->span, (uint_fast64_t)count << 32);
    atomic_store(&r->given_up, false);
    r->pass_serial++;
    r->share_pass = (struct ao_share_pass){.serial = r->pass_serial, .count = count, .pixels = AO_TILE * AO_TILE,
                                           .sums = r->pass_sums, .left = entries_left, .lend = lend_entries,
                                           .renderer = r};
    ao_pool_run(r->pool, pass_job, r);
    bool finished = !aborted(r) && !atomic_load(&r->given_up);
    const struct ao_render_share *share = r->config.share;
    for (int arrived[2] = {0, 1}; share && arrived[0] < arrived[1];) {
        arrived[0] = arrived[1] = 0;
        if (!share->settle(share->user, &r->share_pass, finished, arrived))
            return false;
        add_entries(r, arrived[0], arrived[1]);
    }
    return finished;
}

/* ---- planning: run by the render thread between passes ---- */

/* The pixels of tile t (fewer than AO_TILE x AO_TILE at the right and bottom edges). */
static int tile_pixels(const struct ao_render *r, int t)
{
    struct ao_tile rect = tile_rect(r, t);
    return (rect.x1 - rect.x0) * (rect.y1 - rect.y0);
}

/* Fills the work list with the tiles of this process's (every tile without a share) that the next
 * pass traces, dealt to the threads' shares by tile row, and returns how many pixels they hold
 * and the samples they lack of the target: the tiles ao_tile_wanted picks, with the busiest tile's
 * spp and the largest gain that the last survey found. */
static struct next_pass select_tiles(struct ao_render *r, bool adaptive)
{
    /* With a share, one list in row order, the same whatever the threads. */
    int threads = r->config.threads, groups = r->config.share ? 1 : threads, tiles = r->tiles_x * r->tiles_y;
    uint32_t target = r->config.target_spp, busiest = r->busiest;
    double fastest = r->fastest;
    struct next_pass plan = {0, 0};
    int n = 0;
    for (int k = 0; k < threads; k++) {
        r->shares[k].begin = n;
        if (k >= groups) {
            r->shares[k].end = n;
            continue;
        }
        for (int t = k * r->tiles_x; t < tiles; t++) {
            if (r->mine[t] && ao_tile_wanted(&r->tiles[t], tile_pixels(r, t), target, adaptive, busiest, fastest)) {
                r->work[n++] = t;
                plan.pixels += (uint64_t)tile_pixels(r, t);
                plan.lack += (uint64_t)(target - ao_tile_spp(&r->tiles[t])) * (uint64_t)tile_pixels(r, t);
            }
            if ((t + 1) % r->tiles_x == 0) /* the end of a row: on to this share's next row */
                t += (groups - 1) * r->tiles_x;
        }
        r->shares[k].end = n;
    }
    return plan;
}

/* What the processes add up or maximise after a pass (struct ao_share_tally's slots). */
enum { EXACT_VARIANCE, EXACT_MEAN, EXACT_SQUARES };
enum { TOTAL_EYE, TOTAL_SHADOW, TOTAL_SAMPLES, TOTAL_SHORT, TOTAL_LACK };
enum { MOST_SECONDS, MOST_GAVE_UP, MOST_SPPPP, MOST_SPP, MOST_BUSIEST, MOST_FASTEST, MOST_UNHALVED, MOST_UNSETTLED };
_Static_assert((int)EXACT_SQUARES < (int)AO_TALLY_EXACT && (int)TOTAL_LACK < (int)AO_TALLY_TOTAL &&
                   (int)MOST_UNSETTLED < (int)AO_TALLY_MOST,
               "the tally's slots");

/* Whether the reference (if any) has the image's size: the RMSE is taken only then. */
static bool has_reference(const struct ao_render *r)
{
    return r->config.reference && r->config.reference_width == r->width &&
           r->config.reference_height == r->height;
}

/* Over the pixels of tile t, the sum of the squared differences of their running average (as
 * ao_accum_resolve makes it) from the reference, in row order. */
static double tile_squares(const struct ao_render *r, int t)
{
    struct ao_tile rect = tile_rect(r, t);
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
static void tally_tiles(const struct ao_render *r, struct ao_share_tally *tally)
{
    uint32_t target = r->config.target_spp;
    bool reference = has_reference(r);
    for (int t = 0; t < r->tiles_x * r->tiles_y; t++) {
        if (!r->mine[t])
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
            tally->total[TOTAL_LACK] += (uint64_t)(target - spp) * (uint64_t)tile_pixels(r, t);
            most[MOST_BUSIEST] = spp > most[MOST_BUSIEST] ? spp : most[MOST_BUSIEST];
            double gain = ao_tile_settled(ts) ? ao_tile_gain(ts, tile_pixels(r, t)) : 0.0;
            most[MOST_FASTEST] = gain > most[MOST_FASTEST] ? gain : most[MOST_FASTEST];
        }
    }
    for (int k = 0; k < AO_TALLY_EXACT; k++)
        ao_sum_normalize(&tally->exact[k]);
}

/* The next pass with adaptive sampling (`adaptive`) or without: as the last survey planned it, or
 * planned here (over the processes: every one takes the same path). False when the share stops. */
static bool next_pass(struct ao_render *r, bool adaptive, struct next_pass *plan)
{
    if (!r->next_known[adaptive]) {
        struct next_pass own = select_tiles(r, adaptive);
        uint64_t values[2] = {own.pixels, own.lack};
        const struct ao_render_share *share = r->config.share;
        double start = now_seconds();
        if (share && !share->add_up(share->user, values, 2))
            return false;
        if (share)
            r->share_seconds += now_seconds() - start;
        r->next[adaptive] = (struct next_pass){values[0], values[1]};
        r->next_known[adaptive] = true;
    }
    *plan = r->next[adaptive];
    return true;
}

/* After a pass this process ran (finished or not), with the pass's rays, seconds and largest share
 * of samples: combines the tally over the processes (with a share), adds the pass's rays and
 * seconds to info and, when every process finished it, fills in info's per-pixel counts, error
 * estimate, RMSE, converged share and whether the run is done, keeps the image mean and plans the
 * next pass. *counts: whether the pass counts; false when the share stops. */
static bool survey(struct ao_render *r, struct ao_frame_info *info, bool adaptive, bool finished, uint64_t rays[2],
                   double seconds, uint32_t spppp, bool *counts)
{
    struct ao_share_tally tally;
    memset(&tally, 0, sizeof tally);
    tally.total[TOTAL_EYE] = rays[0];
    tally.total[TOTAL_SHADOW] = rays[1];
    tally.most[MOST_SECONDS] = seconds + r->share_seconds;
    tally.most[MOST_GAVE_UP] = finished ? 0.0 : 1.0;
    tally.most[MOST_SPPPP] = spppp;
    if (finished || r->config.share)
        tally_tiles(r, &tally);
    const struct ao_render_share *share = r->config.share;
    double start = now_seconds();
    if (share && !share->combine(share->user, &tally))
        return false;
    r->share_seconds = share ? now_seconds() - start : 0.0;
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
    info->rmse = has_reference(r) ? sqrt(ao_sum_value(&tally.exact[EXACT_SQUARES]) / (3.0 * image)) : NAN;

    /* The next pass's plan, and what it says of this one. */
    r->busiest = (uint32_t)tally.most[MOST_BUSIEST];
    r->fastest = tally.most[MOST_FASTEST];
    r->next[0] = (struct next_pass){tally.total[TOTAL_SHORT], tally.total[TOTAL_LACK]};
    r->next_known[0] = true;
    r->next_known[1] = false;
    struct next_pass plan;
    if (!next_pass(r, adaptive, &plan))
        return false;
    uint64_t next = plan.pixels;
    info->converged = adaptive ? 1.0 - (double)next / image : 0.0;
    info->spp_left = (double)plan.lack / image;
    bool error_reached = r->config.target_error > 0.0 && tally.most[MOST_UNSETTLED] == 0.0 &&
                         info->error <= r->config.target_error;
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
    while ((size_t)cap * 2 * pixels <= AUTO_SAMPLES)
        cap *= 2;
    return cap;
}

/* The most samples per pixel any tile of the work list takes in this pass. */
static uint32_t largest_share(const struct ao_render *r)
{
    uint32_t most = 0;
    for (int n = 0; n < r->shares[r->config.threads - 1].end; n++) {
        struct ao_tile_work w = tile_work(r, r->work[n], NULL);
        uint32_t samples = (uint32_t)(w.rounds * w.count);
        most = samples > most ? samples : most;
    }
    return most;
}

/* ---- publishing ---- */

static double rmse(const float *image, const float *reference, size_t count)
{
    double sum = 0.0;
    for (size_t k = 0; k < count; k++) {
        double d = (double)image[k] - (double)reference[k];
        sum += d * d;
    }
    return sqrt(sum / (double)count);
}

/* Tile t's estimated error, as struct ao_frame's tile_error holds it: NAN until both halves of the
 * tile have a pass. */
static float tile_error(const struct ao_render *r, int t)
{
    const struct ao_tile_state *ts = &r->tiles[t];
    if (ts->spp[0] == 0 || ts->spp[1] == 0)
        return NAN;
    return r->image_mean > 0.0 ? (float)(sqrt(ts->variance / tile_pixels(r, t)) / r->image_mean) : 0.0f;
}

/* Frame f's facts for a whole image of this run, info's included. */
static void frame_facts(const struct ao_render *r, struct ao_frame *f, const struct ao_frame_info *info)
{
    f->tile = AO_TILE;
    f->tiles_x = r->tiles_x;
    f->tiles_y = r->tiles_y;
    f->block = 1;
    f->image_width = r->width;
    f->image_height = r->height;
    f->info = *info;
}

/* Resolves the running average into the back frame with its tile errors and info; the frame, or
 * NULL when memory is short. */
static struct ao_frame *resolve(struct ao_render *r, const struct ao_frame_info *info)
{
    struct ao_frame *f = ao_frames_back(&r->frames, r->width, r->height, r->tiles_x * r->tiles_y);
    if (!f)
        return NULL;
    ao_accum_resolve(&r->accum, f->rgb);
    for (int t = 0; t < r->tiles_x * r->tiles_y; t++)
        f->tile_error[t] = tile_error(r, t);
    frame_facts(r, f, info);
    return f;
}

/* Publishes the pass just surveyed; false when memory is short. */
static bool publish(struct ao_render *r, const struct ao_frame_info *info)
{
    if (!resolve(r, info))
        return false;
    ao_frames_publish(&r->frames);
    return true;
}

/* With a share: the records of this process's tiles, in tile order (a tile not traced in this run
 * is black, with no samples); returns how many. */
static int pack_records(struct ao_render *r)
{
    const struct ao_accum *a = &r->accum;
    int count = 0;
    for (int t = 0; t < r->tiles_x * r->tiles_y; t++) {
        if (!r->mine[t])
            continue;
        struct tile_record *record = &r->records[count++];
        struct ao_tile rect = tile_rect(r, t);
        bool traced = r->tiles[t].passes > 0;
        float *rgb = record->rgb;
        record->most = 0;
        record->samples = 0;
        for (int j = rect.y0; j < rect.y1; j++)
            for (int i = rect.x0; i < rect.x1; i++) {
                size_t p = (size_t)j * (size_t)r->width + (size_t)i;
                uint32_t n = traced ? a->count[p] : 0;
                double inv = n ? 1.0 / n : 0.0;
                for (int c = 0; c < 3; c++)
                    *rgb++ = traced ? (float)(a->sum[3 * p + c] * inv) : 0.0f;
                record->most = n > record->most ? n : record->most;
                record->samples += n;
            }
        record->error = tile_error(r, t);
    }
    return count;
}

/* With a share: gathers every process's tiles; the leader resolves them into the back frame with
 * info, its spp and mean spp those of the tiles gathered when `counted` (after an interruption,
 * when the aborted pass's finished tiles hold more than info says). False when the share stops
 * (or, the leader, memory is short). */
static bool gather(struct ao_render *r, const struct ao_frame_info *info, bool counted)
{
    const struct ao_render_share *share = r->config.share;
    int count = pack_records(r);
    double start = now_seconds();
    bool leads = !share->follows;
    if (!share->gather(share->user, r->records, count, sizeof *r->records, leads ? r->all_records : NULL,
                       r->tiles_x * r->tiles_y))
        return false;
    r->share_seconds += now_seconds() - start;
    if (!leads)
        return true;
    struct ao_frame *f = ao_frames_back(&r->frames, r->width, r->height, r->tiles_x * r->tiles_y);
    if (!f)
        return false;
    uint32_t most = 0;
    uint64_t samples = 0;
    for (int t = 0; t < r->tiles_x * r->tiles_y; t++) {
        const struct tile_record *record = &r->all_records[t];
        struct ao_tile rect = tile_rect(r, t);
        size_t row = 3 * (size_t)(rect.x1 - rect.x0) * sizeof(float);
        for (int j = rect.y0; j < rect.y1; j++)
            memcpy(f->rgb + 3 * ((size_t)j * (size_t)r->width + (size_t)rect.x0),
                   record->rgb + 3 * (size_t)(j - rect.y0) * (size_t)(rect.x1 - rect.x0), row);
        f->tile_error[t] = record->error;
        most = record->most > most ? record->most : most;
        samples += record->samples;
    }
    frame_facts(r, f, info);
    if (counted) {
        f->info.spp = most;
        f->info.mean_spp = (double)samples / ((double)r->width * (double)r->height);
    }
    r->ungathered = false;
    return true;
}

/* ao_preview_trace's stop. */
static bool preview_stops(void *user)
{
    return aborted(user);
}

/* The pool's job for a preview. */
static void preview_job(void *user, int self)
{
    (void)self;
    struct ao_render *r = user;
    ao_preview_trace(&r->preview, preview_stops, r);
}

/* While the camera is being moved, no preview finer than cells of a quarter of the first's: each
 * move restarts the run before a finer one would be done (at 3840x2160, cells of 8 pixels take
 * some 30 ms, moves come every 16 ms), so that tracing it only takes cores from the window. Waits
 * while the settings say so and nothing restarts or stops the run; true when the previews may go
 * on. Render thread. */
static bool navigation_allows(struct ao_render *r, int first, int block)
{
    if (block >= first / 4)
        return true;
    pthread_mutex_lock(&r->lock);
    while (r->settings.navigating && !r->stop && r->restarts == r->pass_restarts)
        pthread_cond_wait(&r->wake, &r->lock);
    pthread_mutex_unlock(&r->lock);
    return !aborted(r);
}

/* Traces and publishes the previews of the run that begins with info (pass 0) and camera, coarse
 * to fine, until the first full pass is due or a restart or stop aborts one; false when memory is
 * short. */
static bool preview(struct ao_render *r, const struct ao_camera *camera, const struct ao_frame_info *info)
{
    int first = ao_preview_first_block(r->width, r->height);
    for (int block = first; block > 1 && !aborted(r) && navigation_allows(r, first, block);
         block = ao_preview_next_block(block)) {
        struct ao_preview *p = &r->preview;
        if (!ao_preview_begin(p, &r->ctx, camera, r->width, r->height, block))
            return true;
        struct ao_frame *f = ao_frames_back(&r->frames, p->width, p->height, 0);
        if (!f)
            return false;
        p->rgb = f->rgb;
        ao_pool_run(r->pool, preview_job, r);
        if (aborted(r))
            break;
        f->tile = AO_TILE;
        f->tiles_x = f->tiles_y = 0;
        f->block = block;
        f->image_width = r->width;
        f->image_height = r->height;
        f->info = *info;
        ao_frames_publish(&r->frames);
        if (r->config.on_preview)
            r->config.on_preview(info, r->config.user);
    }
    return true;
}

const struct ao_frame *ao_render_take_frame(struct ao_render *render)
{
    return ao_frames_take(&render->frames);
}

int ao_render_take_log(struct ao_render *render, struct ao_frame_info *out, int most)
{
    return ao_frames_take_log(&render->frames, out, most);
}

/* ---- the render thread ---- */

/* True while there is no pass to run: paused, or done until the settings change. Called with
 * r->lock held. */
static bool idle(const struct ao_render *r, const struct ao_frame_info *info)
{
    return r->settings.paused || (info->restarts == r->restarts && r->done);
}

/* Waits until there is a pass to run; false on stop. Called with r->lock held. */
static bool wait_for_work(struct ao_render *r, const struct ao_frame_info *info)
{
    while (!r->stop && idle(r, info))
        pthread_cond_wait(&r->wake, &r->lock);
    return !r->stop;
}

/* What a pass is rendered with: the settings, and (with a share, the leader's) restarts, the
 * generation of the sums; `own` counts this process's restarts, which abort its pass. */
struct pass_start {
    struct ao_settings settings;
    uint64_t own, restarts;
};

/* Takes the settings for the next pass and, with a share, begins it on every process (another
 * process than the leader takes part in the leader's gathers while it waits); info: the facts of
 * the last pass. Called with r->lock held, which it releases; false when the share ended the run. */
static bool take_pass(struct ao_render *r, struct pass_start *p, const struct ao_frame_info *info)
{
    p->settings = r->settings;
    p->own = p->restarts = r->restarts;
    pthread_mutex_unlock(&r->lock);
    const struct ao_render_share *share = r->config.share;
    if (!share)
        return true;
    for (;;) {
        enum ao_share_step step = share->begin(share->user, AO_SHARE_PASS, &p->settings, &p->restarts);
        if (step != AO_SHARE_GATHER)
            return step == AO_SHARE_PASS;
        if (!gather(r, info, false))
            return false;
    }
}

/* The leader with a share: gathers the image from every process and publishes it with info; false
 * when the share stops or memory is short. */
static bool gather_frame(struct ao_render *r, const struct ao_frame_info *info)
{
    const struct ao_render_share *share = r->config.share;
    struct ao_settings settings = r->settings;
    uint64_t restarts = 0;
    if (share->begin(share->user, AO_SHARE_GATHER, &settings, &restarts) != AO_SHARE_GATHER || !gather(r, info, false))
        return false;
    ao_frames_publish(&r->frames);
    return true;
}

/* Allocates the accumulation, tile states and work lists of a width x height run; false with one
 * message when memory is short. */
static bool allocate_run(struct ao_render *r)
{
    r->tiles_x = (r->width + AO_TILE - 1) / AO_TILE;
    r->tiles_y = (r->height + AO_TILE - 1) / AO_TILE;
    if (!ao_accum_init(&r->accum, r->width, r->height))
        return false;
    size_t tiles = (size_t)r->tiles_x * (size_t)r->tiles_y, owned = 0;
    const struct ao_render_share *share = r->config.share;
    r->tiles = calloc(tiles, sizeof *r->tiles);
    r->work = calloc(tiles, sizeof *r->work);
    r->mine = malloc(tiles);
    if (r->mine)
        for (size_t t = 0; t < tiles; t++)
            owned += r->mine[t] = !share || share->owns(share->user, (int)t, (int)tiles);
    if (share) {
        r->pass_sums = malloc(tiles * AO_TILE * AO_TILE * sizeof *r->pass_sums);
        r->records = malloc((owned ? owned : 1) * sizeof *r->records);
        r->all_records = share->follows ? NULL : malloc(tiles * sizeof *r->all_records);
    }
    if (!r->tiles || !r->work || !r->mine ||
        (share && (!r->pass_sums || !r->records || (!share->follows && !r->all_records)))) {
        fprintf(stderr, "aoview: out of memory for a %dx%d image\n", r->width, r->height);
        return false;
    }
    return true;
}

/* Frees what allocate_run allocated; accepts what it left half done. */
static void free_run(struct ao_render *r)
{
    ao_accum_finish(&r->accum);
    free(r->tiles);
    free(r->work);
    free(r->mine);
    free(r->pass_sums);
    free(r->records);
    free(r->all_records);
    r->tiles = NULL;
    r->work = NULL;
    r->mine = NULL;
    r->pass_sums = NULL;
    r->records = r->all_records = NULL;
}

/* Starts a run of the settings s (restarts `restarts`): tile states cleared (the sums follow, tile
 * by tile: add_tile), at the size of s, and the previews traced; false when memory is short. */
static bool start_run(struct ao_render *r, const struct ao_settings *s, uint64_t restarts, struct ao_frame_info *info)
{
    if (s->width != r->width || s->height != r->height) {
        free_run(r);
        r->width = s->width;
        r->height = s->height;
        if (!allocate_run(r))
            return false;
    }
    memset(r->tiles, 0, (size_t)r->tiles_x * (size_t)r->tiles_y * sizeof *r->tiles);
    /* Nothing sampled: every tile short of the target (all of them) joins the first pass. */
    r->busiest = 0;
    r->fastest = 0.0;
    uint64_t pixels = r->config.target_spp ? (uint64_t)r->width * (uint64_t)r->height : 0;
    r->next[0] = r->next[1] = (struct next_pass){pixels, pixels * r->config.target_spp};
    r->next_known[0] = r->next_known[1] = true;
    r->ungathered = false;
    /* Nothing measured yet: the previews carry these facts. */
    *info = (struct ao_frame_info){.restarts = restarts, .target_spp = r->config.target_spp,
                                   .target_error = r->config.target_error, .time_limit = r->config.time_limit,
                                   .spp_left = NAN, .error = NAN, .converged = NAN, .rmse = NAN,
                                   .sampling = s->sampling, .aa = s->aa, .output = s->output, .shading = s->shading};
    return !s->previews || r->config.share || preview(r, &s->camera, info);
}

static void *render_main(void *arg)
{
    struct ao_render *r = arg;
    const struct ao_render_share *share = r->config.share;
    bool follows = share && share->follows, leads = share && !follows;
    struct ao_frame_info info = {.restarts = UINT64_MAX};
    struct pass_start next;
    bool begun = false; /* the leader began the next pass before it published the last */
    ao_tracer_thread_init();
    pthread_mutex_lock(&r->lock);
    while (begun || (follows ? !r->stop : wait_for_work(r, &info))) {
        /* Take the settings, unless they were taken; a restart starts a run. */
        if (begun) {
            pthread_mutex_unlock(&r->lock);
        } else if (!take_pass(r, &next, &info)) {
            ao_render_stop(r);
            pthread_mutex_lock(&r->lock);
            break;
        }
        begun = false;
        struct ao_settings s = next.settings;
        uint64_t own = next.own, restarts = next.restarts;
        r->ctx.sampling = s.sampling;
        r->ctx.aa = s.aa;
        r->ctx.output = s.output;
        r->ctx.shading = s.shading;
        r->pass_restarts = own;
        if (info.restarts != restarts && !start_run(r, &s, restarts, &info)) {
            ao_render_stop(r);
            pthread_mutex_lock(&r->lock);
            break;
        }

        /* Plan the pass: its tiles, its samples (from every process's pixels). */
        struct next_pass plan;
        if (!next_pass(r, s.adaptive, &plan)) {
            ao_render_stop(r);
            pthread_mutex_lock(&r->lock);
            break;
        }
        uint64_t pixels = plan.pixels;
        select_tiles(r, s.adaptive);
        r->tile_pass = (struct ao_tile_pass){.target_spp = r->config.target_spp,
                                             .samples = pass_samples(&s, pixels),
                                             .per_ray = s.spppp > 0 ? 0 : AUTO_PER_RAY,
                                             .sobol = r->ctx.sequence == AO_SEQUENCE_SOBOL};
        uint32_t spppp = largest_share(r);

        /* Run it, unless nothing is left to sample (adaptive sampling was just turned on), and
         * survey it (with a share, every process's tiles). */
        bool counts = false;
        if (pixels) {
            double start = now_seconds();
            ao_camera_view(&s.camera, r->width, r->height, &r->ctx.view);
            atomic_store(&r->eye_rays, 0);
            atomic_store(&r->shadow_rays, 0);
            bool finished = run_pass(r);
            uint64_t rays[2] = {atomic_load(&r->eye_rays), atomic_load(&r->shadow_rays)};
            if (!survey(r, &info, s.adaptive, finished, rays, now_seconds() - start, spppp, &counts)) {
                ao_render_stop(r);
                pthread_mutex_lock(&r->lock);
                break;
            }
        }

        /* Publish it: with a share the leader gathers a frame when one is due, for the last pass
         * and when it pauses, and begins the next pass before it publishes this one (the others
         * wait for it); the others keep no frames. */
        if (counts && !follows) {
            if (leads) {
                r->ungathered = true;
                pthread_mutex_lock(&r->lock);
                bool pausing = r->settings.paused;
                pthread_mutex_unlock(&r->lock);
                if ((info.done || pausing || share->due(share->user)) && !gather_frame(r, &info)) {
                    ao_render_stop(r);
                    pthread_mutex_lock(&r->lock);
                    break;
                }
                if (!info.done) {
                    pthread_mutex_lock(&r->lock);
                    if (r->stop || idle(r, &info))
                        pthread_mutex_unlock(&r->lock);
                    else if (!(begun = take_pass(r, &next, &info)))
                        ao_render_stop(r);
                }
            } else if (!publish(r, &info)) {
                ao_render_stop(r);
                pthread_mutex_lock(&r->lock);
                break;
            }
            if (r->config.on_pass)
                r->config.on_pass(&info, r->config.user);
        }
        /* Done: the image is finished until the settings change (the leader gathers what it has
         * not before it idles); another process's run goes on until the leader ends it. */
        bool finishes = (counts ? info.done : !pixels) && !follows;
        if (leads && r->ungathered && !begun) {
            pthread_mutex_lock(&r->lock);
            bool idles = !r->stop && ((finishes && own == r->restarts) || idle(r, &info));
            pthread_mutex_unlock(&r->lock);
            if (idles && !gather_frame(r, &info)) {
                ao_render_stop(r);
                pthread_mutex_lock(&r->lock);
                break;
            }
        }
        pthread_mutex_lock(&r->lock);
        if (finishes && own == r->restarts) {
            r->done = true;
            pthread_cond_broadcast(&r->finished);
        }
    }
    r->last_info = info;
    pthread_mutex_unlock(&r->lock);
    if (share)
        share->end(share->user);
    return NULL;
}

/* ---- life cycle and control ---- */

struct ao_render *ao_render_create(const struct ao_render_config *config,
                                   const struct ao_settings *settings)
{
    struct ao_render *r = calloc(1, sizeof *r);
    if (!r) {
        fprintf(stderr, "aoview: out of memory starting the renderer\n");
        return NULL;
    }
    r->config = *config;
    r->settings = *settings;
    r->width = settings->width;
    r->height = settings->height;
    ao_frames_init(&r->frames);
    r->ctx = (struct ao_context){.scene = config->scene, .tracer = config->tracer,
                                 .ao_distance = config->ao_distance, .seed = config->seed,
                                 .sequence = config->sequence, .below = config->below};
    pthread_mutex_init(&r->lock, NULL);
    pthread_cond_init(&r->wake, NULL);
    pthread_cond_init(&r->finished, NULL);
    r->shares = aligned_alloc(_Alignof(struct share), (size_t)config->threads * sizeof *r->shares);
    if (!r->shares) {
        fprintf(stderr, "aoview: out of memory starting the renderer\n");
        ao_render_destroy(r);
        return NULL;
    }
    for (int k = 0; k < config->threads; k++)
        atomic_init(&r->shares[k].next, 0);
    /* The render thread works tiles too, so the pool has threads - 1 workers besides it. */
    if (!allocate_run(r) || !(r->pool = ao_pool_create(config->threads, ao_tracer_thread_init))) {
        ao_render_destroy(r);
        return NULL;
    }
    r->started = pthread_create(&r->thread, NULL, render_main, r) == 0;
    if (!r->started) {
        fprintf(stderr, "aoview: could not start the render thread\n");
        ao_render_destroy(r);
        return NULL;
    }
    return r;
}

/* Stops the render thread and waits for it; the accumulation is then main's to read. */
static void join_render_thread(struct ao_render *render)
{
    ao_render_stop(render);
    if (render->started)
        pthread_join(render->thread, NULL);
    render->started = false;
}

const struct ao_frame *ao_render_resolve_stopped(struct ao_render *render)
{
    join_render_thread(render);
    struct ao_frame_info info = render->last_info;
    if (!render->accum.count)
        return NULL;
    if (render->config.share) { /* every process's tiles, not traced in this run black */
        if (!gather(render, &info, true) || render->config.share->follows)
            return NULL;
        /* the frame gather filled, still the back one (already that size) */
        struct ao_frame *f = ao_frames_back(&render->frames, render->width, render->height,
                                            render->tiles_x * render->tiles_y);
        f->info.done = false;
        return f;
    }
    for (int t = 0; t < render->tiles_x * render->tiles_y; t++)
        if (render->tiles[t].passes == 0) { /* not traced in this run: sums of an earlier one */
            struct ao_tile rect = tile_rect(render, t);
            ao_accum_clear(&render->accum, rect.x0, rect.y0, rect.x1, rect.y1);
        }
    struct ao_frame *f = resolve(render, &info);
    if (!f)
        return NULL;
    size_t pixels = (size_t)f->width * (size_t)f->height;
    uint32_t most = 0;
    uint64_t samples = 0;
    for (size_t p = 0; p < pixels; p++) {
        most = render->accum.count[p] > most ? render->accum.count[p] : most;
        samples += render->accum.count[p];
    }
    f->info.spp = most;
    f->info.mean_spp = (double)samples / (double)pixels;
    f->info.done = false;
    f->info.rmse = has_reference(render) ? rmse(f->rgb, render->config.reference, 3 * pixels) : NAN;
    return f;
}

void ao_render_destroy(struct ao_render *render)
{
    if (!render)
        return;
    join_render_thread(render);
    ao_pool_destroy(render->pool);
    pthread_cond_destroy(&render->finished);
    pthread_cond_destroy(&render->wake);
    pthread_mutex_destroy(&render->lock);
    ao_frames_finish(&render->frames);
    free(render->shares);
    free_run(render);
    free(render);
}

void ao_render_get_settings(struct ao_render *render, struct ao_settings *out)
{
    pthread_mutex_lock(&render->lock);
    *out = render->settings;
    pthread_mutex_unlock(&render->lock);
}

/* Bumps the restart counter so that the pass in flight aborts. Called with render->lock held. */
static void restart_locked(struct ao_render *render)
{
    render->restarts++;
    render->done = false;
    atomic_store(&render->live_restarts, render->restarts);
    pthread_cond_broadcast(&render->wake);
}

bool ao_render_set_settings(struct ao_render *render, const struct ao_settings *settings)
{
    pthread_mutex_lock(&render->lock);
    const struct ao_settings *old = &render->settings;
    bool changes_estimate = old->width != settings->width || old->height != settings->height ||
                            old->sampling != settings->sampling || old->aa != settings->aa ||
                            old->output != settings->output || old->shading != settings->shading ||
                            memcmp(&old->camera, &settings->camera, sizeof old->camera) != 0;
    if (old->adaptive != settings->adaptive) /* what is left to sample changes */
        render->done = false;
    render->settings = *settings;
    if (changes_estimate)
        restart_locked(render);
    pthread_cond_broadcast(&render->wake);
    pthread_mutex_unlock(&render->lock);
    return changes_estimate;
}

void ao_render_restart(struct ao_render *render)
{
    pthread_mutex_lock(&render->lock);
    restart_locked(render);
    pthread_mutex_unlock(&render->lock);
}

bool ao_render_wait(struct ao_render *render)
{
    pthread_mutex_lock(&render->lock);
    while (!render->done && !render->stop)
        pthread_cond_wait(&render->finished, &render->lock);
    bool done = render->done;
    pthread_mutex_unlock(&render->lock);
    return done;
}

void ao_render_stop(struct ao_render *render)
{
    pthread_mutex_lock(&render->lock);
    render->stop = true;
    atomic_store(&render->live_stop, true);
    pthread_cond_broadcast(&render->wake);
    pthread_cond_broadcast(&render->finished);
    pthread_mutex_unlock(&render->lock);
}
