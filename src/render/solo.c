/* The solo share: one process renders every tile, so the run share's hooks (pass.h) have nothing
 * to begin, combine or gather; see render_share.h. */
#include "render_share.h"

#include <math.h>

static bool restart(struct ao_run_share *s, int tiles)
{
    (void)s, (void)tiles;
    return true;
}

static bool owns(const struct ao_run_share *s, int tile)
{
    (void)s, (void)tile;
    return true;
}

static bool add_up(struct ao_run_share *s, uint64_t *values, int count)
{
    (void)s, (void)values, (void)count;
    return true;
}

static double waited(struct ao_run_share *s)
{
    (void)s;
    return 0.0;
}

static bool combine(struct ao_run_share *s, struct ao_share_tally *tally)
{
    (void)s, (void)tally;
    return true;
}

static bool begin(struct ao_run_share *s, struct ao_run *run, struct ao_pass_start *p,
                  const struct ao_frame_info *info)
{
    (void)s, (void)run, (void)p, (void)info;
    return true;
}

static bool begun(const struct ao_run_share *s)
{
    (void)s;
    return false;
}

static bool run_pass(struct ao_run_share *s, struct ao_run *run)
{
    (void)s;
    return ao_pass_run(run);
}

/* Every pass is published and reported. */
static bool publish(struct ao_run_share *s, struct ao_run *run, const struct ao_settings *settings,
                    const struct ao_frame_info *info, bool *ending)
{
    (void)s, (void)settings, (void)ending;
    if (!ao_pass_publish(run, info))
        return false;
    if (run->config.on_pass)
        run->config.on_pass(info, run->config.user);
    return true;
}

static bool rest(struct ao_run_share *s, struct ao_run *run, const struct ao_settings *settings,
                 const struct ao_frame_info *info, bool finishes, uint64_t own)
{
    (void)s, (void)run, (void)settings, (void)info, (void)finishes, (void)own;
    return true;
}

/* The RMSE of count values of image against reference. */
static double rmse(const float *image, const float *reference, size_t count)
{
    double sum = 0.0;
    for (size_t k = 0; k < count; k++) {
        double d = (double)image[k] - (double)reference[k];
        sum += d * d;
    }
    return sqrt(sum / (double)count);
}

/* The accumulation resolved, a tile not traced in this run cleared, its spp, mean spp and RMSE
 * counted from the pixels. */
static struct ao_frame *stopped(struct ao_run_share *s, struct ao_run *run, const struct ao_frame_info *info)
{
    (void)s;
    for (int t = 0; t < run->tiles_x * run->tiles_y; t++)
        if (run->tiles[t].passes == 0) /* not traced in this run: sums of an earlier one */
            ao_pass_clear_tile(run, t);
    struct ao_frame *f = ao_pass_resolve(run, info);
    if (!f)
        return NULL;
    size_t pixels = (size_t)f->width * (size_t)f->height;
    uint32_t most = 0;
    uint64_t samples = 0;
    for (size_t p = 0; p < pixels; p++) {
        most = run->accum.count[p] > most ? run->accum.count[p] : most;
        samples += run->accum.count[p];
    }
    f->info.spp = most;
    f->info.mean_spp = (double)samples / (double)pixels;
    f->info.done = false;
    f->info.rmse = ao_pass_has_reference(run) ? rmse(f->rgb, run->config.reference, 3 * pixels) : NAN;
    return f;
}

static void nothing(struct ao_run_share *s)
{
    (void)s;
}

static struct ao_run_share solo = {.restart = restart, .owns = owns, .add_up = add_up, .waited = waited,
                                   .combine = combine, .begin = begin, .begun = begun, .run = run_pass,
                                   .publish = publish, .rest = rest, .stopped = stopped, .end = nothing,
                                   .destroy = nothing};

struct ao_run_share *ao_solo_share(void)
{
    return &solo;
}
