/* preview.c: the block sizes of the previews after a restart, the grid a preview traces, its cells
 * (each the mean of AO_PREVIEW_SAMPLES samples at the cell's centre: exact on an open plane under
 * cosine sampling, where every sample is the albedo), and the stop asked between tiles. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>

#include "preview.h"
#include "scene_load.h"
#include "tracer.h"
#include "unit_main.h"

/* An open plane of albedo 0.7 under a sky of 1, the horizon in the image's upper part. */
static const char PLANE[] = "camera eye 0 1 3 target 0 0 0 up 0 1 0 fov 40\nbackground 1\n"
                            "quad corner -1e4 0 -1e4 edge1 0 0 2e4 edge2 2e4 0 0 albedo 0.7\n";

/* The first block brings the long side nearest to 64 cells in log scale (64 / sqrt 2 to 64 sqrt 2
 * cells), a power of two of at least 4; images too small for that get 1 (no preview). */
static void test_first_block(void **state)
{
    (void)state;
    assert_int_equal(ao_preview_first_block(640, 480), 8);
    assert_int_equal(ao_preview_first_block(480, 640), 8);
    assert_int_equal(ao_preview_first_block(3840, 2160), 64);
    assert_int_equal(ao_preview_first_block(256, 10), 4);
    assert_int_equal(ao_preview_first_block(160, 120), 1);
    assert_int_equal(ao_preview_first_block(1, 1), 1);
    for (int side = 1; side <= 8192; side++) {
        int block = ao_preview_first_block(side, side / 3 + 1);
        if (block == 1) {
            assert_true(side / 4.0 < 64 / sqrt(2.0));   /* a block of 4 would give too few cells */
            continue;
        }
        assert_true(block >= 4 && (block & (block - 1)) == 0);
        double cells = (double)side / block;
        assert_true(cells >= 64 / sqrt(2.0) - 1e-9 && cells < 64 * sqrt(2.0));
    }
}

/* Halving to the last block of 4; after it the full pass (1). */
static void test_next_block(void **state)
{
    (void)state;
    assert_int_equal(ao_preview_next_block(64), 32);
    assert_int_equal(ao_preview_next_block(8), 4);
    assert_int_equal(ao_preview_next_block(4), 1);
    assert_int_equal(ao_preview_next_block(1), 1);
}

struct plane {
    struct ao_scene scene;
    struct ao_tracer *tracer;
    struct ao_context ctx;
};

static void plane_begin(struct plane *p)
{
    ao_tracer_thread_init();
    assert_true(ao_scene_parse(&p->scene, PLANE, "plane.scene", NULL));
    p->tracer = ao_tracer_create(&p->scene);
    assert_non_null(p->tracer);
    p->ctx = (struct ao_context){.scene = &p->scene, .tracer = p->tracer, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                 .ao_distance = INFINITY, .seed = 1};
}

static void plane_finish(struct plane *p)
{
    ao_tracer_destroy(p->tracer);
    ao_scene_finish(&p->scene);
}

static bool never(void *user)
{
    (void)user;
    return false;
}

/* Stops once *user calls have said no. */
static bool after(void *user)
{
    int *left = user;
    return (*left)-- <= 0;
}

/* The grid: ceil(width / block) x ceil(height / block) cells, in tiles of 16 x 16, without jitter;
 * every cell traced, the plane's exactly its albedo, the sky's the background, rows whole. */
static void test_trace_open_plane(void **state)
{
    (void)state;
    struct plane pl;
    plane_begin(&pl);
    struct ao_preview p;
    assert_true(ao_preview_begin(&p, &pl.ctx, &pl.scene.camera, 650, 470, 8));
    assert_false(p.ctx.aa);
    assert_int_equal(p.block, 8);
    assert_int_equal(p.width, 82);
    assert_int_equal(p.height, 59);
    assert_int_equal(p.tiles_x, 6);
    assert_int_equal(p.tiles, 6 * 4);
    size_t n = (size_t)3 * 82 * 59;
    p.rgb = malloc(n * sizeof *p.rgb);
    assert_non_null(p.rgb);
    for (size_t k = 0; k < n; k++)
        p.rgb[k] = -1.0f;
    ao_preview_trace(&p, never, NULL);
    int sky_rows = 0;
    for (int j = 0; j < p.height; j++) {
        const float *row = p.rgb + (size_t)3 * j * p.width;
        bool sky = row[0] == 1.0f;
        assert_true(sky || fabsf(row[0] - 0.7f) < 1e-6f);
        if (sky)   /* the sky's rows come first */
            assert_int_equal(sky_rows++, j);
        for (int k = 0; k < 3 * p.width; k++)
            assert_true(row[k] == row[0]);
    }
    assert_true(sky_rows > 0 && sky_rows < p.height);
    free(p.rgb);
    plane_finish(&pl);
}

/* The stop is asked before each tile: no tile after it says so, and every tile before it whole. */
static void test_stop_between_tiles(void **state)
{
    (void)state;
    struct plane pl;
    plane_begin(&pl);
    struct ao_preview p;
    assert_true(ao_preview_begin(&p, &pl.ctx, &pl.scene.camera, 640, 480, 8));   /* 80 x 60: 5 x 4 tiles */
    size_t n = (size_t)3 * 80 * 60;
    p.rgb = malloc(n * sizeof *p.rgb);
    assert_non_null(p.rgb);
    for (int tiles = 0; tiles <= 3; tiles++) {
        for (size_t k = 0; k < n; k++)
            p.rgb[k] = -1.0f;
        atomic_store(&p.next, 0);
        int left = tiles;
        ao_preview_trace(&p, after, &left);
        for (int j = 0; j < 60; j++)
            for (int i = 0; i < 80; i++) {
                int tile = j / 16 * 5 + i / 16;
                float v = p.rgb[3 * ((size_t)j * 80 + (size_t)i)];
                assert_true(tile < tiles ? v >= 0.0f : v == -1.0f);
            }
    }
    free(p.rgb);
    plane_finish(&pl);
}

/* A camera that cannot form an image: refused. */
static void test_begin_refuses_a_degenerate_camera(void **state)
{
    (void)state;
    struct plane pl;
    plane_begin(&pl);
    struct ao_camera camera = pl.scene.camera;
    camera.up = ao_vec3_sub(camera.target, camera.eye);
    struct ao_preview p;
    assert_false(ao_preview_begin(&p, &pl.ctx, &camera, 640, 480, 8));
    plane_finish(&pl);
}

UNIT_TEST_MAIN(cmocka_unit_test(test_first_block), cmocka_unit_test(test_next_block),
               cmocka_unit_test(test_trace_open_plane), cmocka_unit_test(test_stop_between_tiles),
               cmocka_unit_test(test_begin_refuses_a_degenerate_camera))
