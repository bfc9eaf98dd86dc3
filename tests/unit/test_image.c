/* image.c: the sRGB curve, PFM and PNG round trips, malformed PFMs, atomic writes. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "capture.h"
#include "image.h"

/* Each test works in a fresh directory under $TMPDIR (or /tmp), removed afterwards. */
struct fixture {
    char dir[256];
    char path[512];
};

static int setup(void **state)
{
    struct fixture *fx = calloc(1, sizeof *fx);
    const char *tmp = getenv("TMPDIR");
    snprintf(fx->dir, sizeof fx->dir, "%s/aoview-image-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(fx->dir))
        return -1;
    *state = fx;
    return 0;
}

static int teardown(void **state)
{
    struct fixture *fx = *state;
    DIR *d = opendir(fx->dir);
    for (struct dirent *e; d && (e = readdir(d));) {
        char p[600];
        snprintf(p, sizeof p, "%s/%s", fx->dir, e->d_name);
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0 && unlink(p) != 0)
            rmdir(p);
    }
    if (d)
        closedir(d);
    int rc = rmdir(fx->dir);
    free(fx);
    return rc;
}

/* fx->path = dir/name. */
static const char *in_dir(struct fixture *fx, const char *name)
{
    snprintf(fx->path, sizeof fx->path, "%s/%s", fx->dir, name);
    return fx->path;
}

static int count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    for (struct dirent *e; (e = readdir(d));)
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(d);
    return n;
}

static void write_bytes(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, size, f), size);
    assert_int_equal(fclose(f), 0);
}

/* Reads a whole file into a malloc'd buffer; *size gets its length. */
static unsigned char *read_bytes(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    unsigned char *buf = malloc(1 << 20);
    *size = fread(buf, 1, 1 << 20, f);
    fclose(f);
    return buf;
}

/* Runs ao_image_read_pfm on path, expecting failure and exactly one error line naming path. */
static void expect_pfm_rejected(const char *path)
{
    struct capture c;
    capture_begin(&c);
    float *rgb = NULL;
    int w = -1, h = -1;
    bool ok = ao_image_read_pfm(path, &rgb, &w, &h);
    char text[1024];
    capture_end(&c, text, sizeof text);
    size_t n = strlen(text);
    assert_false(ok);
    assert_null(rgb);
    assert_int_equal(c.errors, 1);
    assert_true(n > strlen(path) + 2);
    assert_memory_equal(text, path, strlen(path));
    assert_int_equal(text[n - 1], '\n');
    assert_null(memchr(text, '\n', n - 1));
}

/* A PFM file built from a header string and raw payload bytes. */
static void write_pfm_raw(const char *path, const char *header, const void *payload, size_t size)
{
    size_t hn = strlen(header);
    unsigned char *buf = malloc(hn + size + 1);
    memcpy(buf, header, hn);
    if (size)
        memcpy(buf + hn, payload, size);
    write_bytes(path, buf, hn + size);
    free(buf);
}

static float srgb_reference(double x)
{
    return (float)(x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055);
}

static void test_srgb_known_values(void **state)
{
    (void)state;
    assert_float_equal(ao_image_srgb_encode(0.0f), 0.0f, 0.0f);
    assert_float_equal(ao_image_srgb_encode(1.0f), 1.0f, 1e-6f);
    assert_float_equal(ao_image_srgb_encode(0.001f), 0.01292f, 1e-7f);        /* linear branch */
    assert_float_equal(ao_image_srgb_encode(0.0031308f), 0.040449936f, 1e-7f); /* its end */
    assert_float_equal(ao_image_srgb_encode(0.18f), 0.46135613f, 1e-6f);      /* power branch */
    assert_float_equal(ao_image_srgb_encode(0.5f), 0.73535698f, 1e-6f);
    /* The whole curve follows the formula evaluated in double precision. */
    for (int i = 0; i <= 10000; i++) {
        double x = i / 10000.0;
        assert_float_equal(ao_image_srgb_encode((float)x), srgb_reference((float)x), 2e-7f);
    }
}

static void test_srgb_clamps(void **state)
{
    (void)state;
    assert_float_equal(ao_image_srgb_encode(-0.5f), 0.0f, 0.0f);
    assert_float_equal(ao_image_srgb_encode(-INFINITY), 0.0f, 0.0f);
    assert_float_equal(ao_image_srgb_encode(NAN), 0.0f, 0.0f);
    assert_float_equal(ao_image_srgb_encode(2.0f), ao_image_srgb_encode(1.0f), 0.0f);
    assert_float_equal(ao_image_srgb_encode(INFINITY), ao_image_srgb_encode(1.0f), 0.0f);
}

static void test_srgb8_rounds_to_nearest(void **state)
{
    (void)state;
    /* 255 * encode: 0, 3.29, 10.31, 117.65, 187.52, 255, then clamped and NaN inputs. */
    const float in[] = {0.0f, 0.001f, 0.0031308f, 0.18f, 0.5f, 1.0f, 7.0f, -1.0f, NAN};
    const uint8_t want[] = {0, 3, 10, 118, 188, 255, 255, 0, 0};
    uint8_t out[9];
    ao_image_encode_srgb8(in, 9, out);
    assert_memory_equal(out, want, sizeof want);
}

/* round(255 encode(x)) with the curve in double precision: what the table must give. */
static int code_in_double(float x)
{
    double v = x > 0.0f ? (x < 1.0f ? x : 1.0) : 0.0;
    double e = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return (int)floor(255.0 * e + 0.5);
}

/* The table's codes are the correctly rounded ones for every float in [0, 1] tried: every 97th bit
 * pattern up to 1 (about ten million, every bucket of the table many times, its steps among them)
 * and each side of every step between codes; the BGRA form holds the same codes, channels
 * swapped, alpha 255. */
static void test_srgb8_table_is_correctly_rounded(void **state)
{
    (void)state;
    enum { BATCH = 4096 };
    static float in[BATCH];
    static uint8_t out[BATCH];
    int n = 0;
    uint32_t one = 0x3F800000;
    for (uint32_t bits = 0; bits <= one; bits += 97) {
        memcpy(&in[n++], &bits, sizeof bits);
        if (n == BATCH || bits + 97 > one) {
            ao_image_encode_srgb8(in, (size_t)n, out);
            for (int k = 0; k < n; k++)
                if (out[k] != code_in_double(in[k]))
                    fail_msg("%.9g: table %d, double %d", (double)in[k], out[k], code_in_double(in[k]));
            n = 0;
        }
    }
    /* each side of each step: the largest float of each code and its successor */
    for (int code = 0; code < 255; code++) {
        uint32_t lo = 0, hi = one;
        while (lo + 1 < hi) {
            uint32_t mid = lo + (hi - lo) / 2;
            float x;
            memcpy(&x, &mid, sizeof x);
            if (code_in_double(x) > code)
                hi = mid;
            else
                lo = mid;
        }
        float pair[2];
        uint8_t got[2];
        memcpy(&pair[0], &lo, sizeof lo);
        memcpy(&pair[1], &hi, sizeof hi);
        ao_image_encode_srgb8(pair, 2, got);
        assert_int_equal(got[0], code);
        assert_int_equal(got[1], code + 1);
    }
    const float pixel[6] = {0.18f, 0.5f, 1.0f, -1.0f, 0.0031308f, 2.0f};
    uint8_t bgra[8], codes[6];
    ao_image_encode_srgb8(pixel, 6, codes);
    ao_image_encode_srgb8_bgra(pixel, 2, bgra);
    const uint8_t want[8] = {codes[2], codes[1], codes[0], 255, codes[5], codes[4], codes[3], 255};
    assert_memory_equal(bgra, want, sizeof want);
}

static float *pattern(int w, int h)
{
    float *rgb = malloc(sizeof(float) * 3 * (size_t)w * (size_t)h);
    for (int i = 0; i < 3 * w * h; i++)
        rgb[i] = (float)i * 0.37f - 5.0f + 1e-7f * (float)(i % 7);
    return rgb;
}

static void test_pfm_round_trip(void **state)
{
    struct fixture *fx = *state;
    const int sizes[][2] = {{1, 1}, {7, 5}, {3, 11}, {13, 2}};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        int w = sizes[k][0], h = sizes[k][1];
        float *rgb = pattern(w, h), *back = NULL;
        int bw = 0, bh = 0;
        assert_true(ao_image_write_pfm(in_dir(fx, "a.pfm"), rgb, w, h));
        assert_true(ao_image_read_pfm(fx->path, &back, &bw, &bh));
        assert_int_equal(bw, w);
        assert_int_equal(bh, h);
        assert_memory_equal(back, rgb, sizeof(float) * 3 * (size_t)(w * h));
        free(rgb);
        free(back);
    }
    assert_int_equal(count_entries(fx->dir), 1);
}

static float le_float(const unsigned char *b)
{
    uint32_t u = (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
    float v;
    memcpy(&v, &u, sizeof v);
    return v;
}

static void test_pfm_layout(void **state)
{
    struct fixture *fx = *state;
    const int w = 3, h = 5;
    float *rgb = pattern(w, h);
    assert_true(ao_image_write_pfm(in_dir(fx, "a.pfm"), rgb, w, h));
    size_t n;
    unsigned char *bytes = read_bytes(fx->path, &n);
    const char header[] = "PF\n3 5\n-1.0\n";
    size_t hn = sizeof header - 1;
    assert_int_equal(n, hn + 12 * (size_t)(w * h));
    assert_memory_equal(bytes, header, hn);
    /* Stored row r is image row h-1-r: the first stored row is the bottom one. */
    for (int r = 0; r < h; r++)
        for (int i = 0; i < 3 * w; i++)
            assert_float_equal(le_float(bytes + hn + 4 * (size_t)(r * 3 * w + i)),
                               rgb[(h - 1 - r) * 3 * w + i], 0.0f);
    free(bytes);
    free(rgb);
}

static void put_be(unsigned char *b, float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    for (int i = 0; i < 4; i++)
        b[i] = (unsigned char)(u >> (24 - 8 * i));
}

/* The PFM at path must read as a width x height image whose values count 1, 2, 3, ... top row first. */
static void assert_pfm_counts(const char *path, int width, int height)
{
    float *rgb = NULL;
    int w = 0, h = 0;
    assert_true(ao_image_read_pfm(path, &rgb, &w, &h));
    assert_int_equal(w, width);
    assert_int_equal(h, height);
    for (int i = 0; i < 3 * width * height; i++)
        assert_float_equal(rgb[i], (float)(i + 1), 0.0f);
    free(rgb);
}

static void test_pfm_big_endian_and_loose_header(void **state)
{
    struct fixture *fx = *state;
    /* 2x2: stored bottom row (values 7..12) first, then the top row (1..6). */
    unsigned char payload[48];
    for (int i = 0; i < 12; i++)
        put_be(payload + 4 * i, (float)((i + 6) % 12 + 1));
    write_pfm_raw(in_dir(fx, "be.pfm"), "PF \t\n 2\n\n  2 \r\n 4.5\n", payload, sizeof payload);
    assert_pfm_counts(fx->path, 2, 2);
}

/* Header lines ended by CR LF, as a tool writing in Windows' text mode makes them: read as the
 * same image (the LF after the scale's CR was taken for the first pixel byte, so the file was
 * refused as holding data after its pixels); a lone CR before a pixel whose first byte is an LF
 * stays a pixel byte. */
static void test_pfm_crlf_header(void **state)
{
    struct fixture *fx = *state;
    unsigned char payload[24];
    for (int i = 0; i < 6; i++)
        put_be(payload + 4 * i, (float)(i + 1));
    write_pfm_raw(in_dir(fx, "crlf.pfm"), "PF\r\n2 1\r\n1.0\r\n", payload, sizeof payload);
    assert_pfm_counts(fx->path, 2, 1);
    float *rgb = NULL;
    int w = 0, h = 0;
    unsigned char lf_first[12] = {0x0a, 0, 0x80, 0x3f, 0, 0, 0, 0x40, 0, 0, 0x40, 0x40}; /* 1.0000012, 2, 3 LE */
    write_pfm_raw(in_dir(fx, "cr.pfm"), "PF\r1 1\r-1.0\r", lf_first, sizeof lf_first);
    assert_true(ao_image_read_pfm(fx->path, &rgb, &w, &h));
    assert_float_equal(rgb[1], 2.0f, 0.0f);
    assert_true(rgb[0] > 1.0f && rgb[0] < 1.00001f);
    free(rgb);
}

static void test_pfm_malformed_rejected(void **state)
{
    struct fixture *fx = *state;
    unsigned char payload[32] = {0};
    unsigned char nan_payload[12] = {0, 0, 0xc0, 0x7f};
    unsigned char inf_payload[12] = {0, 0, 0x80, 0x7f};
    char long_token[2000] = "PF\n";
    memset(long_token + 3, '1', sizeof long_token - 5);
    const struct {
        const char *header;
        const unsigned char *payload;
        size_t size;
    } cases[] = {
        {"", NULL, 0},                                /* empty file */
        {"hello world, not an image\n", NULL, 0},     /* garbage */
        {"P6\n2 1\n255\n", payload, 6},               /* another format */
        {"Pf\n2 1\n-1.0\n", payload, 8},              /* greyscale */
        {"PF\n2 1\n-1.0\n", payload, 23},             /* truncated by one byte */
        {"PF\n2 1\n-1.0\n", payload, 0},              /* header only */
        {"PF\n2 1\n-1.0\n", payload, 25},             /* trailing data */
        {"PF\n2 1", NULL, 0},                         /* truncated header */
        {"PF\n2 1\n-1.0", NULL, 0},                   /* no whitespace after the scale */
        {"PF\n0 1\n-1.0\n", NULL, 0},                 /* zero width */
        {"PF\n-2 1\n-1.0\n", payload, 24},            /* negative width */
        {"PF\n2 1x\n-1.0\n", payload, 24},            /* garbage in a number */
        {"PF\n2 1\n0\n", payload, 24},                /* zero scale */
        {"PF\n2 1\nnan\n", payload, 24},              /* NaN scale */
        {"PF\n99999999999 1\n-1.0\n", payload, 24},   /* overflowing width */
        {"PF\n100000 100000\n-1.0\n", payload, 24},   /* oversized, must not allocate */
        {"PF\n16384 16384\n-1.0\n", payload, 24},     /* sides fine, too many pixels */
        {"PF\n16384 2\n-1.0\n", payload, 24},         /* plausible, payload too short */
        {long_token, NULL, 0},                        /* endless header token */
        {"PF\n1 1\n-1.0\n", nan_payload, 12},         /* NaN pixel */
        {"PF\n1 1\n-1.0\n", inf_payload, 12},         /* infinite pixel */
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        write_pfm_raw(in_dir(fx, "bad.pfm"), cases[k].header, cases[k].payload, cases[k].size);
        expect_pfm_rejected(fx->path);
    }
    expect_pfm_rejected(in_dir(fx, "missing.pfm"));
}

static void test_png_round_trip(void **state)
{
    struct fixture *fx = *state;
    const int w = 7, h = 5;
    uint8_t rgb[7 * 5 * 3];
    for (int i = 0; i < w * h * 3; i++)
        rgb[i] = (uint8_t)(i * 37 + 11);
    assert_true(ao_image_write_png(in_dir(fx, "a.png"), rgb, w, h));
    uint8_t *back = NULL;
    int bw = 0, bh = 0;
    assert_true(ao_image_read_png(fx->path, &back, &bw, &bh));
    assert_int_equal(bw, w);
    assert_int_equal(bh, h);
    assert_memory_equal(back, rgb, sizeof rgb);
    free(back);
    assert_int_equal(count_entries(fx->dir), 1);
}

static void test_png_read_rejects_garbage(void **state)
{
    struct fixture *fx = *state;
    write_bytes(in_dir(fx, "bad.png"), "not a png", 9);
    uint8_t *rgb = NULL;
    int w, h;
    assert_false(ao_image_read_png(fx->path, &rgb, &w, &h));
    assert_null(rgb);
}

static void test_write_fails_cleanly(void **state)
{
    struct fixture *fx = *state;
    float px[3] = {1, 2, 3};
    uint8_t px8[3] = {1, 2, 3};
    /* Into a directory that does not exist: nothing is created anywhere. */
    assert_false(ao_image_write_pfm(in_dir(fx, "nodir/a.pfm"), px, 1, 1));
    assert_false(ao_image_write_png(in_dir(fx, "nodir/a.png"), px8, 1, 1));
    assert_int_equal(count_entries(fx->dir), 0);
    /* Onto a directory: the rename fails and the temporary file is removed. */
    assert_int_equal(mkdir(in_dir(fx, "taken.pfm"), 0700), 0);
    assert_false(ao_image_write_pfm(fx->path, px, 1, 1));
    assert_int_equal(count_entries(fx->dir), 1);
}

static void test_overwrite_is_atomic(void **state)
{
    struct fixture *fx = *state;
    float a[3] = {1, 2, 3}, b[6] = {4, 5, 6, 7, 8, 9};
    assert_true(ao_image_write_pfm(in_dir(fx, "a.pfm"), a, 1, 1));
    /* A reader holding the old file keeps seeing it whole: the new one is a new inode. */
    int old = open(fx->path, O_RDONLY);
    assert_true(old >= 0);
    struct stat before, after;
    assert_int_equal(fstat(old, &before), 0);
    assert_true(ao_image_write_pfm(fx->path, b, 2, 1));
    assert_int_equal(stat(fx->path, &after), 0);
    assert_true(before.st_ino != after.st_ino);
    unsigned char old_bytes[64];
    assert_int_equal(pread(old, old_bytes, sizeof old_bytes, 0), 24); /* 12-byte header + 1 px */
    for (int i = 0; i < 3; i++)
        assert_float_equal(le_float(old_bytes + 12 + 4 * i), a[i], 0.0f);
    close(old);
    float *rgb = NULL;
    int w, h;
    assert_true(ao_image_read_pfm(fx->path, &rgb, &w, &h));
    assert_int_equal(w, 2);
    assert_memory_equal(rgb, b, sizeof b);
    free(rgb);
    assert_int_equal(count_entries(fx->dir), 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_srgb_known_values),
        cmocka_unit_test(test_srgb_clamps),
        cmocka_unit_test(test_srgb8_rounds_to_nearest),
        cmocka_unit_test(test_srgb8_table_is_correctly_rounded),
        cmocka_unit_test_setup_teardown(test_pfm_round_trip, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pfm_layout, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pfm_big_endian_and_loose_header, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pfm_crlf_header, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pfm_malformed_rejected, setup, teardown),
        cmocka_unit_test_setup_teardown(test_png_round_trip, setup, teardown),
        cmocka_unit_test_setup_teardown(test_png_read_rejects_garbage, setup, teardown),
        cmocka_unit_test_setup_teardown(test_write_fails_cleanly, setup, teardown),
        cmocka_unit_test_setup_teardown(test_overwrite_is_atomic, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
