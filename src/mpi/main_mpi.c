/* aoview-mpi: `mpirun -np N aoview-mpi [aoview's options] SCENE` renders aoview's image on N
 * ranks: each loads the scene and traces and keeps the tiles it owns; rank 0 leads (its window's
 * keys and mouse set every rank's passes), gathers the image when it shows or writes it, and
 * writes --stats and the progress bar from the few numbers the ranks combine after each pass. */
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "app_load.h"
#include "app_output.h"
#include "app_signals.h"
#include "cli.h"
#include "cluster.h"
#include "cluster_faults.h"
#include "config.h"
#include "image.h"
#include "program.h"
#include "window.h"

/* After an interruption rank 0 waits ANSWER_SECONDS for the other ranks to answer (mpirun sends
 * SIGTERM to every rank at once and SIGKILL a second later), then SALVAGE_SECONDS for their tiles
 * (each joins its render thread first), leaving half a second for a PNG (OSMesa and LLVM load at
 * the first); the others wait up to LINGER_SECONDS for rank 0's release with the run's status
 * (mpirun kills at once what is left of a job whose other ranks have all ended). A window is
 * gathered at most FRAME_SECONDS apart; headless, a safety copy every --safety-copy seconds. */
static const double ANSWER_SECONDS = 0.2, SALVAGE_SECONDS = 0.3, LINGER_SECONDS = 5.0, FRAME_SECONDS = 1.0 / 60.0,
                    SAFETY_COPY_SECONDS = 5.0;

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

/* Takes aoview-mpi's own option, --safety-copy SECONDS, out of argv into *seconds; false with the
 * message when its value is not a number of seconds >= 0. */
static bool take_own_options(int *argc, char **argv, double *seconds, char *message, size_t size)
{
    int kept = 1;
    bool ok = true;
    for (int k = 1; k < *argc; k++) {
        if (strcmp(argv[k], "--safety-copy") != 0) {
            argv[kept++] = argv[k];
            continue;
        }
        char *end = NULL;
        double value = k + 1 < *argc ? strtod(argv[k + 1], &end) : NAN;
        if (ok && k + 1 >= *argc) {
            snprintf(message, size, "--safety-copy: needs a number of seconds");
            ok = false;
        } else if (ok && (end == argv[k + 1] || *end || !(value >= 0.0) || isinf(value))) {
            snprintf(message, size, "--safety-copy: expected seconds >= 0, got '%s'", argv[k + 1]);
            ok = false;
        }
        *seconds = ok ? value : *seconds;
        k++;
    }
    argv[kept] = NULL;
    *argc = kept;
    return ok;
}

/* Parses argv on every rank (aoview's options and --safety-copy into *copy); 0, or the exit status
 * after one message (from rank 0, or from a rank whose options alone fail). Every rank takes rank
 * 0's scene budget, by default its machine's (budget.h), so that ranks on machines of other sizes
 * load the same scene (the budget decides what is instanced and which BVH is built). */
static int parse(int argc, char **argv, int rank, struct ao_options *opts, double *copy)
{
    char message[512];
    bool parsed = take_own_options(&argc, argv, copy, message, sizeof message) &&
                  ao_cli_parse(argc, argv, opts, message, sizeof message);
    for (int k = 1; k < argc; k++) /* before the parser's own complaints about it */
        if (strcmp(argv[k], "--compare") == 0) {
            snprintf(message, sizeof message, "--compare: not available in aoview-mpi");
            parsed = false;
        }
    bool first_parsed = ao_cluster_agree(rank == 0 ? parsed : true);
    if (ao_cluster_agree(parsed)) {
        opts->scene_budget = ao_cluster_first(opts->scene_budget);
        return 0;
    }
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

/* A digest of the loaded scene: everything in it that the image depends on (the camera, the ao
 * distance and the image size are the options' digest's, as the options may replace them). */
static uint64_t scene_digest(const struct ao_scene *scene)
{
    size_t counts[] = {scene->sphere_count, scene->mesh_count, scene->instance_count, scene->albedo_count};
    uint64_t hash = fnv(0xcbf29ce484222325u, counts, sizeof counts);
    hash = fnv(hash, &scene->background, sizeof scene->background);
    hash = fnv(hash, scene->spheres, scene->sphere_count * sizeof *scene->spheres);
    for (size_t i = 0; i < scene->mesh_count; i++) {   /* every unique mesh once */
        const struct ao_mesh *m = &scene->meshes[i];
        size_t sizes[] = {m->vertex_count, m->triangle_count};
        hash = fnv(hash, sizes, sizeof sizes);
        hash = fnv(hash, m->positions, m->vertex_count * sizeof *m->positions);
        hash = fnv(hash, m->normals, m->vertex_count * sizeof *m->normals);
        hash = fnv(hash, m->indices, 3 * m->triangle_count * sizeof *m->indices);
    }
    for (size_t i = 0; i < scene->instance_count; i++) {   /* field by field: no padding hashed */
        const struct ao_instance *in = &scene->instances[i];
        uint32_t ids[] = {in->mesh, in->albedo, in->flat};
        hash = fnv(hash, ids, sizeof ids);
        hash = fnv(hash, in->to_local, sizeof in->to_local);
        hash = fnv(hash, in->normals, sizeof in->normals);
        hash = fnv(hash, in->slack, sizeof in->slack);
    }
    return fnv(hash, scene->albedos, scene->albedo_count * sizeof *scene->albedos);
}

/* A digest of what the image and the --stats rows depend on besides the scene: the render config
 * and settings but the threads (the camera, ao distance and size included), and the reference's
 * pixels, from which every rank takes its tiles' share of the RMSE. */
static uint64_t options_digest(const struct ao_render_config *c, const struct ao_settings *s)
{
    double numbers[] = {s->width, s->height, (double)c->seed, c->target_spp, c->target_error, c->time_limit,
                        c->ao_distance, c->sequence, c->below, s->sampling, s->aa, s->spppp, s->adaptive,
                        s->output, s->shading, c->reference != NULL, c->reference_width, c->reference_height};
    uint64_t hash = fnv(0xcbf29ce484222325u, numbers, sizeof numbers);
    hash = fnv(hash, &s->camera, sizeof s->camera);
    size_t floats = c->reference ? 3 * (size_t)c->reference_width * (size_t)c->reference_height : 0;
    return fnv(hash, c->reference, floats * sizeof *c->reference);
}

/* Writes what was held in `held` (see load) to stderr, each line naming the rank, and closes it. */
static void release(FILE *held, bool say, int rank)
{
    char line[4096];
    rewind(held);
    bool start = true;
    while (say && fgets(line, sizeof line, held)) {
        if (start)
            fprintf(stderr, "aoview-mpi: rank %d: ", rank);
        fputs(line, stderr);
        start = strchr(line, '\n') != NULL;
    }
    fclose(held);
}

/* Loads the scene and the rest on every rank at once; a rank other than 0 holds back what it says
 * (its stderr goes to a temporary file) and says it, naming itself, only if rank 0 loaded, so that
 * a file missing everywhere is reported once; 0 when every rank has it and the same scene and
 * options as rank 0 (else rank 0 names the first rank that differs). */
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
        release(held, first_loaded, rank);
    if (!ao_cluster_agree(status == 0))
        return AO_EXIT_RUNTIME;
    int scene = ao_cluster_differs(scene_digest(&app->scene));
    int options = scene >= 0 ? -1 : ao_cluster_differs(options_digest(config, settings));
    if (scene < 0 && options < 0)
        return 0;
    if (rank == 0 && scene >= 0)
        fprintf(stderr, "aoview-mpi: rank %d loaded another scene than rank 0 (every rank needs the same file)\n",
                scene);
    else if (rank == 0)
        fprintf(stderr, "aoview-mpi: rank %d was given other options than rank 0 (only --threads, -o, --stats and -q "
                        "may differ, and --reference's path but not its image)\n",
                options);
    return AO_EXIT_USAGE;
}

/* After an interruption (a signal here or at another rank, a lost rank, rank 0's request to stop).
 * A rank other than 0 tells rank 0 it is alive and which signal stopped it, sends its tiles and
 * waits for rank 0's release with the run's status. Rank 0 asks the others to stop and waits for
 * their answers. When a rank did not answer (lost: killed or crashed, which made mpirun stop the
 * job) its tiles are gone: rank 0 names it and writes the last copy it gathered, saying how old it
 * is. Otherwise it gathers the tiles as the ranks hold them and writes that image (or the last copy,
 * when they do not come in time), naming the rank whose signal ended the run if not its own. */
static int interrupted(struct ao_app *app, struct ao_cluster *cluster, const struct ao_options *opts, int rank,
                       int sig)
{
    if (rank != 0) {
        ao_cluster_answer(cluster, sig);
        ao_cluster_salvage(cluster, SALVAGE_SECONDS);
        ao_render_resolve_stopped(app->render);
        int status = sig ? 128 + sig : AO_EXIT_RUNTIME;
        ao_cluster_await_release(cluster, LINGER_SECONDS, &status);
        return status;
    }
    ao_cluster_halt(cluster);
    char missing[256], ranks[256], why[600], copy_text[96] = "";
    ao_cluster_missing(cluster, ANSWER_SECONDS, missing, sizeof missing);
    int theirs = ao_cluster_signalled(cluster, ranks, sizeof ranks);
    sig = atomic_load(&app->interrupt.caught); /* mpirun's SIGTERM may come after another rank's answer */
    const struct ao_frame *copy = ao_render_take_frame(app->render), *frame = NULL;
    double age = ao_cluster_copy_age(cluster);
    if (copy)
        snprintf(copy_text, sizeof copy_text, "the last copy, gathered %.1f s ago, stopped", age);
    if (!missing[0]) {
        ao_cluster_salvage(cluster, SALVAGE_SECONDS);
        frame = ao_render_resolve_stopped(app->render);
    }
    /* "interrupted by SIGTERM" with the ranks' image, "...; the last copy, gathered 1.2 s ago, stopped"
     * with the copy; ao_app_write adds " at N spp" */
    const char *copied = frame || !copy ? "" : copy_text, *then = copied[0] ? "; " : "";
    int status = sig ? 128 + sig : theirs ? 128 + theirs : AO_EXIT_RUNTIME;
    if (missing[0]) {
        snprintf(why, sizeof why, "rank %s lost (killed or crashed)%s%s", missing, then, copied);
        status = AO_EXIT_RUNTIME;
    } else if (sig) {
        snprintf(why, sizeof why, "interrupted by %s%s%s", ao_app_signal_name(sig), then, copied);
    } else if (ranks[0]) {
        snprintf(why, sizeof why, "rank %s %s%s%s%s", ranks, theirs ? "interrupted by " : "failed",
                 theirs ? ao_app_signal_name(theirs) : "", then, copied);
    } else {
        snprintf(why, sizeof why, "stopped%s%s", then, copied);
    }
    frame = frame ? frame : copy;
    if (!frame)
        fprintf(stderr, "\naoview: %s before the first image was gathered: nothing written\n", why);
    status = ao_app_write(app, opts, frame, why, false, frame ? status : AO_EXIT_RUNTIME);
    ao_cluster_release(cluster, status);
    return status;
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
    enum ao_window_result result = ao_window_run(app->render, &info);
    if (result != AO_WINDOW_NO_DISPLAY || !ao_app_go_headless(opts)) {
        *status = result == AO_WINDOW_OK ? 0 : AO_EXIT_RUNTIME;
        return true;
    }
    app->reporter.progress = !opts->quiet && watched_on_terminal();
    return false;
}

/* What the cluster's listener stops: the renderer, or rank 0's window at once (as a signal to it
 * would), naming the rank that ended the run. */
struct listener {
    struct ao_app *app;
    struct ao_cluster *cluster;
    atomic_bool window;
};

/* ao_cluster_listen's callback. */
static void stop_run(void *user)
{
    struct listener *l = user;
    if (atomic_load(&l->window)) {
        char ranks[256];
        int sig = ao_cluster_signalled(l->cluster, ranks, sizeof ranks);
        fprintf(stderr, "aoview: rank %s %s%s: the run ends\n", ranks[0] ? ranks : "?",
                sig ? "interrupted by " : "failed", sig ? ao_app_signal_name(sig) : "");
        _exit(sig ? 128 + sig : AO_EXIT_RUNTIME);
    }
    ao_render_stop(l->app->render);
}

/* Renders on every rank; rank 0 shows the window or writes. Returns the exit status; *clean says
 * whether every rank got to the end alike (MPI may then be finalized). */
static int run(struct ao_app *app, const struct ao_options *opts, double copy, int rank, bool *clean)
{
    struct ao_options mine = *opts;
    if (rank != 0) /* only rank 0 shows, reports and writes; every rank takes its tiles' RMSE */
        mine.quiet = mine.headless = true, mine.stats_path = NULL, mine.output = NULL;
    struct ao_render_config config;
    struct ao_settings settings;
    /* Rank 0's -o before loading, so that a run never renders for nothing. */
    const char *output = mine.output ? mine.output : "aoview.png";
    bool checked = rank != 0 || ((!mine.headless || ao_image_check_output(output)) &&
                                 ao_app_check_files(&mine, &output, mine.output || mine.headless ? 1 : 0));
    if (!ao_cluster_agree(checked))
        return AO_EXIT_RUNTIME;
    int status = load(app, &mine, rank, &config, &settings);
    if (status)
        return status;
    app->reporter.progress = !mine.quiet && mine.headless && watched_on_terminal();
    app->reporter.notify = ao_window_notify;
    struct ao_cluster *cluster = ao_cluster_create();
    if (!cluster)
        return AO_EXIT_RUNTIME;
    ao_cluster_set_interval(cluster, mine.headless ? copy : FRAME_SECONDS);
    config.share = ao_cluster_share(cluster);
    app->render = ao_render_create(&config, &settings);
    if (!ao_cluster_agree(app->render != NULL)) {
        ao_cluster_destroy(cluster);
        return AO_EXIT_RUNTIME;
    }
    ao_app_watch(app, app->render);
    struct listener listener = {.app = app, .cluster = cluster};
    atomic_init(&listener.window, !mine.headless);
    ao_cluster_listen(cluster, stop_run, &listener);

    /* Rank 0's window, or headless (also where no window can be opened): the other ranks follow
     * rank 0's passes until its render thread ends theirs. */
    bool shown = !mine.headless && show_window(app, &mine, &status);
    if (!shown) {
        atomic_store(&listener.window, false);
        ao_cluster_set_interval(cluster, copy);
        atomic_store(&app->interrupt.graceful, true);
        int sig;
        bool finished = ao_app_wait(app, &sig);
        if (!finished && (sig || rank == 0 || !ao_cluster_ended(cluster))) {
            *clean = false;
            ao_cluster_stop(cluster);
            return interrupted(app, cluster, &mine, rank, sig);
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
    ao_app_stop_watcher(&app->interrupt);   /* a signal from now on must not stop a freed renderer */
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
    /* After MPI_Init, whose SIGBUS handler (Open MPI's backtraces) the program's replaces; the core
     * has said nothing yet. */
    ao_program_init();
    struct ao_options opts;
    double copy = SAFETY_COPY_SECONDS;
    int status = parse(argc, argv, rank, &opts, &copy);
    if (status || opts.help || opts.version) {
        bool printed = status || rank != 0 ||
                       (opts.help ? ao_app_print(ao_cli_usage()) &&
                                    ao_app_print("\naoview-mpi also takes:\n"
                                                 "  --safety-copy S       headless: rank 0 gathers the image every S "
                                                 "seconds (default\n"
                                                 "                        5; 0: never), which it writes if a rank is "
                                                 "lost\n")
                                  : ao_app_print("aoview-mpi " AO_VERSION "\n"));
        ao_cluster_finalize();
        return printed ? status : AO_EXIT_RUNTIME;
    }
    if (!ao_cluster_agree(ao_app_start_watcher(&app, rank != 0))) {
        ao_cluster_finalize();
        return AO_EXIT_RUNTIME;
    }
    bool clean = true;
    status = ao_app_finish(&app, run(&app, &opts, copy, rank, &clean));
    if (clean)
        ao_cluster_finalize();
    return status;
}
