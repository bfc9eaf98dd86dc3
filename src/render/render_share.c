/* The renderer's side of a share; see render_share.h and share.h. */
#include "render_share.h"

#include <string.h>

#include "clock.h"

/* ---- a pass with a share ---- */

/* With a share: adds entries [begin, end) of the work list, which another process traced for this
 * one, from the pass's sums. */
static void add_entries(struct ao_run *r, int begin, int end)
{
    for (int n = begin; n < end; n++) {
        int t = r->work[n];
        uint32_t next;
        struct ao_tile_work work = ao_pass_tile_work(r, t, &next);
        ao_pass_add_tile(r, t, &work, next, r->pass_sums + (size_t)n * AO_TILE * AO_TILE);
    }
}

/* With a share: the next entry of this process's list for its threads, or -1 when none is left. */
static int take_entry(struct ao_run *r)
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
    uint_fast64_t span = atomic_load_explicit(&((struct ao_run *)renderer)->span, memory_order_relaxed);
    uint32_t front = (uint32_t)span, back = (uint32_t)(span >> 32);
    return back > front ? (int)(back - front) : 0;
}

/* struct ao_share_pass's lend: up to `most` entries not begun, from the end of the list, for
 * another process. */
static int lend_entries(void *renderer, int most, int *first, int *tiles, struct ao_tile_work *works)
{
    struct ao_run *r = renderer;
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
        works[k] = ao_pass_tile_work(r, tiles[k], NULL);
    }
    return (int)count;
}

/* The team's job for a pass with a share, on any thread: the entries of this process's list,
 * adding those that other processes traced for it as their sums come, then tiles borrowed from
 * other processes. */
static void render_shared(void *user, int self)
{
    (void)self;
    struct ao_run *r = user;
    const struct ao_render_share *share = r->config.share;
    const struct ao_share_pass *pass = &r->share_pass;
    uint64_t eye = 0, shadow = 0;
    while (!ao_pass_aborted(r)) {
        int arrived[2] = {0, 0};
        bool going = share->poll(share->user, pass, arrived);
        add_entries(r, arrived[0], arrived[1]);
        if (!going) {
            atomic_store(&r->given_up, true);
            break;
        }
        int n = take_entry(r);
        if (n >= 0) {
            ao_pass_render_tile(r, n, &eye, &shadow);
            continue;
        }
        struct ao_share_loan loan;
        if (!share->borrow(share->user, pass, &loan))
            break;
        struct ao_tile rect = ao_pass_tile_rect(r, loan.tile);
        ao_estimate_tile(&r->ctx, &rect, &loan.work, loan.sums, &eye, &shadow);
        share->repay(share->user, pass, &loan);
    }
    atomic_fetch_add_explicit(&r->eye_rays, eye, memory_order_relaxed);
    atomic_fetch_add_explicit(&r->shadow_rays, shadow, memory_order_relaxed);
}

bool ao_render_share_pass(struct ao_run *r)
{
    int count = ao_pass_begin(r);
    r->share_pass = (struct ao_share_pass){.serial = r->pass_serial, .count = count, .pixels = AO_TILE * AO_TILE,
                                           .sums = r->pass_sums, .left = entries_left, .lend = lend_entries,
                                           .renderer = r};
    ao_pool_run(r->pool, render_shared, r);
    bool finished = !ao_pass_aborted(r) && !atomic_load(&r->given_up);
    const struct ao_render_share *share = r->config.share;
    for (int arrived[2] = {0, 1}; arrived[0] < arrived[1];) {
        arrived[0] = arrived[1] = 0;
        if (!share->settle(share->user, &r->share_pass, finished, arrived))
            return false;
        add_entries(r, arrived[0], arrived[1]);
    }
    return finished;
}

/* ---- gathers ---- */

/* With a share: the records of this process's tiles, in tile order (a tile not traced in this run
 * is black, with no samples); returns how many. */
static int pack_records(struct ao_run *r)
{
    const struct ao_accum *a = &r->accum;
    int count = 0;
    for (int t = 0; t < r->tiles_x * r->tiles_y; t++) {
        if (!r->mine[t])
            continue;
        struct ao_tile_record *record = &r->records[count++];
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

bool ao_render_share_gather(struct ao_run *r, const struct ao_frame_info *info, bool counted)
{
    const struct ao_render_share *share = r->config.share;
    int count = pack_records(r);
    double start = ao_clock_seconds();
    bool leads = !share->follows;
    if (!share->gather(share->user, r->records, count, sizeof *r->records, leads ? r->all_records : NULL,
                       r->tiles_x * r->tiles_y))
        return false;
    r->share_seconds += ao_clock_seconds() - start;
    if (!leads)
        return true;
    struct ao_frame *f = ao_frames_back(&r->frames, r->width, r->height, r->tiles_x * r->tiles_y);
    if (!f)
        return false;
    uint32_t most = 0;
    uint64_t samples = 0;
    for (int t = 0; t < r->tiles_x * r->tiles_y; t++) {
        const struct ao_tile_record *record = &r->all_records[t];
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
    r->ungathered = false;
    return true;
}

bool ao_render_share_frame(struct ao_run *r, const struct ao_settings *settings, const struct ao_frame_info *info)
{
    const struct ao_render_share *share = r->config.share;
    struct ao_settings sent = *settings;
    uint64_t restarts = 0;
    if (share->begin(share->user, AO_SHARE_GATHER, &sent, &restarts) != AO_SHARE_GATHER ||
        !ao_render_share_gather(r, info, false))
        return false;
    ao_frames_publish(&r->frames);
    return true;
}
