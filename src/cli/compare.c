/* The live equal-time comparison (see compare.h): two renderers of one scene taking turns pass by
 * pass, their settings kept alike but for each side's configuration, their frames and charts; and
 * the pure pieces its views use (labels, layouts, composing the two images). */
#include "compare.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "sampling.h"
#include "text.h"

/* One side: its renderer and configuration, what the turns know of its current run, and what the
 * window shows of it. */
struct side {
    struct ao_compare *compare;
    struct ao_render *render;
    struct ao_compare_side config;
    void *user;                      /* config.on_pass's argument for this side */

    /* The turns, under the comparison's lock. */
    uint64_t run;                    /* ao_frame_info.restarts of the last pass counted */
    bool stale;                      /* both sides were restarted: until this one's passes show a
                                        new run, they are the old run's */
    double seconds;                  /* render seconds of the current run, as of its last pass */
    double pass;                     /* the last pass's seconds */
    bool done;

    /* The window's thread only. */
    const struct ao_frame *shown;
    struct ao_chart chart;
};

struct ao_compare {
    pthread_mutex_t lock;
    struct ao_settings settings;     /* as the user set them: A's sampling and AA, the user's pause */
    void (*on_pass)(const struct ao_frame_info *info, void *user);
    bool closing;                    /* ao_compare_destroy has begun: passes no longer hand turns on */
    struct side sides[2];
};

/* Which side renders now, or -1: the one with fewer render seconds in its run; once one side is
 * done, the other until its pass end nearest the finished side's seconds (taking its next pass to
 * last as long as its last one), so that the two end within half a pass of each other. */
static int turn(const struct ao_compare *c)
{
    const struct side *a = &c->sides[0], *b = &c->sides[1];
    if (c->settings.paused || (a->done && b->done))
        return -1;
    if (!a->done && !b->done)
        return b->seconds < a->seconds ? 1 : 0;
    const struct side *behind = a->done ? b : a, *finished = a->done ? a : b;
    return behind->seconds + 0.5 * behind->pass < finished->seconds ? (int)(behind - c->sides) : -1;
}

/* Hands side k the user's settings with its own sampling and AA, paused unless it is its turn;
 * true when that restarted it. Called with the lock held. */
static bool apply(struct ao_compare *c, int k, int running)
{
    struct ao_settings s = c->settings;
    s.sampling = c->sides[k].config.sampling;
    s.aa = c->sides[k].config.aa;
    s.paused = running != k;
    s.previews = false; /* both sides show full passes of the same size */
    return ao_render_set_settings(c->sides[k].render, &s);
}

/* Hands the turn to the side whose turn it is. Called with the lock held. */
static void apply_turn(struct ao_compare *c)
{
    int running = turn(c);
    apply(c, 0, running);
    apply(c, 1, running);
}

/* Restarts both sides (those that the settings did not restart already) and starts their turns
 * over, A first. Called with the lock held. */
static void start_over(struct ao_compare *c, bool a_restarted, bool b_restarted)
{
    if (!a_restarted)
        ao_render_restart(c->sides[0].render);
    if (!b_restarted)
        ao_render_restart(c->sides[1].render);
    for (int k = 0; k < 2; k++) {
        struct side *side = &c->sides[k];
        side->stale = true;
        side->seconds = side->pass = 0.0;
        side->done = false;
    }
    apply_turn(c);
}

/* config.on_pass of each side, on its render thread: counts the pass towards its run, hands the
 * turn on, then reports the pass to the caller's on_pass. */
static void on_pass(const struct ao_frame_info *info, void *user)
{
    struct side *side = user;
    struct ao_compare *c = side->compare;
    pthread_mutex_lock(&c->lock);
    /* After a restart, a pass of the old run (finished as the restart came) counts for nothing. */
    bool counts = info->restarts != side->run || !side->stale;
    side->run = info->restarts;
    side->stale = side->stale && !counts;
    if (counts && !c->closing) {
        side->pass = info->seconds - side->seconds;
        side->seconds = info->seconds;
        side->done = info->done;
        apply_turn(c);
    }
    if (c->on_pass)
        c->on_pass(info, side->user);
    pthread_mutex_unlock(&c->lock);
}

struct ao_compare *ao_compare_create(const struct ao_render_config *config, const struct ao_settings *settings,
                                     const struct ao_compare_side sides[2], void *const users[2])
{
    struct ao_compare *c = calloc(1, sizeof *c);
    if (!c) {
        ao_text_report("aoview: out of memory for the comparison");
        return NULL;
    }
    pthread_mutex_init(&c->lock, NULL);
    c->settings = *settings;
    c->settings.sampling = sides[0].sampling;
    c->settings.aa = sides[0].aa;
    c->on_pass = config->on_pass;
    /* Both start paused, so that no pass reports before both exist; then A takes the first turn. */
    for (int k = 0; k < 2; k++) {
        struct side *side = &c->sides[k];
        side->compare = c;
        side->config = sides[k];
        side->user = users[k];
        struct ao_render_config side_config = *config;
        side_config.sequence = sides[k].sequence;
        side_config.on_pass = on_pass;
        side_config.user = side;
        struct ao_settings s = *settings;
        s.sampling = sides[k].sampling;
        s.aa = sides[k].aa;
        s.paused = true;
        if (!(side->render = ao_render_create(&side_config, &s))) {
            ao_compare_destroy(c);
            return NULL;
        }
    }
    pthread_mutex_lock(&c->lock);
    apply_turn(c);
    pthread_mutex_unlock(&c->lock);
    return c;
}

void ao_compare_destroy(struct ao_compare *c)
{
    if (!c)
        return;
    /* A side's pass may hand the turn to the other at any time: no more of that, then neither
     * renderer is touched by the other's thread while it is taken down. */
    pthread_mutex_lock(&c->lock);
    c->closing = true;
    pthread_mutex_unlock(&c->lock);
    for (int k = 0; k < 2; k++)
        ao_render_destroy(c->sides[k].render);
    pthread_mutex_destroy(&c->lock);
    free(c);
}

void ao_compare_get_settings(struct ao_compare *c, struct ao_settings *out)
{
    pthread_mutex_lock(&c->lock);
    *out = c->settings;
    pthread_mutex_unlock(&c->lock);
}

void ao_compare_set_settings(struct ao_compare *c, const struct ao_settings *settings)
{
    pthread_mutex_lock(&c->lock);
    c->sides[0].config.sampling = settings->sampling;
    c->sides[0].config.aa = settings->aa;
    c->settings = *settings;
    int running = turn(c);
    bool a = apply(c, 0, running), b = apply(c, 1, running);
    if (a || b)
        start_over(c, a, b);
    pthread_mutex_unlock(&c->lock);
}

void ao_compare_restart(struct ao_compare *c)
{
    pthread_mutex_lock(&c->lock);
    start_over(c, false, false);
    pthread_mutex_unlock(&c->lock);
}

bool ao_compare_running(struct ao_compare *c)
{
    pthread_mutex_lock(&c->lock);
    bool running = turn(c) >= 0;
    pthread_mutex_unlock(&c->lock);
    return running;
}

bool ao_compare_take_frames(struct ao_compare *c)
{
    bool fresh = false;
    for (int k = 0; k < 2; k++) {
        const struct ao_frame *f = ao_render_take_frame(c->sides[k].render);
        if (f) {
            c->sides[k].shown = f;
            ao_chart_add(&c->sides[k].chart, &f->info);
            fresh = true;
        }
    }
    return fresh;
}

const struct ao_frame *ao_compare_frame(const struct ao_compare *c, int k)
{
    return c->sides[k].shown;
}

void ao_compare_chart(const struct ao_compare *c, struct ao_chart *out)
{
    out->count = 0;
    for (int k = 0; k < 2; k++) {
        const struct ao_chart *chart = &c->sides[k].chart;
        int keep = chart->count < AO_CHART_CURVES / 2 ? chart->count : AO_CHART_CURVES / 2;
        for (int i = chart->count - keep; i < chart->count; i++)
            out->curves[out->count++] = chart->curves[i];
    }
}

struct ao_compare_side ao_compare_partner(struct ao_compare_side current)
{
    current.sampling = current.sampling == AO_SAMPLING_COSINE ? AO_SAMPLING_UNIFORM : AO_SAMPLING_COSINE;
    return current;
}

void ao_compare_label(const char *name, const struct ao_compare_side *side, const struct ao_frame_info *info,
                      const char *separator, char *out, size_t size)
{
    char config[64], rmse[48] = "";
    ao_cli_side_name(side, config, sizeof config);
    if (!isnan(info->rmse))
        snprintf(rmse, sizeof rmse, "%sRMSE %.4g", separator, info->rmse);
    snprintf(out, size, "%s: %s%s%u spp  %.3g s%s", name, config, separator, info->spp, info->seconds, rmse);
}

void ao_compare_labels(struct ao_compare *c, const char *separator, char labels[2][AO_COMPARE_LABEL])
{
    static const char *const names[2] = {"A", "B"};
    for (int k = 0; k < 2; k++) {
        pthread_mutex_lock(&c->lock);
        struct ao_compare_side side = c->sides[k].config;
        pthread_mutex_unlock(&c->lock);
        ao_compare_label(names[k], &side, &c->sides[k].shown->info, separator, labels[k], AO_COMPARE_LABEL);
    }
}

void ao_compare_status(struct ao_compare *c, const char *scene, const char *separator, char *out, size_t size)
{
    char labels[2][AO_COMPARE_LABEL];
    ao_compare_labels(c, "  ", labels);
    pthread_mutex_lock(&c->lock);
    const char *state = c->settings.paused ? "paused" : turn(c) < 0 ? "finished" : NULL;
    pthread_mutex_unlock(&c->lock);
    snprintf(out, size, "%s%scompare%s%s%s%s%s%s", scene, separator, separator, labels[0], separator, labels[1],
             state ? separator : "", state ? state : "");
}

int ao_compare_width(enum ao_compare_layout layout, int width)
{
    return layout == AO_COMPARE_SIDE_BY_SIDE ? 2 * width : width;
}

void ao_compare_compose(enum ao_compare_layout layout, int split, const float *a, const float *b, int width,
                        int height, float *out)
{
    size_t row = 3 * (size_t)width;
    for (size_t y = 0; y < (size_t)height; y++) {
        const float *ra = a + y * row, *rb = b + y * row;
        if (layout == AO_COMPARE_SIDE_BY_SIDE) {
            memcpy(out + 2 * y * row, ra, row * sizeof *out);
            memcpy(out + (2 * y + 1) * row, rb, row * sizeof *out);
        } else {
            size_t left = 3 * (size_t)(split < 0 ? 0 : split > width ? width : split);
            memcpy(out + y * row, ra, left * sizeof *out);
            memcpy(out + y * row + left, rb + left, (row - left) * sizeof *out);
        }
    }
}
