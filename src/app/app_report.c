/* The --stats rows and the progress bar; see app_report.h. */
#include "app_report.h"

#include <math.h>
#include <sys/stat.h>
#include <unistd.h>

#include "clock.h"
#include "file.h"
#include "render.h"
#include "text.h"

/* The headless progress bar redraws at most this often (and once more at the end). */
static const double BAR_SECONDS = 0.1;

double ao_app_mrays_per_second(const struct ao_frame_info *info)
{
    return info->seconds > 0.0 ? (double)(info->eye_rays + info->shadow_rays) / info->seconds / 1e6 : 0.0;
}

/* Redraws the progress bar: filled, and its percentage, by the share of the run done
 * (ao_progress_share: never back, full only once done), the samples (ao_progress_format_spp), the
 * error ("--" while not known), the seconds, the time left and the rate, the normals view without
 * the AO estimate's error, time left and rate (as the window's status); at most every
 * BAR_SECONDS, and at the end. */
static void draw_bar(struct ao_reporter *rep, const struct ao_frame_info *info)
{
    ao_progress_add(&rep->eta, info);
    double share = ao_progress_share(&rep->eta, info), now = ao_clock_seconds();
    if (!info->done && rep->drawn_at > 0.0 && now - rep->drawn_at < BAR_SECONDS)
        return;
    rep->drawn_at = now;
    int filled = (int)(30.0 * share);
    char spp[64], figures[128] = "";
    ao_progress_format_spp(info, spp, sizeof spp);
    if (info->output != AO_OUTPUT_NORMALS) {
        char left[32], error[32] = "--";
        ao_progress_format(ao_progress_left(&rep->eta, info), left, sizeof left);
        if (!isnan(info->error))
            snprintf(error, sizeof error, "%.2f %%", 100.0 * info->error);
        snprintf(figures, sizeof figures, "  error %s  %.1f s  %s  %.1f Mrays/s", error, info->seconds, left,
                 ao_app_mrays_per_second(info));
    } else {
        snprintf(figures, sizeof figures, "  %.1f s", info->seconds);
    }
    fprintf(stderr, "\r[%.*s%*s] %3d %%  %s%s \033[K", filled, "##############################", 30 - filled, "",
            (int)(100.0 * share), spp, figures);
    if (info->done)
        fputc('\n', stderr);
}

/* Says once that writing --stats failed. */
static void stats_failed(struct ao_stats *st)
{
    char name[AO_TEXT_SIZE];
    if (!st->failed)
        fprintf(stderr, "%s: write failed\n", ao_text_escape(st->path, name, sizeof name));
    st->failed = true;
}

/* Before the first row: empties a regular file (a FIFO or device has nothing to empty) and writes
 * the header. */
static void start_stats(struct ao_stats *st)
{
    struct stat status;
    int fd = fileno(st->file);
    if (fstat(fd, &status) != 0 || (S_ISREG(status.st_mode) && ftruncate(fd, 0) != 0) ||
        fputs(st->header, st->file) < 0)
        stats_failed(st);
}

bool ao_app_open_stats(struct ao_stats *st, const char *path, bool sides, bool rmse)
{
    bool created;
    if (!(st->file = ao_file_open_output(path, "--stats", &created)))
        return false;
    st->path = path;
    atomic_store(&st->created, created);
    snprintf(st->header, sizeof st->header,
             "%spass,spp,seconds,eye_rays,shadow_rays,mrays_per_s%s,mean_spp,error,converged\n",
             sides ? "side," : "", rmse ? ",rmse" : "");
    return true;
}

bool ao_app_close_stats(struct ao_stats *st)
{
    if (st->file && fclose(st->file) != 0)
        stats_failed(st);
    if (st->file && atomic_load(&st->created) && !atomic_load(&st->wrote))   /* none, or none whole: a full disk */
        unlink(st->path);
    st->file = NULL;
    return !st->failed;
}

void ao_app_on_pass(const struct ao_frame_info *info, void *user)
{
    struct ao_reporter *rep = user;
    struct ao_stats *st = rep->stats;
    if (st && !atomic_exchange(&st->started, true))
        start_stats(st);
    if (st && !st->failed) {
        if (rep->side)
            fprintf(st->file, "%s,", rep->side);
        fprintf(st->file, "%u,%u,%.6f,%llu,%llu,%.3f", info->pass, info->spp, info->seconds,
                (unsigned long long)info->eye_rays, (unsigned long long)info->shadow_rays,
                ao_app_mrays_per_second(info));
        if (!isnan(info->rmse))
            fprintf(st->file, ",%.9g", info->rmse);
        fprintf(st->file, ",%.3f,%.6g,%.4f\n", info->mean_spp, info->error, info->converged);
        if (fflush(st->file) != 0)
            stats_failed(st);
        else
            atomic_store(&st->wrote, true);
    }
    if (rep->progress)
        draw_bar(rep, info);
    /* Equal time: end the side at the pass end nearest stop_at, taking the next pass to last as
     * long as this one (time_limit ends it at the first end past stop_at otherwise). */
    struct ao_render *render = atomic_load(&rep->render);
    if (render && rep->stop_at > 0.0 && !info->done &&
        info->seconds + 0.5 * (info->seconds - rep->pass_end) >= rep->stop_at)
        ao_render_stop(render);
    rep->pass_end = info->seconds;
    if (rep->notify)
        rep->notify();
}

void ao_app_on_preview(const struct ao_frame_info *info, void *user)
{
    (void)info;
    struct ao_reporter *rep = user;
    if (rep->notify)
        rep->notify();
}
