/* aoview-mpi: `mpirun -np N aoview-mpi [aoview's options] SCENE` renders aoview's image on N
 * ranks: each loads the scene and traces the tiles it claims from rank 0, which gathers every
 * pass's sums, and shows the window (its keys and mouse set every rank's passes) or, headless,
 * writes -o; and --stats and the progress bar. */
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "app.h"
#include "cli.h"
#include "cluster.h"
#include "config.h"
#include "image.h"
#include "window.h"

/* How long rank 0 waits for the other ranks to answer after an interruption: mpirun sends SIGTERM
 * to every rank at once and SIGKILL a second later, and a PNG takes about 0.5 s to write. The
 * other ranks then wait up to LINGER_SECONDS for that SIGKILL: mpirun kills at once what is left
 * of a job whose other ranks have all ended. */
static const double ANSWER_SECONDS = 0.2;
enum { LINGER_SECONDS = 5 };

/* Whether the user watches stderr on a terminal: mpirun hands its ranks a pipe for stderr (and a
 * terminal for stdout, always), so rank 0 also asks about its parent's, which is mpirun's when
 * rank 0 runs on mpirun's machine. */
static bool watched_on_terminal(void)
{
    if (isatty(STDERR_FILENO))
        return true;
    char path[64];
    snprintf(path, sizeof path, "/proc/%ld/fd/2", (long)getppid());
    int fd = open(path, O_WRONLY | O_NOCTTY);
    bool terminal = fd >= 0 && isatty(fd);
    if (fd >= 0)
        close(fd);
    return terminal;
}

/* Parses argv on every rank; 0, or the exit status after one message (from rank 0, or from a rank
 * whose options alone fail). */
static int parse(int argc, char **argv, int rank, struct ao_options *opts)
{
    char message[512];
    bool parsed = ao_cli_parse(argc, argv, opts, message, sizeof message);
    for (int k = 1; k < argc; k++) /* before the parser's own complaints about it */
        if (strcmp(argv[k], "--compare") == 0) {
            snprintf(message, sizeof message, "--compare: not available in aoview-mpi");
            parsed = false;
        }
    bool first_parsed = ao_cluster_agree(rank == 0 ? parsed : true);
    if (ao_cluster_agree(parsed))
        return 0;
    if (!parsed && (rank == 0 || first_parsed))
        fprintf(stderr, "aoview-mpi: %s (try --help)\n", message);
    return AO_EXIT_USAGE;
}

/* FNV-1a over size bytes, continuing from hash. */
static uint64_t fnv(uint64_t hash, const void *data, size_t size)
{
    const unsigned char *bytes = data;
    for (size_t k = 0; k < size; k++)
        hash = (hash ^ bytes[k]) * 0x100000001b3u;
    return hash;
}

/* A fingerprint of what the image depends on: the render config and settings but the threads, and
 * the scene's geometry, so that ranks given other options or other files are caught. */
static uint64_t fingerprint(const struct ao_render_config *c, const struct ao_settings *s, const struct ao_scene *scene)
{
    double numbers[] = {s->width, s->height, (double)c->seed, c->target_spp, c->target_error, c->time_limit,
                        c->ao_distance, c->sequence, c->below, s->sampling, s->aa, s->spppp, s->adaptive,
                        s->output, s->shading, scene->background.x, scene->background.y, scene->background.z,
                        (double)scene->sphere_count, (double)scene->triangle_count};
    uint64_t hash = fnv(0xcbf29ce484222325u, numbers, sizeof numbers);
    hash = fnv(hash, &s->camera, sizeof s->camera);
    hash = fnv(hash, scene->positions, scene->vertex_count * sizeof *scene->positions);
    return fnv(hash, scene->indices, 3 * scene->triangle_count * sizeof *scene->indices);
}

/* Writes what was held in `held` (see load) to stderr and closes it. */
static void release(FILE *held, bool say)
{
    char buffer[4096];
    size_t n;
    rewind(held);
    while (say && (n = fread(buffer, 1, sizeof buffer, held)) > 0)
        fwrite(buffer, 1, n, stderr);
    fclose(held);
}

/* Loads the scene and the rest on every rank at once; a rank other than 0 holds back what it says
 * (its stderr goes to a temporary file) and says it only if rank 0 loaded, so that a file missing
 * everywhere is reported once; 0 when every rank has it. */
static int load(struct ao_app *app, const struct ao_options *opts, int rank, struct ao_render_config *config,
                struct ao_settings *settings)
{
    FILE *held = rank == 0 ? NULL : tmpfile();
    int saved = held ? dup(STDERR_FILENO) : -1;
    if (saved >= 0)
        dup2(fileno(held), STDERR_FILENO);
    int status = ao_app_load(app, opts, config, settings);
    if (saved >= 0) {
        dup2(saved, STDERR_FILENO);
        close(saved);
    }
    bool first_loaded = ao_cluster_agree(rank != 0 || status == 0);
    if (held)
        release(held, first_loaded);
    if (!ao_cluster_agree(status == 0))
        return AO_EXIT_RUNTIME;
    if (ao_cluster_same(fingerprint(config, settings, &app->scene)))
        return 0;
    if (rank == 0)
        fprintf(stderr, "aoview-mpi: the ranks were given different options or scene files (only --threads, -o, "
                        "--stats, --reference and -q may differ)\n");
    return AO_EXIT_USAGE;
}

/* After an interruption: the other ranks tell rank 0 they are alive and by which signal; rank 0
 * names those that did not answer (lost: killed or crashed, which made mpirun stop the job), or
 * the rank interrupted while rank 0 was not (a signal to that rank alone, which stopped rank 0's
 * cluster), and writes the image of the last merged pass, the newest frame published (the render
 * thread may be in a tile for long: mpirun's SIGKILL does not wait for it; its --stats row is
 * written). sig: rank 0's own signal, 0 when it has none (yet). */
static int interrupted(struct ao_app *app, struct ao_cluster *cluster, const struct ao_options *opts, int rank,
                       int sig)
{
    if (rank != 0) {
        ao_cluster_answer(cluster, sig);
        sleep(LINGER_SECONDS);
        return 128 + sig;
    }
    char missing[256], why[320];
    ao_cluster_missing(cluster, ANSWER_SECONDS, missing, sizeof missing);
    int alone_sig, alone = ao_cluster_interrupted(cluster, &alone_sig);
    if (!sig) /* mpirun's SIGTERM to every rank may reach rank 0 after another rank's answer */
        sig = atomic_load(&app->interrupt.caught);
    int status = missing[0] ? AO_EXIT_RUNTIME : 128 + sig;
    if (!sig && alone > 0) {
        snprintf(why, sizeof why, "rank %d interrupted by %s, stopped", alone, ao_app_signal_name(alone_sig));
        status = alone_sig > 0 ? 128 + alone_sig : AO_EXIT_RUNTIME;
    } else if (missing[0]) {
        snprintf(why, sizeof why, "rank %s lost (killed or crashed), stopped", missing);
    } else {
        snprintf(why, sizeof why, "interrupted by %s", ao_app_signal_name(sig));
    }
    const struct ao_frame *frame = ao_render_take_frame(app->render);
    if (!frame)
        fprintf(stderr, "\naoview: %s before the first pass was merged: nothing written\n", why);
    return ao_app_write(app, opts, frame, why, false, !frame ? AO_EXIT_RUNTIME : status);
}

/* Rank 0: shows the window until the user quits; false where no window can be opened (after one
 * line: the run goes on headless, with the progress bar), *status AO_EXIT_RUNTIME when OpenGL
 * failed. */
static bool show_window(struct ao_app *app, const struct ao_options *opts, int *status)
{
    /* No config: V, which would start renderers of its own, is not available. */
    struct ao_window_info info = {.scene_name = app->scene.name, .quiet = opts->quiet, .seed = opts->seed,
                                  .save_exr = opts->save_exr, .reference = app->reference,
                                  .reference_width = app->reference_width,
                                  .reference_height = app->reference_height, .pixel_size = opts->pixel_size,
                                  .difference = opts->view == AO_VIEW_MODE_DIFFERENCE};
    if (ao_app_run_window(app, opts, &info, status))
        return true;
    app->reporter.progress = !opts->quiet && watched_on_terminal();
    return false;
}

/* Renders on every rank; rank 0 shows the window or writes. Returns the exit status; *clean says
 * whether every rank got to the end alike (MPI may then be finalized). */
static int run(struct ao_app *app, const struct ao_options *opts, int rank, bool *clean)
{
    struct ao_options mine = *opts;
    if (rank != 0) /* only rank 0 shows, reports and writes */
        mine.quiet = mine.headless = true, mine.stats_path = NULL, mine.reference_path = NULL, mine.output = NULL;
    struct ao_render_config config;
    struct ao_settings settings;
    /* Rank 0's -o before loading, so that a run never renders for nothing. */
    if (!ao_cluster_agree(rank != 0 || !mine.headless || ao_image_check_output(mine.output ? mine.output : "aoview.png")))
        return AO_EXIT_RUNTIME;
    int status = load(app, &mine, rank, &config, &settings);
    if (status)
        return status;
    app->reporter.progress = !mine.quiet && mine.headless && watched_on_terminal();
    app->reporter.notify = ao_window_notify;
    struct ao_cluster *cluster = ao_cluster_create();
    if (!cluster)
        return AO_EXIT_RUNTIME;
    config.share = ao_cluster_share(cluster);
    app->render = ao_render_create(&config, &settings);
    if (!ao_cluster_agree(app->render != NULL)) {
        ao_cluster_destroy(cluster);
        return AO_EXIT_RUNTIME;
    }
    ao_app_watch(app, app->render);

    /* Rank 0's window, or headless (also where no window can be opened): the other ranks follow
     * rank 0's passes until its render thread ends theirs. */
    bool shown = !mine.headless && show_window(app, &mine, &status);
    if (!shown) {
        atomic_store(&app->interrupt.graceful, true);
        int sig;
        bool finished = ao_app_wait(app, &sig);
        if (!finished && (sig || rank == 0)) {
            *clean = false;
            ao_cluster_stop(cluster);
            bool alone = rank == 0 && ao_cluster_interrupted(cluster, NULL) > 0;
            return sig || alone ? interrupted(app, cluster, &mine, rank, sig) : AO_EXIT_RUNTIME;
        }
    }
    if (rank == 0)
        ao_render_stop(app->render);
    char summary[1024];
    ao_cluster_summary(cluster, summary, sizeof summary);
    if (rank == 0 && !mine.quiet)
        fprintf(stderr, "aoview-mpi: %s\n", summary);
    if (rank == 0 && !shown)
        status = ao_app_write(app, &mine, ao_render_take_frame(app->render), NULL, false, 0);
    ao_render_destroy(app->render);   /* before the cluster, which its render thread may still use */
    app->render = NULL;
    ao_cluster_destroy(cluster);
    return status;
}

int main(int argc, char **argv)
{
    /* Before MPI starts its threads, so that they all inherit the mask. */
    struct ao_app app = {0};
    if (!ao_app_begin())
        return AO_EXIT_RUNTIME;
    ao_app_block_signals(&app);
    int rank, size;
    if (!ao_cluster_init(&argc, &argv, &rank, &size))
        return AO_EXIT_RUNTIME;
    struct ao_options opts;
    int status = parse(argc, argv, rank, &opts);
    if (status || opts.help || opts.version) {
        if (!status && rank == 0 && !ao_app_print(opts.help ? ao_cli_usage() : "aoview-mpi " AO_VERSION "\n"))
            status = AO_EXIT_RUNTIME;
        ao_cluster_finalize();
        return status;
    }
    if (!ao_cluster_agree(ao_app_start_watcher(&app, rank != 0))) {
        ao_cluster_finalize();
        return AO_EXIT_RUNTIME;
    }
    bool clean = true;
    status = ao_app_finish(&app, run(&app, &opts, rank, &clean));
    if (clean)
        ao_cluster_finalize();
    return status;
}
