/* The renderer's side of a share (render_share.c) and the decisions the processes make together,
 * without MPI: 2 and 3 simulated ranks, each a renderer on a thread of its own, joined by a share
 * kept in memory (struct ao_render_share, share.h): a leader whose settings every rank renders
 * with, collectives as rendezvous of every rank, loans made by calling the lender's pass directly,
 * the image gathered on the leader. The gathered image and the leader's pass facts (spp, rays,
 * error, RMSE, converged share, done: every column but the seconds) must be one process's, bit for
 * bit; a share that drops one rank's part must not pass. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "share.h"
#include "tracer.h"

static const char SCENE[] = "camera eye 0 1.5 4 target 0 0.5 0 fov 40\n"
                            "background 0.2 0.3 0.4\n"
                            "quad corner -5 0 -5 edge1 0 0 10 edge2 10 0 0 albedo 0.6\n"
                            "sphere center 0 0.5 0 radius 0.5 albedo 0.9 0.5 0.2\n"
                            "sphere center 1 0.25 0.5 radius 0.25\n";

enum { MOST_RANKS = 3, MOST_PASSES = 256, MOST_VALUES = 4, RETURNED = 4096 };

/* What the simulated ranks share, under `lock`: the rendezvous in progress (its generation, the
 * ranks arrived, what each brought), each rank's pass open to loans, the entries whose sums came
 * back, and the newest pass given up. */
struct bus {
    pthread_mutex_t lock;
    pthread_cond_t changed;
    int ranks;
    uint64_t generation;
    int arrived;
    /* A rendezvous's contributions and result. */
    struct {
        struct ao_share_tally tally;
        uint64_t values[MOST_VALUES];
        const void *records;
        int count;
    } in[MOST_RANKS];
    enum ao_share_step step;
    struct ao_settings settings;
    uint64_t restarts;
    struct ao_share_tally tally;
    uint64_t values[MOST_VALUES];
    void *all;
    size_t size;
    /* Loans: each rank's pass (serial, its struct, open to lend), entries lent and not repaid, the
     * entries repaid and not yet reported to the owner. */
    struct {
        uint64_t serial;
        const struct ao_share_pass *pass;
        bool open;
        int outstanding;
        int returned[RETURNED];
        int returns;
    } loans[MOST_RANKS];
    uint64_t given_up;
    int loans_made;
    bool drop;               /* the broken share: rank 1's tally and records are lost */
};

/* One simulated rank: its share and its place on the bus. */
struct rank {
    struct ao_render_share share;
    struct bus *bus;
    int rank, dues;
};

/* Rendezvous of every rank: `bring` (under the lock) leaves this rank's part; the last to arrive
 * runs `settle` on what all brought; every rank then runs `take` on the result. */
static void rendezvous(struct rank *k, void (*bring)(struct rank *k, void *arg),
                       void (*settle)(struct bus *b), void (*take)(struct rank *k, void *arg), void *arg)
{
    struct bus *b = k->bus;
    pthread_mutex_lock(&b->lock);
    bring(k, arg);
    uint64_t generation = b->generation;
    if (++b->arrived == b->ranks) {
        settle(b);
        b->arrived = 0;
        b->generation++;
        pthread_cond_broadcast(&b->changed);
    }
    while (b->generation == generation)
        pthread_cond_wait(&b->changed, &b->lock);
    take(k, arg);
    pthread_mutex_unlock(&b->lock);
}

/* ---- begin: the leader's step, settings and restarts to every rank ---- */

struct start {
    enum ao_share_step step;
    struct ao_settings *settings;
    uint64_t *restarts;
};

static void bring_start(struct rank *k, void *arg)
{
    struct start *s = arg;
    if (k->rank != 0)
        return;
    k->bus->step = s->step;
    k->bus->settings = *s->settings;
    k->bus->restarts = *s->restarts;
}

static void settle_nothing(struct bus *b)
{
    (void)b;
}

static void take_start(struct rank *k, void *arg)
{
    struct start *s = arg;
    s->step = k->bus->step;
    if (s->step == AO_SHARE_PASS) {
        *s->settings = k->bus->settings;
        *s->restarts = k->bus->restarts;
    }
}

static enum ao_share_step begin(void *user, enum ao_share_step step, struct ao_settings *settings, uint64_t *restarts)
{
    struct start s = {step, settings, restarts};
    rendezvous(user, bring_start, settle_nothing, take_start, &s);
    return s.step;
}

/* ---- combine and add_up ---- */

static void bring_tally(struct rank *k, void *arg)
{
    k->bus->in[k->rank].tally = *(struct ao_share_tally *)arg;
}

static void settle_tally(struct bus *b)
{
    memset(&b->tally, 0, sizeof b->tally);
    for (int r = 0; r < b->ranks; r++) {
        if (b->drop && r == 1)
            continue;
        const struct ao_share_tally *t = &b->in[r].tally;
        for (int j = 0; j < AO_TALLY_EXACT; j++)
            ao_sum_merge(&b->tally.exact[j], &t->exact[j]);
        for (int j = 0; j < AO_TALLY_TOTAL; j++)
            b->tally.total[j] += t->total[j];
        for (int j = 0; j < AO_TALLY_MOST; j++)
            b->tally.most[j] = fmax(b->tally.most[j], t->most[j]);
    }
}

static void take_tally(struct rank *k, void *arg)
{
    *(struct ao_share_tally *)arg = k->bus->tally;
}

static bool combine(void *user, struct ao_share_tally *tally)
{
    rendezvous(user, bring_tally, settle_tally, take_tally, tally);
    return true;
}

struct values {
    uint64_t *values;
    int count;
};

static void bring_values(struct rank *k, void *arg)
{
    struct values *v = arg;
    assert_true(v->count <= MOST_VALUES);
    memcpy(k->bus->in[k->rank].values, v->values, (size_t)v->count * sizeof *v->values);
    k->bus->in[k->rank].count = v->count;
}

static void settle_values(struct bus *b)
{
    memset(b->values, 0, sizeof b->values);
    for (int r = 0; r < b->ranks; r++)
        for (int j = 0; j < b->in[r].count; j++)
            b->values[j] += b->in[r].values[j];
}

static void take_values(struct rank *k, void *arg)
{
    struct values *v = arg;
    memcpy(v->values, k->bus->values, (size_t)v->count * sizeof *v->values);
}

static bool add_up(void *user, uint64_t *values, int count)
{
    struct values v = {values, count};
    rendezvous(user, bring_values, settle_values, take_values, &v);
    return true;
}

/* ---- gather: rank r's records are tiles r, r + N, r + 2N, ... ---- */

struct records {
    const void *mine;
    int count;
    size_t size;
    void *all;
};

static void bring_records(struct rank *k, void *arg)
{
    struct records *g = arg;
    k->bus->in[k->rank].records = g->mine;
    k->bus->in[k->rank].count = g->count;
    if (k->rank == 0) {
        k->bus->all = g->all;
        k->bus->size = g->size;
    }
}

static void settle_records(struct bus *b)
{
    for (int r = 0; r < b->ranks; r++)
        for (int n = 0; n < b->in[r].count && !(b->drop && r == 1); n++)
            memcpy((unsigned char *)b->all + (size_t)(r + n * b->ranks) * b->size,
                   (const unsigned char *)b->in[r].records + (size_t)n * b->size, b->size);
}

static void take_nothing(struct rank *k, void *arg)
{
    (void)k, (void)arg;
}

static bool gather(void *user, const void *mine, int count, size_t size, void *all, int tiles)
{
    (void)tiles;
    struct records g = {mine, count, size, all};
    rendezvous(user, bring_records, settle_records, take_nothing, &g);
    return true;
}

static bool owns(void *user, int tile, int tiles)
{
    (void)tiles;
    struct rank *k = user;
    return tile % k->bus->ranks == k->rank;
}

/* A frame is due at every third pass, so that gathers come mid-run too. */
static bool due(void *user)
{
    struct rank *k = user;
    return ++k->dues % 3 == 0;
}

static void end(void *user)
{
    struct rank *k = user;
    if (k->rank != 0)
        return;
    struct ao_settings settings;
    memset(&settings, 0, sizeof settings);
    uint64_t restarts = 0;
    begin(k, AO_SHARE_END, &settings, &restarts);
}

/* ---- loans: a borrower takes one entry at a time from another rank's open pass ---- */

/* Lock held: this rank's pass is pass from now on (its first poll), open to lend. */
static void open_pass(struct rank *k, const struct ao_share_pass *pass)
{
    struct bus *b = k->bus;
    if (b->loans[k->rank].serial == pass->serial)
        return;
    b->loans[k->rank].serial = pass->serial;
    b->loans[k->rank].pass = pass;
    b->loans[k->rank].open = true;
}

/* Lock held: one entry of this rank's whose sums came back, into arrived (else left empty). */
static void report(struct rank *k, int arrived[2])
{
    struct bus *b = k->bus;
    if (b->loans[k->rank].returns == 0)
        return;
    int n = b->loans[k->rank].returned[--b->loans[k->rank].returns];
    arrived[0] = n;
    arrived[1] = n + 1;
}

/* Before each tile: the last rank is slowed by 1 ms a tile, so that the others borrow from it. */
static bool poll(void *user, const struct ao_share_pass *pass, int arrived[2])
{
    struct rank *k = user;
    pthread_mutex_lock(&k->bus->lock);
    open_pass(k, pass);
    report(k, arrived);
    bool going = k->bus->given_up != pass->serial;
    pthread_mutex_unlock(&k->bus->lock);
    if (k->rank == k->bus->ranks - 1)
        nanosleep(&(struct timespec){.tv_nsec = 1000000}, NULL);
    return going;
}

static bool borrow(void *user, const struct ao_share_pass *pass, struct ao_share_loan *loan)
{
    struct rank *k = user;
    struct bus *b = k->bus;
    pthread_mutex_lock(&b->lock);
    bool lent = false;
    for (int v = 1; v < b->ranks && !lent && b->given_up != pass->serial; v++) {
        int owner = (k->rank + v) % b->ranks, first;
        const struct ao_share_pass *theirs = b->loans[owner].pass;
        if (b->loans[owner].serial != pass->serial || !b->loans[owner].open)
            continue;
        lent = theirs->lend(theirs->renderer, 1, &first, &loan->tile, &loan->work) == 1;
        if (lent) {
            b->loans_made++;
            b->loans[owner].outstanding++;
            loan->sums = theirs->sums + (size_t)first * (size_t)theirs->pixels;
            loan->ticket = owner * RETURNED + first;
        }
    }
    pthread_mutex_unlock(&b->lock);
    return lent;
}

static void repay(void *user, const struct ao_share_pass *pass, const struct ao_share_loan *loan)
{
    (void)pass;
    struct bus *b = ((struct rank *)user)->bus;
    pthread_mutex_lock(&b->lock);
    int owner = loan->ticket / RETURNED;
    b->loans[owner].outstanding--;
    b->loans[owner].returned[b->loans[owner].returns++] = loan->ticket % RETURNED;
    pthread_cond_broadcast(&b->changed);
    pthread_mutex_unlock(&b->lock);
}

static bool settle(void *user, const struct ao_share_pass *pass, bool finished, int arrived[2])
{
    struct rank *k = user;
    struct bus *b = k->bus;
    pthread_mutex_lock(&b->lock);
    open_pass(k, pass);
    b->loans[k->rank].open = false;
    if (!finished)
        b->given_up = pass->serial;
    while (b->loans[k->rank].returns == 0 && b->loans[k->rank].outstanding > 0)
        pthread_cond_wait(&b->changed, &b->lock);
    report(k, arrived);
    pthread_mutex_unlock(&b->lock);
    return true;
}

/* ---- the test ---- */

/* What the passes say, the leader's or one process's. */
struct passes {
    int count;
    struct ao_frame_info info[MOST_PASSES];
};

static void record_pass(const struct ao_frame_info *info, void *user)
{
    struct passes *p = user;
    assert_true(p->count < MOST_PASSES);
    p->info[p->count++] = *info;
}

/* Renders with config and settings on `ranks` ranks (0: one process, no share) until rank 0 is
 * done; returns a malloc'd copy of its last frame, the passes in *passes. */
static float *render(struct ao_render_config config, const struct ao_settings *settings, int ranks, bool drop,
                     struct passes *passes, int *loans)
{
    struct bus b = {.ranks = ranks, .drop = drop};
    pthread_mutex_init(&b.lock, NULL);
    pthread_cond_init(&b.changed, NULL);
    struct rank k[MOST_RANKS];
    struct ao_render *render[MOST_RANKS];
    for (int r = 0; r < (ranks ? ranks : 1); r++) {
        k[r] = (struct rank){.share = {.begin = begin, .owns = owns, .poll = poll, .borrow = borrow, .repay = repay,
                                       .settle = settle, .combine = combine, .add_up = add_up, .due = due,
                                       .gather = gather, .end = end, .follows = r != 0, .user = &k[r]},
                             .bus = &b, .rank = r};
        config.share = ranks ? &k[r].share : NULL;
        config.on_pass = r == 0 ? record_pass : NULL;
        config.user = passes;
        render[r] = ao_render_create(&config, settings);
        assert_non_null(render[r]);
    }
    assert_true(ao_render_wait(render[0]));
    const struct ao_frame *frame = ao_render_take_frame(render[0]);
    assert_non_null(frame);
    size_t bytes = 3 * sizeof(float) * (size_t)settings->width * (size_t)settings->height;
    float *copy = malloc(bytes);
    assert_non_null(copy);
    memcpy(copy, frame->rgb, bytes);
    for (int r = 0; r < (ranks ? ranks : 1); r++) /* rank 0 first: its end ends the others' runs */
        ao_render_destroy(render[r]);
    pthread_cond_destroy(&b.changed);
    pthread_mutex_destroy(&b.lock);
    *loans = b.loans_made;
    return copy;
}

/* Whether two runs' passes say the same but for the seconds. */
static bool same_passes(const struct passes *a, const struct passes *b)
{
    if (a->count != b->count)
        return false;
    for (int n = 0; n < a->count; n++) {
        struct ao_frame_info x = a->info[n], y = b->info[n];
        x.seconds = y.seconds = 0.0;
        if (memcmp(&x, &y, sizeof x) != 0)
            return false;
    }
    return true;
}

/* 2 and 3 ranks of 1 thread against one process of 2, adaptive sampling and auto passes, a target
 * error and a reference (a grey image): the image and every pass's facts the same bits, with tiles
 * lent by the slowed rank; and the broken share (rank 1's tally and records lost) differs in both. */
static void test_ranks_render_one_process_image(void **state)
{
    (void)state;
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, SCENE, "share.scene", NULL));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    assert_non_null(tracer);
    struct ao_settings settings = {.width = 72, .height = 40, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .adaptive = true, .camera = scene.camera};
    static float grey[3 * 72 * 40];
    for (size_t n = 0; n < sizeof grey / sizeof grey[0]; n++)
        grey[n] = 0.5f;
    struct ao_render_config config = {.scene = &scene, .tracer = tracer, .threads = 2, .seed = 11,
                                      .target_spp = 256, .target_error = 0.03, .ao_distance = INFINITY,
                                      .reference = grey, .reference_width = 72, .reference_height = 40};
    static struct passes one, many;
    int loans;
    float *expected = render(config, &settings, 0, false, &one, &loans);
    assert_true(one.count > 3);
    assert_true(one.info[one.count - 1].done);
    config.threads = 1;
    size_t bytes = sizeof grey;
    for (int ranks = 2; ranks <= 3; ranks++) {
        for (int drop = 0; drop <= 1; drop++) {
            memset(&many, 0, sizeof many);
            float *image = render(config, &settings, ranks, drop, &many, &loans);
            if (drop) {
                assert_true(memcmp(image, expected, bytes) != 0);
                assert_false(same_passes(&one, &many));
            } else {
                assert_memory_equal(image, expected, bytes);
                assert_true(same_passes(&one, &many));
                assert_true(loans > 0);
            }
            free(image);
        }
    }
    free(expected);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ranks_render_one_process_image),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
