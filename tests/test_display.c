/* gl suite: the display shader path through OSMesa (no display server) against the CPU's sRGB
 * encoding, and the display's letterbox geometry. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "display.h"
#include "headless.h"
#include "image.h"

/* A linear test image whose every pixel differs: negative values, values above 1, tiny values
 * around the curve's 0.0031308 knee, and a red ramp along x and a green ramp along y so that
 * flipped rows or columns, swapped channels or a misaligned row stride all show. */
static float *gradient(int width, int height)
{
    float *rgb = malloc(sizeof *rgb * 3 * (size_t)width * (size_t)height);
    assert_non_null(rgb);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            float *p = rgb + 3 * ((size_t)y * width + x);
            float fx = width > 1 ? (float)x / (width - 1) : 0.5f;
            float fy = height > 1 ? (float)y / (height - 1) : 0.5f;
            p[0] = 1.4f * fx - 0.2f;                       /* -0.2 .. 1.2 */
            p[1] = fy * fy * fy;                           /* dense near 0 */
            p[2] = 0.0062616f * (float)((x * 7 + y * 3) % 11) / 10.0f  /* 0 .. 2x the knee */
                   + (x == y ? 3.0f : 0.0f);               /* a bright diagonal */
        }
    return rgb;
}

/* Renders rgb through ao_headless_write_png, reads the PNG back and checks every channel of every
 * pixel against ao_image_encode_srgb8 within 1/255 (GPU pow against libm powf). */
static void check_round_trip(int width, int height)
{
    char dir[] = "/tmp/aoview-test-display-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[sizeof dir + 16];
    snprintf(path, sizeof path, "%s/out.png", dir);

    float *rgb = gradient(width, height);
    size_t count = 3 * (size_t)width * (size_t)height;
    uint8_t *expected = malloc(count);
    assert_non_null(expected);
    ao_image_encode_srgb8(rgb, count, expected);

    assert_true(ao_headless_write_png(path, rgb, width, height));
    uint8_t *got = NULL;
    int got_width = 0, got_height = 0;
    assert_true(ao_image_read_png(path, &got, &got_width, &got_height));
    assert_int_equal(got_width, width);
    assert_int_equal(got_height, height);

    int worst = 0;
    size_t worst_at = 0;
    for (size_t i = 0; i < count; i++) {
        int diff = abs((int)got[i] - (int)expected[i]);
        if (diff > worst) {
            worst = diff;
            worst_at = i;
        }
    }
    if (worst > 1)
        fail_msg("%dx%d: pixel (%zu, %zu) channel %zu is %d, CPU says %d (linear %g)", width, height,
                 worst_at / 3 % (size_t)width, worst_at / 3 / (size_t)width, worst_at % 3,
                 got[worst_at], expected[worst_at], (double)rgb[worst_at]);

    free(got);
    free(expected);
    free(rgb);
    assert_int_equal(unlink(path), 0);
    assert_int_equal(rmdir(dir), 0);
}

/* An odd size: 37 * 3 bytes per row is not a multiple of 4, so a wrong pack or unpack alignment
 * shears the image. */
static void test_odd_size_matches_cpu(void **state)
{
    (void)state;
    check_round_trip(37, 23);
}

/* Degenerate shapes: one pixel, one row, one column. */
static void test_thin_sizes_match_cpu(void **state)
{
    (void)state;
    check_round_trip(1, 1);
    check_round_trip(129, 1);
    check_round_trip(1, 67);
}

/* Every value the encoder can meet, in one 256 x 64 image: a dense ramp over [-0.01, 1.01]. */
static void test_dense_ramp_matches_cpu(void **state)
{
    (void)state;
    int width = 256, height = 64;
    char dir[] = "/tmp/aoview-test-display-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[sizeof dir + 16];
    snprintf(path, sizeof path, "%s/ramp.png", dir);

    size_t count = 3 * (size_t)width * (size_t)height;
    float *rgb = malloc(sizeof *rgb * count);
    uint8_t *expected = malloc(count);
    assert_non_null(rgb);
    assert_non_null(expected);
    for (size_t i = 0; i < count; i++)
        rgb[i] = -0.01f + 1.02f * (float)i / (float)(count - 1);
    ao_image_encode_srgb8(rgb, count, expected);

    assert_true(ao_headless_write_png(path, rgb, width, height));
    uint8_t *got = NULL;
    int got_width = 0, got_height = 0;
    assert_true(ao_image_read_png(path, &got, &got_width, &got_height));
    int off = 0;
    for (size_t i = 0; i < count; i++) {
        int diff = abs((int)got[i] - (int)expected[i]);
        assert_in_range(diff, 0, 1);
        off += diff;
    }
    /* Disagreements can only sit on rounding boundaries: a handful out of 49152. */
    assert_in_range(off, 0, (int)(count / 100));

    free(got);
    free(expected);
    free(rgb);
    assert_int_equal(unlink(path), 0);
    assert_int_equal(rmdir(dir), 0);
}

/* Letterbox: the image keeps its aspect ratio, centred, bars on the wider side only. */
static void test_fit_letterboxes(void **state)
{
    (void)state;
    struct ao_display_rect r = ao_display_fit(640, 480, 640, 480);
    assert_true(r.x == 0 && r.y == 0 && r.width == 640 && r.height == 480);
    r = ao_display_fit(640, 480, 1000, 480);      /* wider window: bars left and right */
    assert_true(r.x == 180 && r.y == 0 && r.width == 640 && r.height == 480);
    r = ao_display_fit(640, 480, 320, 1000);      /* taller window: bars top and bottom */
    assert_true(r.x == 0 && r.y == 380 && r.width == 320 && r.height == 240);
    r = ao_display_fit(37, 23, 1, 1);             /* never negative, never larger than the window */
    assert_true(r.width >= 0 && r.height >= 0 && r.width <= 1 && r.height <= 1);
}

/* Read by LeakSanitizer in sanitizer builds: Mesa's OSMesa keeps a few hundred bytes per context
 * that OSMesaDestroyContext does not free (a bare create/destroy leaks them too), so leaks whose
 * stack passes through libOSMesa are Mesa's, not ours. */
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void)
{
    return "leak:libOSMesa.so\n";
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_odd_size_matches_cpu),
        cmocka_unit_test(test_thin_sizes_match_cpu),
        cmocka_unit_test(test_dense_ramp_matches_cpu),
        cmocka_unit_test(test_fit_letterboxes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
