/* The heat maps' pure parts (heatmap.c): the colour ramp's ends and order on its log scale, a tile
 * without an estimate (and a whole preview) in the grey of "not known", and the difference view's
 * mean over the three channels. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "heatmap.h"
#include "unit_main.h"

/* The colour's brightness, to compare where the ramp stands. */
static float sum(const float rgb[3])
{
    return rgb[0] + rgb[1] + rgb[2];
}

/* The ends: 0, anything at or below the low end, and NaN are the darkest blue; at or above the high
 * end the red; every colour of the ramp stays apart from the grey of "not known". */
static void test_ramp(void **state)
{
    (void)state;
    float low[3], zero[3], nan_[3], high[3], above[3], mid[3];
    ao_heatmap_colour(&ao_heatmap_error, 1e-4, low);
    ao_heatmap_colour(&ao_heatmap_error, 0.0, zero);
    ao_heatmap_colour(&ao_heatmap_error, NAN, nan_);
    ao_heatmap_colour(&ao_heatmap_error, 0.1, high);
    ao_heatmap_colour(&ao_heatmap_error, 5.0, above);
    ao_heatmap_colour(&ao_heatmap_error, 3e-3, mid);
    assert_memory_equal(low, zero, sizeof low);
    assert_memory_equal(low, nan_, sizeof low);
    assert_memory_equal(high, above, sizeof high);
    assert_true(low[2] > low[0] && low[2] > low[1]);     /* blue */
    assert_true(high[0] > high[1] && high[0] > high[2]); /* red */
    assert_true(sum(low) < sum(mid));
    for (int k = 0; k <= 100; k++) {
        float rgb[3];
        ao_heatmap_colour(&ao_heatmap_difference, pow(10.0, -4.0 + 4.0 * k / 100.0), rgb);
        float distance = fabsf(rgb[0] - ao_heatmap_unknown[0]) + fabsf(rgb[1] - ao_heatmap_unknown[1]) +
                         fabsf(rgb[2] - ao_heatmap_unknown[2]);
        assert_true(distance > 0.05f);
    }
}

/* Tiles: an estimated tile in its error's colour, one not estimated yet (NaN) in the grey, a preview
 * (no tiles) grey all over; the tiles at the right and bottom edges clipped. */
static void test_tiles(void **state)
{
    (void)state;
    enum { W = 20, H = 18 };
    float rgb[3 * W * H] = {0}, heat[3 * W * H], errors[4] = {1e-4f, NAN, 0.1f, 3e-3f}, want[3];
    struct ao_frame f = {.width = W, .height = H, .rgb = rgb, .tile = 16, .tiles_x = 2, .tiles_y = 2,
                         .tile_error = errors, .block = 1, .image_width = W, .image_height = H};
    ao_heatmap_tiles(&f, heat);
    ao_heatmap_colour(&ao_heatmap_error, 1e-4, want);
    assert_memory_equal(heat, want, sizeof want);                               /* (0, 0): tile 0 */
    assert_memory_equal(heat + 3 * 17, ao_heatmap_unknown, sizeof want);        /* (17, 0): tile 1 */
    ao_heatmap_colour(&ao_heatmap_error, 0.1, want);
    assert_memory_equal(heat + 3 * (W * 17 + 3), want, sizeof want);            /* (3, 17): tile 2 */
    ao_heatmap_colour(&ao_heatmap_error, 3e-3, want);
    assert_memory_equal(heat + 3 * (W * H - 1), want, sizeof want);             /* tile 3 */
    struct ao_frame preview = f;
    preview.tiles_x = preview.tiles_y = 0;
    preview.block = 4;
    ao_heatmap_tiles(&preview, heat);
    for (int p = 0; p < W * H; p++)
        assert_memory_equal(heat + 3 * p, ao_heatmap_unknown, sizeof want);
}

/* The difference view: per pixel the mean of |image - reference| over the three channels. */
static void test_pixels(void **state)
{
    (void)state;
    float image[6] = {0.5f, 0.5f, 0.5f, 1.0f, 0.0f, 0.2f}, reference[6] = {0.5f, 0.5f, 0.5f, 0.0f, 1.0f, 0.2f};
    float heat[6], want[3];
    ao_heatmap_pixels(image, reference, 2, 1, heat);
    ao_heatmap_colour(&ao_heatmap_difference, 0.0, want);
    assert_memory_equal(heat, want, sizeof want);
    ao_heatmap_colour(&ao_heatmap_difference, 2.0 / 3.0, want);
    for (int c = 0; c < 3; c++)
        assert_float_equal(heat[3 + c], want[c], 1e-6f);
}

UNIT_TEST_MAIN(cmocka_unit_test(test_ramp), cmocka_unit_test(test_tiles), cmocka_unit_test(test_pixels))
