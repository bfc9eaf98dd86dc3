/* Benchmark: when the running average is as good as the finest preview it replaces on screen. The
 * window keeps the finest preview (4x4-pixel cells, one eye ray through each cell's centre, 8 AO
 * samples) until the average has PREVIEW_UNTIL_SPP samples per pixel (window.c). Per size, against
 * a converged image (--reference-spp samples a pixel, adaptive sampling off), one line per mean
 * spp n of the window's run (seed 1, cosine, AA, auto passes, adaptive sampling): the RMSE of the
 * average and of the preview (its cells shown as blocks), both as the screen shows them (8-bit
 * sRGB codes over 255) at every pixel, and at the preview's scale (the 4x4 means of the average
 * and of the reference against the cells), then the least n whose average beats the preview at
 * full resolution. Asserts nothing.
 * Run: ./build/tests/bench_preview [--size WxH ...] [--reference-spp N] [SCENE] (default: the bunny
 * at 1920x1080 and 3840x2160, 256 spp) */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "config.h"
#include "image.h"
#include "preview.h"
#include "program.h"
#include "render.h"
#include "scene.h"
#include "tracer.h"

enum { THREADS = 2, BLOCK = 4 };
static const uint32_t COUNTS[] = {1, 2, 3, 4, 6, 8, 9, 10, 11, 12, 16};

/* The final frame of a run of the window's estimator to target_spp (adaptive: every tile takes the
 * same samples until settled at 16, so its mean is target_spp), copied into a malloc'd buffer. */
static float *render(const struct ao_scene *scene, const struct ao_tracer *tracer, int width, int height,
                     uint32_t target_spp, bool adaptive, int spppp, double *mean_spp)
{
    struct ao_render_config config = {.scene = scene, .tracer = tracer, .threads = THREADS, .seed = 1,
                                      .target_spp = target_spp, .ao_distance = scene->ao_distance,
                                      .sequence = AO_SEQUENCE_SOBOL};
    struct ao_settings settings = {.width = width, .height = height, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .spppp = spppp, .adaptive = adaptive, .camera = scene->camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    if (!r || !ao_render_wait(r))
        exit(1);
    const struct ao_frame *f = ao_render_take_frame(r);
    size_t floats = 3 * (size_t)width * (size_t)height;
    float *copy = malloc(floats * sizeof *copy);
    if (!f || !copy)
        exit(1);
    memcpy(copy, f->rgb, floats * sizeof *copy);
    *mean_spp = f->info.mean_spp;
    ao_render_destroy(r);
    return copy;
}

static bool never(void *user)
{
    (void)user;
    return false;
}

/* The finest preview as the window shows it: each cell's value over its block x block pixels. */
static float *preview(const struct ao_scene *scene, const struct ao_tracer *tracer, int width, int height)
{
    struct ao_context ctx = {.scene = scene, .tracer = tracer, .sampling = AO_SAMPLING_COSINE, .aa = true,
                             .ao_distance = scene->ao_distance, .seed = 1, .sequence = AO_SEQUENCE_SOBOL};
    struct ao_preview p;
    if (!ao_preview_begin(&p, &ctx, &scene->camera, width, height, BLOCK))
        exit(1);
    p.rgb = malloc(3 * sizeof *p.rgb * (size_t)p.width * (size_t)p.height);
    float *image = malloc(3 * sizeof *image * (size_t)width * (size_t)height);
    if (!p.rgb || !image)
        exit(1);
    ao_preview_trace(&p, never, NULL);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++)
            memcpy(image + 3 * ((size_t)y * width + x), p.rgb + 3 * ((size_t)(y / BLOCK) * p.width + x / BLOCK),
                   3 * sizeof *image);
    free(p.rgb);
    return image;
}

/* RMSE of a against b over count values as the screen shows them: 8-bit sRGB codes over 255. */
static double screen_rmse(const float *a, const float *b, size_t count)
{
    enum { CHUNK = 4096 };
    uint8_t ca[CHUNK], cb[CHUNK];
    double sum = 0.0;
    for (size_t k = 0; k < count; k += CHUNK) {
        size_t n = count - k < CHUNK ? count - k : CHUNK;
        ao_image_encode_srgb8(a + k, n, ca);
        ao_image_encode_srgb8(b + k, n, cb);
        for (size_t i = 0; i < n; i++) {
            double d = ((double)ca[i] - (double)cb[i]) / 255.0;
            sum += d * d;
        }
    }
    return sqrt(sum / (double)count);
}

/* The image's BLOCK x BLOCK means (cells cut at the edges averaged over what they hold). */
static float *cell_means(const float *image, int width, int height, int *cw, int *ch)
{
    *cw = (width + BLOCK - 1) / BLOCK;
    *ch = (height + BLOCK - 1) / BLOCK;
    float *cells = calloc(3 * (size_t)*cw * (size_t)*ch, sizeof *cells);
    int *counts = calloc((size_t)*cw * (size_t)*ch, sizeof *counts);
    if (!cells || !counts)
        exit(1);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            size_t c = (size_t)(y / BLOCK) * *cw + x / BLOCK;
            counts[c]++;
            for (int k = 0; k < 3; k++)
                cells[3 * c + k] += image[3 * ((size_t)y * width + x) + k];
        }
    for (size_t c = 0; c < (size_t)*cw * *ch; c++)
        for (int k = 0; k < 3; k++)
            cells[3 * c + k] /= (float)counts[c];
    free(counts);
    return cells;
}

static void measure(const struct ao_scene *scene, const struct ao_tracer *tracer, int width, int height,
                    uint32_t reference_spp)
{
    size_t count = 3 * (size_t)width * (size_t)height;
    double mean, t0 = bench_now();
    float *reference = render(scene, tracer, width, height, reference_spp, false, 16, &mean);
    float *shown = preview(scene, tracer, width, height);
    int cw, ch;
    float *reference_cells = cell_means(reference, width, height, &cw, &ch);
    float *preview_cells = cell_means(shown, width, height, &cw, &ch);
    size_t cell_count = 3 * (size_t)cw * (size_t)ch;
    double preview_full = screen_rmse(shown, reference, count);
    double preview_coarse = screen_rmse(preview_cells, reference_cells, cell_count);
    printf("%dx%d (reference %u spp, %.0f s): finest preview (%d px cells) RMSE %.4f at every pixel, %.4f at its "
           "scale\n", width, height, reference_spp, bench_now() - t0, BLOCK, preview_full, preview_coarse);
    uint32_t crossover = 0;
    for (size_t k = 0; k < sizeof COUNTS / sizeof COUNTS[0]; k++) {
        float *average = render(scene, tracer, width, height, COUNTS[k], true, 0, &mean);
        float *average_cells = cell_means(average, width, height, &cw, &ch);
        double full = screen_rmse(average, reference, count);
        double coarse = screen_rmse(average_cells, reference_cells, cell_count);
        printf("  average at %4.1f spp: RMSE %.4f at every pixel (%s the preview), %.4f at the preview's scale\n",
               mean, full, full <= preview_full ? "beats" : "worse than", coarse);
        if (!crossover && full <= preview_full)
            crossover = COUNTS[k];
        free(average);
        free(average_cells);
    }
    printf("%dx%d: the average beats the finest preview at every pixel from %u spp\n", width, height, crossover);
    fflush(stdout);
    free(reference);
    free(shown);
    free(reference_cells);
    free(preview_cells);
}

int main(int argc, char **argv)
{
    ao_program_init();
    const char *path = AO_DEFAULT_SCENE;
    int sizes[8][2], count = 0;
    uint32_t reference_spp = 256;
    for (int k = 1; k < argc; k++) {
        if (strcmp(argv[k], "--size") == 0 && k + 1 < argc && count < 8 &&
            sscanf(argv[k + 1], "%dx%d", &sizes[count][0], &sizes[count][1]) == 2)
            count++, k++;
        else if (strcmp(argv[k], "--reference-spp") == 0 && k + 1 < argc)
            reference_spp = (uint32_t)atoi(argv[++k]);
        else
            path = argv[k];
    }
    if (!count) {
        sizes[0][0] = 1920, sizes[0][1] = 1080, sizes[1][0] = 3840, sizes[1][1] = 2160;
        count = 2;
    }
    struct ao_scene scene;
    struct ao_tracer *tracer = bench_load(path, &scene);
    printf("%s, %d threads\n", scene.name, THREADS);
    for (int k = 0; k < count; k++)
        measure(&scene, tracer, sizes[k][0], sizes[k][1], reference_spp);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    return 0;
}
