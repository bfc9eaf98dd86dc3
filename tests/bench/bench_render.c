/* Benchmark: aoview against the bare-Embree ceiling measured in the same run on the very same
 * occlusion rays (and, for the all-rays ratio, eye rays), per scene, thread count and samples per
 * pass, with the share of a pass spent inside aoview's own Embree calls; BVH build time, peak
 * memory, pass time and key-press latency at 640x480, and a 4K image's memory. Prints figures;
 * asserts nothing (speed lives here, not in the tests).
 * Run: meson test -C build --benchmark -v */
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "bench_util.h"
#include "mesh.h"
#include "program.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"
#include "tracer_bench.h"

enum { SIZE = 512, REPEATS = 5, RECORDED = 1 << 16 };

/* The ceiling is always Embree's: for a scene aoview traces with its direct back end, the ratio
 * then says how much that back end beats Embree by. */

static double peak_rss_mib(void)
{
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss / 1024.0;
}

/* ---- renders ---- */

static struct ao_render *start(const struct ao_scene *scene, const struct ao_tracer *tracer, int width,
                               int height, int threads, int spppp, uint32_t spp)
{
    struct ao_render_config config = {.scene = scene, .tracer = tracer,
                                      .threads = threads, .seed = 1, .target_spp = spp,
                                      .ao_distance = scene->ao_distance};
    struct ao_settings settings = {.width = width, .height = height, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .spppp = spppp, .camera = scene->camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    if (!r)
        exit(1);
    return r;
}

/* Renders to completion and returns the final frame's facts. */
static struct ao_frame_info run(const struct ao_scene *scene, const struct ao_tracer *tracer, int width,
                                int height, int threads, int spppp, uint32_t spp)
{
    struct ao_render *r = start(scene, tracer, width, height, threads, spppp, spp);
    if (!ao_render_wait(r))
        exit(1);
    struct ao_frame_info info = ao_render_take_frame(r)->info;
    ao_render_destroy(r);
    return info;
}

/* ---- the ceiling ---- */

struct bare_job {
    const struct ao_tracer *tracer;
    struct ao_packet *packets;
    size_t count;
    enum ao_bare how;
    double seconds;
};

static void *bare_main(void *arg)
{
    struct bare_job *job = arg;
    ao_tracer_thread_init();
    job->seconds = ao_tracer_time_bare(job->tracer, job->packets, job->count, job->how);
    return NULL;
}

/* Rays per second of bare Embree on the recorded packets dealt out to `threads` threads in turn,
 * so that each gets the same mix of cheap (soon blocked) and dear (open) rays from all over the
 * image: all rays over the slower thread's time, as a pass waits for its last tile. (Contiguous
 * halves differ in cost, and the slower thread's time then understates the ceiling by up to a
 * third; the sum of the threads' own rates overstates it when one runs partly alone.) */
static double bare_rate(const struct ao_tracer *tracer, const struct ao_ray_recorder *rec, int threads,
                        enum ao_bare how)
{
    struct bare_job jobs[2];
    pthread_t ids[2];
    size_t rays = 0;
    for (int k = 0; k < threads; k++) {
        struct ao_packet *dealt = malloc((rec->count / (size_t)threads + 1) * sizeof *dealt);
        if (!dealt)
            exit(1);
        size_t count = 0;
        for (size_t p = (size_t)k; p < rec->count; p += (size_t)threads) {
            dealt[count++] = rec->packets[p];
            rays += (size_t)rec->packets[p].count;
        }
        jobs[k] = (struct bare_job){tracer, dealt, count, how, 0};
    }
    for (int k = 0; k < threads; k++)
        pthread_create(&ids[k], NULL, bare_main, &jobs[k]);
    double slowest = 0;
    for (int k = 0; k < threads; k++) {
        pthread_join(ids[k], NULL);
        slowest = jobs[k].seconds > slowest ? jobs[k].seconds : slowest;
        free(jobs[k].packets);
    }
    return (double)rays / slowest;
}

/* Starts a recorder that keeps at most RECORDED of `expected` packets, spread evenly. */
static void start_recording(struct ao_ray_recorder *rec, size_t expected)
{
    rec->count = rec->seen = 0;
    rec->stride = expected / RECORDED + 1;
}

/* Records a sample of one pass's occlusion batches and eye packets (every stride-th, spread over the image). */
static void record(struct ao_tracer *tracer, const struct ao_scene *scene, int spppp, struct ao_ray_recorder *occlusion,
                   struct ao_ray_recorder *eye)
{
    start_recording(occlusion, (size_t)SIZE * SIZE * (size_t)spppp / 16);
    start_recording(eye, (size_t)SIZE * SIZE / 16);
    ao_tracer_record(tracer, occlusion, eye);
    run(scene, tracer, SIZE, SIZE, 1, spppp, (uint32_t)spppp);
    ao_tracer_record(tracer, NULL, NULL);
}

/* ---- scenes ---- */

/* A bumpy sphere of 2 n (n - 1) triangles (n = 708: about a million) resting on a ground quad,
 * framed like the bunny scene, with computed normals. */
static void make_big_mesh(struct ao_scene *s, int n)
{
    const float pi = 3.14159265f;
    struct ao_mesh m = {0};
    memset(s, 0, sizeof *s);
    snprintf(s->name, sizeof s->name, "bumpy sphere (generated)");
    /* n rings of n vertices (the poles repeated per column), plus the quad's 4 corners. */
    m.vertex_count = (size_t)n * (size_t)n + 4;
    m.triangle_count = 2 * (size_t)(n - 1) * (size_t)n + 2;
    m.positions = malloc(m.vertex_count * sizeof *m.positions);
    m.indices = malloc(3 * m.triangle_count * sizeof *m.indices);
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            float theta = pi * (float)j / (float)(n - 1), phi = 2 * pi * (float)i / (float)n;
            float r = 0.5f * (1.0f + 0.06f * sinf(9 * phi) * sinf(7 * theta) + 0.02f * sinf(31 * phi + 23 * theta));
            m.positions[(size_t)j * (size_t)n + (size_t)i] =
                ao_vec3_make(r * sinf(theta) * cosf(phi), 0.55f + r * cosf(theta), r * sinf(theta) * sinf(phi));
        }
    uint32_t *t = m.indices, q = (uint32_t)(n * n);
    for (int j = 0; j + 1 < n; j++)
        for (int i = 0; i < n; i++) {
            uint32_t a = (uint32_t)(j * n + i), b = (uint32_t)(j * n + (i + 1) % n), c = a + (uint32_t)n, d = b + (uint32_t)n;
            *t++ = a, *t++ = b, *t++ = c, *t++ = b, *t++ = d, *t++ = c;
        }
    m.positions[q] = ao_vec3_make(-50, 0, -50), m.positions[q + 1] = ao_vec3_make(-50, 0, 50);
    m.positions[q + 2] = ao_vec3_make(50, 0, 50), m.positions[q + 3] = ao_vec3_make(50, 0, -50);
    *t++ = q, *t++ = q + 1, *t++ = q + 2, *t++ = q, *t++ = q + 2, *t++ = q + 3;
    if (!ao_mesh_compute_normals(&m) || !ao_scene_add_flat_mesh(s, &m, ao_vec3_make(0.8f, 0.8f, 0.8f)))
        exit(1);
    s->background = ao_vec3_make(1, 1, 1);
    s->ao_distance = INFINITY;
    s->camera = (struct ao_camera){.eye = {0.5f, 1.0f, 2.5f}, .target = {0, 0.5f, 0}, .up = {0, 1, 0}, .fov = 40};
}

/* ---- reports ---- */

/* One row of a scene's table, or one repeat's figures for it. */
struct row {
    double total, shadow, ceiling, ratio, all_ceiling, all_ratio, in_situ, inside, ms, scaling, bare_scaling;
};

/* Field by field, the median over n rows (a row is doubles only, so its fields are taken by index). */
static struct row median_row(const struct row *rows, int n)
{
    enum { FIELDS = sizeof(struct row) / sizeof(double) };
    double out[FIELDS];
    for (int f = 0; f < FIELDS; f++) {
        double v[REPEATS];
        for (int k = 0; k < n; k++)
            memcpy(&v[k], (const char *)&rows[k] + f * sizeof(double), sizeof(double));
        out[f] = bench_median(v, n);
    }
    struct row r;
    memcpy(&r, out, sizeof r);
    return r;
}

/* One repeat at this spppp: aoview and then the ceiling, at one and then two threads, back to
 * back into out[0] and out[1]. Ratio and scaling are this repeat's own quotients, so load from
 * other users of the machine, which drifts over seconds, cancels in them rather than landing on
 * one side of a quotient of medians. */
static void measure(struct ao_scene *scene, struct ao_tracer *tracer, const struct ao_tracer *embree,
                    const struct ao_ray_recorder *occlusion, const struct ao_ray_recorder *eye, int spppp,
                    struct row out[2])
{
    int passes = 64 / spppp < 4 ? 4 : 64 / spppp;
    for (int t = 0; t < 2; t++) {
        /* One thread on Embree: a recorder that keeps no packets times aoview's own Embree calls. */
        struct ao_ray_recorder timer = {.stride = 1};
        bool timed = t == 0 && strcmp(ao_tracer_backend(tracer), "embree") == 0;
        ao_tracer_record(tracer, timed ? &timer : NULL, NULL);
        struct ao_frame_info info = run(scene, tracer, SIZE, SIZE, t + 1, spppp, (uint32_t)(spppp * passes));
        ao_tracer_record(tracer, NULL, NULL);
        double packets = bare_rate(embree, occlusion, t + 1, AO_BARE_OCCLUDED16);
        double stream = bare_rate(embree, occlusion, t + 1, AO_BARE_OCCLUDED1M);
        double eye_rate = bare_rate(embree, eye, t + 1, AO_BARE_INTERSECT16) / 1e6;
        struct row *r = &out[t];
        r->total = (double)(info.eye_rays + info.shadow_rays) / info.seconds / 1e6;
        r->shadow = (double)info.shadow_rays / info.seconds / 1e6;
        r->ceiling = (packets > stream ? packets : stream) / 1e6;
        r->ratio = r->shadow / r->ceiling;
        /* Bare Embree's time for this run's eye and AO rays, each at its own ceiling rate. */
        double eye_share = (double)info.eye_rays / (double)(info.eye_rays + info.shadow_rays);
        r->all_ceiling = 1.0 / (eye_share / eye_rate + (1.0 - eye_share) / r->ceiling);
        r->all_ratio = r->total / r->all_ceiling;
        r->in_situ = timed ? (double)timer.embree_rays / timer.embree_seconds / 1e6 : NAN;
        r->inside = timed ? timer.embree_seconds / info.seconds : NAN;
        r->ms = 1e3 * info.seconds / info.pass;
        r->scaling = r->total / out[0].total;
        r->bare_scaling = r->all_ceiling / out[0].all_ceiling; /* bare Embree's own, on the same rays */
    }
}

/* Prints a scene's table: medians of REPEATS repeats per thread count and spppp. Stores the
 * 2-thread, spppp-16 Mrays/s in *rate_2x16 when it is not NULL. */
static void bench_scene(struct ao_scene *scene, double *rate_2x16)
{
    double t0 = bench_now();
    struct ao_tracer *embree = ao_tracer_create_with(scene, AO_BACKEND_EMBREE);
    double build_ms = 1e3 * (bench_now() - t0);
    struct ao_tracer *tracer = ao_tracer_create(scene);
    if (!tracer || !embree)
        exit(1);
    printf("\n%s: %zu triangles, %zu spheres; Embree BVH build %.0f ms; aoview traces with %s; peak RSS so "
           "far %.0f MiB\n", scene->name, scene->triangle_count, scene->sphere_count, build_ms,
           ao_tracer_backend(tracer), peak_rss_mib());
    static const int spppps[] = {1, 4, 16, 64};
    struct ao_ray_recorder occlusion = {.packets = malloc(RECORDED * sizeof(struct ao_packet)), .capacity = RECORDED};
    struct ao_ray_recorder eye = {.packets = malloc(RECORDED * sizeof(struct ao_packet)), .capacity = RECORDED};
    struct row rows[2][4];
    for (int s = 0; s < 4; s++) {
        struct row repeats[2][REPEATS], pair[2];
        record(embree, scene, spppps[s], &occlusion, &eye);
        for (int k = 0; k < REPEATS; k++) {
            measure(scene, tracer, embree, &occlusion, &eye, spppps[s], pair);
            repeats[0][k] = pair[0], repeats[1][k] = pair[1];
        }
        for (int t = 0; t < 2; t++)
            rows[t][s] = median_row(repeats[t], REPEATS);
    }
    printf("%-7s %-5s %9s %9s %9s %7s %9s %7s %8s %7s %11s %7s %9s %9s\n", "threads", "spppp", "Mrays/s", "shadow",
           "ceiling", "ratio", "all ceil", "all", "in situ", "inside", "passes/s", "ms/pass", "scaling", "bare x2");
    for (int t = 0; t < 2; t++)
        for (int s = 0; s < 4; s++) {
            const struct row *r = &rows[t][s];
            printf("%-7d %-5d %9.2f %9.2f %9.2f %6.0f%% %9.2f %6.0f%%", t + 1, spppps[s], r->total, r->shadow,
                   r->ceiling, 100 * r->ratio, r->all_ceiling, 100 * r->all_ratio);
            if (!isnan(r->inside))
                printf(" %8.2f %6.0f%%", r->in_situ, 100 * r->inside);
            else
                printf(" %8s %7s", "-", "-");
            printf(" %11.1f %7.1f", 1e3 / r->ms, r->ms);
            if (t == 1)
                printf(" %8.2fx %8.2fx", r->scaling, r->bare_scaling);
            putchar('\n');
        }
    if (rate_2x16)
        *rate_2x16 = rows[1][2].total;
    free(occlusion.packets);
    free(eye.packets);
    ao_tracer_destroy(tracer);
    ao_tracer_destroy(embree);
}

/* What the render thread logs at the end of each pass, for bench_interactivity. */
struct pass_log {
    pthread_mutex_t lock;
    pthread_cond_t changed;
    uint64_t restarts;               /* of the newest pass */
    uint32_t pass;                   /* its number within its run */
    double at;                       /* when it was published */
};

static void log_pass(const struct ao_frame_info *info, void *user)
{
    struct pass_log *log = user;
    pthread_mutex_lock(&log->lock);
    log->restarts = info->restarts;
    log->pass = info->pass;
    log->at = bench_now();
    pthread_cond_signal(&log->changed);
    pthread_mutex_unlock(&log->lock);
}

/* Waits until a pass of run `restarts` numbered at least `pass` is published; returns its time. */
static double wait_pass(struct pass_log *log, uint64_t restarts, uint32_t pass)
{
    pthread_mutex_lock(&log->lock);
    while (log->restarts != restarts || log->pass < pass)
        pthread_cond_wait(&log->changed, &log->lock);
    double at = log->at;
    pthread_mutex_unlock(&log->lock);
    return at;
}

/* Pass time at 640x480, one sample per pass, and how long a settings change takes to show: both
 * from the render thread's timestamps (on_pass), the main thread asleep in between. */
static void bench_interactivity(const struct ao_scene *scene)
{
    enum { TRIALS = 21, PASSES = 10 };
    struct ao_tracer *tracer = ao_tracer_create(scene);
    struct pass_log log = {.lock = PTHREAD_MUTEX_INITIALIZER, .changed = PTHREAD_COND_INITIALIZER,
                           .restarts = UINT64_MAX};
    struct ao_render_config config = {.scene = scene, .tracer = tracer,
                                      .threads = 2, .seed = 1, .target_spp = 1u << 30,
                                      .ao_distance = scene->ao_distance, .on_pass = log_pass, .user = &log};
    struct ao_settings settings = {.width = 640, .height = 480, .sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = 1,
                                   .camera = scene->camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    if (!tracer || !r)
        exit(1);
    double latency[TRIALS], pass_ms[TRIALS];
    for (int k = 0; k < TRIALS; k++) {
        /* Steady passes: from the end of the 2nd to the end of the (PASSES + 2)th of this run. */
        double t0 = wait_pass(&log, (uint64_t)k, 2);
        pass_ms[k] = 1e3 * (wait_pass(&log, (uint64_t)k, PASSES + 2) - t0) / PASSES;
        settings.sampling = k % 2 ? AO_SAMPLING_COSINE : AO_SAMPLING_UNIFORM;
        double changed = bench_now();
        ao_render_set_settings(r, &settings);
        latency[k] = 1e3 * (wait_pass(&log, (uint64_t)k + 1, 1) - changed);
    }
    printf("\ninteractivity, %s at 640x480, 2 threads, 1 spp per pass: %.1f ms per pass; a settings change "
           "publishes its first frame after %.1f ms (medians of %d)\n", scene->name, bench_median(pass_ms, TRIALS),
           bench_median(latency, TRIALS), TRIALS);
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
}

/* Memory of a 3840x2160 render: accumulation (36 bytes a pixel, accum.h) plus three float frames. */
static void bench_4k(const struct ao_scene *scene)
{
    struct ao_tracer *tracer = ao_tracer_create(scene);
    double before = peak_rss_mib();
    run(scene, tracer, 3840, 2160, 2, 1, 1);
    printf("3840x2160: peak RSS %.0f MiB (was %.0f MiB before it); accumulation 36 bytes per pixel = %.0f MiB\n",
           peak_rss_mib(), before, 36.0 * 3840 * 2160 / 1048576);
    ao_tracer_destroy(tracer);
}

int main(int argc, char **argv)
{
    ao_program_init();
    setvbuf(stdout, NULL, _IOLBF, 0);
    double bunny = 0, big = 0;
    for (int k = 1; k < argc; k++) {
        struct ao_scene scene;
        if (!ao_scene_load(&scene, argv[k], NULL))
            return 1;
        bench_scene(&scene, k == 1 ? &bunny : NULL);
        if (k == 1) {
            bench_interactivity(&scene);
            bench_4k(&scene);
        }
        ao_scene_finish(&scene);
    }
    struct ao_scene scene;
    make_big_mesh(&scene, 708);
    bench_scene(&scene, &big);
    ao_scene_finish(&scene);
    printf("\n1M-triangle mesh at 2 threads, 16 spp per pass: %.0f%% of the bunny's Mrays/s\n", 100 * big / bunny);
    printf("(medians of %d repeats, ratios and scaling of each repeat's own quotients; ceiling = best of "
           "rtcOccluded16 packets and rtcOccluded1M streams of aoview's batches on a sample of one pass's "
           "occlusion batches; all ceil = bare Embree's rate on this run's eye and AO rays, eye rays by "
           "rtcIntersect16 on a sample of the same pass's eye packets; all = Mrays/s / all ceil; in situ = Mrays/s "
           "of aoview's own rtcOccluded1M calls in the one-thread runs, inside = the share of their time spent in "
           "those calls; bare x2 = all ceil at 2 threads / at 1 thread, bare Embree's own scaling on the same rays)\n",
           REPEATS);
    return 0;
}
