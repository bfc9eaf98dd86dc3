/* The renderer's side of an aoview-mpi share; see render_share.h and share.h. */
#include "render_share.h"

#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "text.h"

/* One tile of the image as a gather moves it (struct ao_render_share's gather): its running average
 * (its pixels row by row, clipped to the image), its error estimate (as struct ao_frame's), the
 * most samples a pixel of it has and their sum over its pixels. */
struct ao_tile_record {
    float rgb[3 * AO_TILE * AO_TILE];
    float error;
    uint32_t most;
    uint64_t samples;
};

/* The share's state, its hooks first (the struct ao_run_share the renderer holds is this): owned
 * by the render thread, but for span and given_up, which every thread of the team takes from or
 * sets, and the loans' callbacks (any thread). */
struct shared {
    struct ao_run_share hooks;
    const struct ao_render_share *share;
    struct ao_run_loop loop;
    struct ao_run *run;
    /* Per tile of the run (`tiles` of them): whether this process owns it. This process's work
     * list as one span of entries [front, back) (front in the low half) that its threads take from
     * the front and the share lends from the back; the lent entries' sums (AO_TILE x AO_TILE an
     * entry); whether the share gave the pass up; the pass as the share sees it. */
    int tiles;
    unsigned char *mine;
    atomic_uint_fast64_t span;
    struct ao_vec3 *pass_sums;
    atomic_bool given_up;
    struct ao_share_pass pass;
    /* The records of a gather (this process's tiles', and the leader's of every tile); the
     * leader's passes not gathered yet; seconds in the share's waits since the last combine, which
     * count in the next pass; the leader's next pass, begun before it published the last. */
    struct ao_tile_record *records, *all_records;
    bool ungathered;
    double seconds;
    struct ao_pass_start next;
    bool begun;
};

/* The state behind the hooks. */
static struct shared *state(struct ao_run_share *s)
{
    return (struct shared *)s;
}

/* ---- a pass with a share ---- */

/* Adds entries [begin, end) of the work list, which another process traced for this one, from the
 * pass's sums. */
static void add_entries(struct shared *st, int begin, int end)
{
    struct ao_run *r = st->run;
    for (int n = begin; n < end; n++) {
        int t = r->pass.work[n];
        struct ao_tile_work work = ao_pass_tile_work(r, t);
        ao_pass_add_tile(r, t, &work, st->pass_sums + (size_t)n * AO_TILE * AO_TILE);
    }
}

/* The next entry of this process's list for its threads, or -1 when none is left. */
static int take_entry(struct shared *st)
{
    uint_fast64_t span = atomic_load_explicit(&st->span, memory_order_relaxed);
    for (;;) {
        uint32_t front = (uint32_t)span, back = (uint32_t)(span >> 32);
        if (front >= back)
            return -1;
        if (atomic_compare_exchange_weak_explicit(&st->span, &span, span + 1, memory_order_relaxed,
                                                  memory_order_relaxed))
            return (int)front;
    }
}

/* struct ao_share_pass's left: the entries not begun. */
static int entries_left(void *renderer)
{
    uint_fast64_t span = atomic_load_explicit(&((struct shared *)renderer)->span, memory_order_relaxed);
    uint32_t front = (uint32_t)span, back = (uint32_t)(span >> 32);
    return back > front ? (int)(back - front) : 0;
}

/* struct ao_share_pass's lend: up to `most` entries not begun, from the end of the list, for
 * another process. */
static int lend_entries(void *renderer, int most, int *first, int *tiles, struct ao_tile_work *works)
{
    struct shared *st = renderer;
    uint_fast64_t span = atomic_load_explicit(&st->span, memory_order_relaxed);
    uint32_t back, count;
    do {
        uint32_t front = (uint32_t)span;
        back = (uint32_t)(span >> 32);
        count = back > front ? back - front : 0;
        count = count < (uint32_t)most ? count : (uint32_t)most;
        if (count == 0)
            return 0;
    } while (!atomic_compare_exchange_weak_explicit(&st->span, &span, span - ((uint_fast64_t)count << 32),
                                                    memory_order_relaxed, memory_order_relaxed));
    *first = (int)(back - count);
    for (uint32_t k = 0; k < count; k++) {
        tiles[k] = st->run->pass.work[*first + (int)k];
        works[k] = ao_pass_tile_work(st->run, tiles[k]);
    }
    return (int)count;
}

/* The team's job for a pass, on any thread: the entries of this process's list, adding those that
 * other processes traced for it as their sums come, then tiles borrowed from other processes. */
static void render_shared(void *user, int self)
{
    (void)self;
    struct shared *st = user;
    struct ao_run *r = st->run;
    const struct ao_render_share *share = st->share;
    uint64_t eye = 0, shadow = 0;
    while (!ao_pass_aborted(r)) {
        int arrived[2] = {0, 0};
        bool going = share->poll(share->user, &st->pass, arrived);
        add_entries(st, arrived[0], arrived[1]);
        if (!going) {
            atomic_store(&st->given_up, true);
            break;
        }
        int n = take_entry(st);
        if (n >= 0) {
            ao_pass_render_tile(r, n, &eye, &shadow);
            continue;
        }
        struct ao_share_loan loan;
        if (!share->borrow(share->user, &st->pass, &loan))
            break;
        struct ao_tile rect = ao_pass_tile_rect(r, loan.tile);
        ao_estimate_tile(&r->pass.ctx, &rect, &loan.work, loan.sums, &eye, &shadow);
        share->repay(share->user, &st->pass, &loan);
    }
    atomic_fetch_add_explicit(&r->pass.eye_rays, eye, memory_order_relaxed);
    atomic_fetch_add_explicit(&r->pass.shadow_rays, shadow, memory_order_relaxed);
}

/* The run hook: the pass on every thread of the team, then the sums of the entries it lent. */
static bool run_pass(struct ao_run_share *s, struct ao_run *r)
{
    struct shared *st = state(s);
    int count = ao_pass_begin(r);
    atomic_store(&st->span, (uint_fast64_t)count << 32);
    atomic_store(&st->given_up, false);
    st->pass = (struct ao_share_pass){.serial = r->pass.serial, .count = count, .pixels = AO_TILE * AO_TILE,
                                      .sums = st->pass_sums, .left = entries_left, .lend = lend_entries,
                                      .renderer = st};
    ao_pool_run(r->pass.pool, render_shared, st);
    bool finished = !ao_pass_aborted(r) && !atomic_load(&st->given_up);
    for (int arrived[2] = {0, 1}; arrived[0] < arrived[1];) {
        arrived[0] = arrived[1] = 0;
        if (!st->share->settle(st->share->user, &st->pass, finished, arrived))
            return false;
        add_entries(st, arrived[0], arrived[1]);
    }
    return finished;
}

/* ---- gathers ---- */

/* The records of this process's tiles, in tile order (a tile not traced in this run is black, with
 * no samples); returns how many. */
static int pack_records(struct shared *st)
{
    const struct ao_run *r = st->run;
    const struct ao_accum *a = &r->accum;
    int count = 0;
    for (int t = 0; t < r->tiles_x * r->tiles_y; t++) {
        if (!st->mine[t])
            continue;
        struct ao_tile_record *record = &st->records[count++];
        struct ao_tile rect = ao_pass_tile_rect(r, t);
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
        record->error = ao_pass_tile_error(r, t);
    }
    return count;
}

/* Gathers every process's tiles (a tile not traced in this run black, with no samples); the leader
 * resolves them into the back frame with info, its spp and mean spp those of the tiles gathered
 * when `counted` (after an interruption, when the aborted pass's finished tiles hold more than
 * info says). False when the share stops (or, the leader, memory is short). */
static bool gather(struct shared *st, const struct ao_frame_info *info, bool counted)
{
    struct ao_run *r = st->run;
    const struct ao_render_share *share = st->share;
    int count = pack_records(st);
    double start = ao_clock_seconds();
    bool leads = !share->follows;
    if (!share->gather(share->user, st->records, count, sizeof *st->records, leads ? st->all_records : NULL,
                       r->tiles_x * r->tiles_y))
        return false;
    st->seconds += ao_clock_seconds() - start;
    if (!leads)
        return true;
    struct ao_frame *f = ao_frames_back(&r->frames, r->width, r->height, r->tiles_x * r->tiles_y);
    if (!f)
        return false;
    uint32_t most = 0;
    uint64_t samples = 0;
    for (int t = 0; t < r->tiles_x * r->tiles_y; t++) {
        const struct ao_tile_record *record = &st->all_records[t];
        struct ao_tile rect = ao_pass_tile_rect(r, t);
        size_t row = 3 * (size_t)(rect.x1 - rect.x0) * sizeof(float);
        for (int j = rect.y0; j < rect.y1; j++)
            memcpy(f->rgb + 3 * ((size_t)j * (size_t)r->width + (size_t)rect.x0),
                   record->rgb + 3 * (size_t)(j - rect.y0) * (size_t)(rect.x1 - rect.x0), row);
        f->tile_error[t] = record->error;
        most = record->most > most ? record->most : most;
        samples += record->samples;
    }
    ao_pass_frame_facts(r, f, info);
    if (counted) {
        f->info.spp = most;
        f->info.mean_spp = (double)samples / ((double)r->width * (double)r->height);
    }
    st->ungathered = false;
    return true;
}

/* The leader: tells the others that a gather comes (with settings, which it leaves as they are),
 * gathers the image and publishes it with info; false when the share stops or memory is short. */
static bool frame(struct shared *st, const struct ao_settings *settings, const struct ao_frame_info *info)
{
    struct ao_settings sent = *settings;
    uint64_t restarts = 0;
    if (st->share->begin(st->share->user, AO_SHARE_GATHER, &sent, &restarts) != AO_SHARE_GATHER ||
        !gather(st, info, false))
        return false;
    ao_frames_publish(&st->run->frames);
    return true;
}

/* ---- the loop's hooks ---- */

/* Begins pass p on every process: the leader sends its start, another process waits for the
 * leader's and takes part in its gathers meanwhile (info: the facts of the last pass). No process
 * traces previews: each would trace every one. False when the share ended the run. */
static bool begin_pass(struct shared *st, struct ao_pass_start *p, const struct ao_frame_info *info)
{
    for (;;) {
        enum ao_share_step step = st->share->begin(st->share->user, AO_SHARE_PASS, &p->settings, &p->restarts);
        p->settings.previews = false;
        if (step != AO_SHARE_GATHER)
            return step == AO_SHARE_PASS;
        if (!gather(st, info, false))
            return false;
    }
}

static bool begin(struct ao_run_share *s, struct ao_run *run, struct ao_pass_start *p,
                  const struct ao_frame_info *info)
{
    (void)run;
    struct shared *st = state(s);
    if (!st->begun)
        return begin_pass(st, p, info);
    *p = st->next;
    st->begun = false;
    return true;
}

static bool begun(const struct ao_run_share *s)
{
    return ((const struct shared *)s)->begun;
}

/* The leader after a pass that counts: gathers a frame when one is due (for the last pass, when
 * it pauses, or by the share's clock) and begins the next pass before it reports this one (the
 * others wait for it). Another process publishes and reports nothing. */
static bool publish(struct ao_run_share *s, struct ao_run *run, const struct ao_settings *settings,
                    const struct ao_frame_info *info, bool *ending)
{
    struct shared *st = state(s);
    const struct ao_render_share *share = st->share;
    if (share->follows)
        return true;
    st->ungathered = true;
    bool pausing = st->loop.paused(st->loop.render);
    if ((info->done || pausing || share->due(share->user)) && !frame(st, settings, info))
        return false;
    if (!info->done && st->loop.take(st->loop.render, info, &st->next) &&
        !(st->begun = begin_pass(st, &st->next, info)))
        *ending = true;
    if (run->config.on_pass)
        run->config.on_pass(info, run->config.user);
    return true;
}

/* The leader gathers what it has not before its loop rests (done or idle). */
static bool rest(struct ao_run_share *s, struct ao_run *run, const struct ao_settings *settings,
                 const struct ao_frame_info *info, bool finishes, uint64_t own)
{
    (void)run;
    struct shared *st = state(s);
    if (st->share->follows || !st->ungathered || st->begun || !st->loop.rests(st->loop.render, info, finishes, own))
        return true;
    return frame(st, settings, info);
}

/* Every process sends its tiles; the leader gets the frame, still the back one. */
static struct ao_frame *stopped(struct ao_run_share *s, struct ao_run *r, const struct ao_frame_info *info)
{
    struct shared *st = state(s);
    if (!gather(st, info, true) || st->share->follows)
        return NULL;
    struct ao_frame *f = ao_frames_back(&r->frames, r->width, r->height, r->tiles_x * r->tiles_y);
    f->info.done = false;
    return f;
}

static void end(struct ao_run_share *s)
{
    struct shared *st = state(s);
    st->share->end(st->share->user);
}

/* ---- what pass.c asks ---- */

/* Frees the arrays fitted to a run's tiles. */
static void free_arrays(struct shared *st)
{
    free(st->mine);
    free(st->pass_sums);
    free(st->records);
    free(st->all_records);
    st->mine = NULL;
    st->pass_sums = NULL;
    st->records = st->all_records = NULL;
    st->tiles = 0;
}

/* Fits the arrays to a run of `tiles` tiles (the owners asked again) and forgets what was not
 * gathered. */
static bool restart(struct ao_run_share *s, int tiles)
{
    struct shared *st = state(s);
    st->ungathered = false;
    if (tiles == st->tiles)
        return true;
    free_arrays(st);
    const struct ao_render_share *share = st->share;
    size_t owned = 0, count = (size_t)tiles;
    st->mine = malloc(count);
    for (size_t t = 0; st->mine && t < count; t++)
        owned += st->mine[t] = share->owns(share->user, (int)t, tiles);
    st->pass_sums = malloc(count * AO_TILE * AO_TILE * sizeof *st->pass_sums);
    st->records = malloc((owned ? owned : 1) * sizeof *st->records);
    st->all_records = share->follows ? NULL : malloc(count * sizeof *st->all_records);
    if (!st->mine || !st->pass_sums || !st->records || (!share->follows && !st->all_records)) {
        ao_text_report("aoview: out of memory for a %dx%d image", st->run->width, st->run->height);
        free_arrays(st);
        return false;
    }
    st->tiles = tiles;
    return true;
}

static bool owns(const struct ao_run_share *s, int tile)
{
    return ((const struct shared *)s)->mine[tile];
}

static bool add_up(struct ao_run_share *s, uint64_t *values, int count)
{
    struct shared *st = state(s);
    double start = ao_clock_seconds();
    if (!st->share->add_up(st->share->user, values, count))
        return false;
    st->seconds += ao_clock_seconds() - start;
    return true;
}

static double waited(struct ao_run_share *s)
{
    return state(s)->seconds;
}

static bool combine(struct ao_run_share *s, struct ao_share_tally *tally)
{
    struct shared *st = state(s);
    double start = ao_clock_seconds();
    if (!st->share->combine(st->share->user, tally))
        return false;
    st->seconds = ao_clock_seconds() - start;
    return true;
}

static void destroy(struct ao_run_share *s)
{
    if (!s)
        return;
    free_arrays(state(s));
    free(s);
}

struct ao_run_share *ao_render_share_create(struct ao_run *run, const struct ao_render_share *share,
                                            const struct ao_run_loop *loop)
{
    struct shared *st = calloc(1, sizeof *st);
    if (!st) {
        ao_text_report("aoview: out of memory starting the renderer");
        return NULL;
    }
    st->hooks = (struct ao_run_share){.paced = share->follows, .one_list = true, .restart = restart, .owns = owns,
                                      .add_up = add_up, .waited = waited, .combine = combine, .begin = begin,
                                      .begun = begun, .run = run_pass, .publish = publish, .rest = rest,
                                      .stopped = stopped, .end = end, .destroy = destroy};
    st->share = share;
    st->loop = *loop;
    st->run = run;
    run->pass.ctx.cut = NULL; /* a borrowed tile is traced to the end: its owner adds its sums */
    atomic_init(&st->span, 0);
    atomic_init(&st->given_up, false);
    if (!restart(&st->hooks, run->tiles_x * run->tiles_y)) {
        destroy(&st->hooks);
        return NULL;
    }
    return &st->hooks;
}
