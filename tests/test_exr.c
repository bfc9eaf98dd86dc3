/* exr.c through image.h: aoview's EXR round trip and header attributes, and reading what other
 * tools write — half or float, scanline or tiled, RGB or RGBA, a data window not at the origin —
 * made here with OpenEXRCore itself; malformed files each refused in one line. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <openexr.h>

#include "image.h"

enum { W = 37, H = 21 };   /* odd sizes: partial tiles and scanline blocks */

static char dir[256];

/* A path in the scratch directory. */
static const char *in_dir(const char *name)
{
    static char path[512];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return path;
}

/* A test image whose values are exact in half precision (multiples of 1/64 below 4). */
static float *pattern(void)
{
    float *rgb = malloc(sizeof(float) * W * H * 3);
    assert_non_null(rgb);
    for (int i = 0; i < W * H * 3; i++)
        rgb[i] = (float)(i % 251) / 64.0f;
    return rgb;
}

/* Writes rgb with OpenEXRCore as another tool would: the given storage and pixel type, an A
 * channel (constant 0.5) when alpha, data window origin (x0, y0). */
static void write_variant(const char *path, const float *rgb, exr_storage_t storage,
                          exr_pixel_type_t type, bool alpha, int x0, int y0)
{
    exr_context_t ctxt;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    assert_int_equal(exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init), EXR_ERR_SUCCESS);
    int part;
    assert_int_equal(exr_add_part(ctxt, NULL, storage, &part), EXR_ERR_SUCCESS);
    exr_attr_box2i_t box;
    box.min.x = x0;
    box.min.y = y0;
    box.max.x = x0 + W - 1;
    box.max.y = y0 + H - 1;
    exr_attr_v2f_t centre;
    centre.x = centre.y = 0.0f;
    assert_int_equal(exr_initialize_required_attr(ctxt, part, &box, &box, 1.0f, &centre, 1.0f,
                                                  EXR_LINEORDER_INCREASING_Y, EXR_COMPRESSION_PIZ),
                     EXR_ERR_SUCCESS);
    if (storage == EXR_STORAGE_TILED)
        assert_int_equal(exr_set_tile_descriptor(ctxt, part, 16, 8, EXR_TILE_ONE_LEVEL,
                                                 EXR_TILE_ROUND_DOWN), EXR_ERR_SUCCESS);
    const char *names[] = {"A", "B", "G", "R"};
    for (int c = alpha ? 0 : 1; c < 4; c++)
        assert_int_equal(exr_add_channel(ctxt, part, names[c], type, EXR_PERCEPTUALLY_LINEAR, 1, 1),
                         EXR_ERR_SUCCESS);
    assert_int_equal(exr_write_header(ctxt), EXR_ERR_SUCCESS);
    static const float half = 0.5f;
    int lines = 1;
    if (storage == EXR_STORAGE_SCANLINE)
        assert_int_equal(exr_get_scanlines_per_chunk(ctxt, part, &lines), EXR_ERR_SUCCESS);
    int tiles_x = storage == EXR_STORAGE_TILED ? (W + 15) / 16 : 1;
    int tiles_y = storage == EXR_STORAGE_TILED ? (H + 7) / 8 : (H + lines - 1) / lines;
    exr_encode_pipeline_t encode = EXR_ENCODE_PIPELINE_INITIALIZER;
    for (int ty = 0; ty < tiles_y; ty++) {
        for (int tx = 0; tx < tiles_x; tx++) {
            exr_chunk_info_t chunk;
            if (storage == EXR_STORAGE_TILED)
                assert_int_equal(exr_write_tile_chunk_info(ctxt, part, tx, ty, 0, 0, &chunk), 0);
            else
                assert_int_equal(exr_write_scanline_chunk_info(ctxt, part, y0 + ty * lines, &chunk), 0);
            if (tx == 0 && ty == 0)
                assert_int_equal(exr_encoding_initialize(ctxt, part, &chunk, &encode), 0);
            else
                assert_int_equal(exr_encoding_update(ctxt, part, &chunk, &encode), 0);
            for (int c = 0; c < encode.channel_count; c++) {
                exr_coding_channel_info_t *ch = &encode.channels[c];
                const char *name = ch->channel_name;
                int k = name[0] == 'R' ? 0 : name[0] == 'G' ? 1 : 2;
                /* A tile's chunk info gives its tile numbers; a scanline block's, its first row. */
                size_t first = storage == EXR_STORAGE_TILED ? (size_t)ty * 8 * W + (size_t)tx * 16
                                                            : (size_t)(chunk.start_y - y0) * W;
                ch->encode_from_ptr = name[0] == 'A' ? (const uint8_t *)&half
                                                     : (const uint8_t *)(rgb + 3 * first + k);
                ch->user_pixel_stride = name[0] == 'A' ? 0 : 12;
                ch->user_line_stride = name[0] == 'A' ? 0 : 12 * W;
                ch->user_bytes_per_element = 4;
                ch->user_data_type = EXR_PIXEL_FLOAT;
            }
            assert_int_equal(exr_encoding_choose_default_routines(ctxt, part, &encode), 0);
            assert_int_equal(exr_encoding_run(ctxt, part, &encode), 0);
        }
    }
    exr_encoding_destroy(ctxt, &encode);
    assert_int_equal(exr_finish(&ctxt), EXR_ERR_SUCCESS);
}

/* Reads path and compares it with rgb exactly. */
static void assert_reads_as(const char *path, const float *rgb)
{
    float *got = NULL;
    int w = 0, h = 0;
    assert_true(ao_image_read_linear(path, &got, &w, &h));
    assert_int_equal(w, W);
    assert_int_equal(h, H);
    for (int i = 0; i < W * H * 3; i++)
        if (got[i] != rgb[i])
            fail_msg("%s: value %d is %g, expected %g", path, i, got[i], rgb[i]);
    free(got);
}

/* aoview's own file: exact floats back, the notes in the header. */
static void test_round_trip(void **state)
{
    (void)state;
    float *rgb = pattern();
    rgb[5] = 1e-30f;   /* no half could hold these */
    rgb[6] = 123456.789f;
    struct ao_image_note notes[] = {{"aoview.spp", "64"}, {"aoview.sampling", "cosine"}};
    const char *path = in_dir("own.exr");
    assert_true(ao_image_write_linear(path, rgb, W, H, notes, 2));
    assert_reads_as(path, rgb);
    exr_context_t ctxt;
    assert_int_equal(exr_start_read(&ctxt, path, NULL), EXR_ERR_SUCCESS);
    const char *value;
    int32_t length;
    assert_int_equal(exr_attr_get_string(ctxt, 0, "aoview.spp", &length, &value), 0);
    assert_string_equal(value, "64");
    const exr_attr_chlist_t *channels;
    assert_int_equal(exr_get_channels(ctxt, 0, &channels), 0);
    assert_int_equal(channels->num_channels, 3);
    for (int c = 0; c < 3; c++)
        assert_int_equal(channels->entries[c].pixel_type, EXR_PIXEL_FLOAT);
    exr_finish(&ctxt);
    free(rgb);
}

/* Every combination other tools write. */
static void test_variants(void **state)
{
    (void)state;
    float *rgb = pattern();
    for (int v = 0; v < 8; v++) {
        exr_storage_t storage = v & 1 ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE;
        exr_pixel_type_t type = v & 2 ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
        bool alpha = v & 4;
        char name[64];
        snprintf(name, sizeof name, "variant%d.exr", v);
        const char *path = in_dir(name);
        write_variant(path, rgb, storage, type, alpha, v == 7 ? -5 : 0, v == 7 ? 9 : 0);
        assert_reads_as(path, rgb);
    }
    free(rgb);
}

/* Reads path with stderr captured: it must fail with one line holding message. */
static void expect_refused(const char *path, const char *message)
{
    FILE *capture = tmpfile();
    assert_non_null(capture);
    fflush(stderr);
    int saved = dup(STDERR_FILENO);
    dup2(fileno(capture), STDERR_FILENO);
    float *rgb = NULL;
    int w, h;
    bool ok = ao_image_read_linear(path, &rgb, &w, &h);
    fflush(stderr);
    dup2(saved, STDERR_FILENO);
    close(saved);
    char err[1024] = "";
    rewind(capture);
    size_t n = fread(err, 1, sizeof err - 1, capture);
    err[n] = '\0';
    fclose(capture);
    if (ok || !strstr(err, message) || strchr(err, '\n') != err + n - 1)
        fail_msg("%s: expected one line with '%s', got ok=%d '%s'", path, message, ok, err);
    free(rgb);
}

/* Truncations and byte flips of a valid file, a non-EXR file, a missing one. */
static void test_malformed(void **state)
{
    (void)state;
    float *rgb = pattern();
    const char *path = in_dir("good.exr");
    assert_true(ao_image_write_linear(path, rgb, W, H, NULL, 0));
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    unsigned char bytes[65536];
    size_t size = fread(bytes, 1, sizeof bytes, f);
    fclose(f);
    assert_true(size > 400 && size < sizeof bytes);
    const char *bad = in_dir("bad.exr");
    f = fopen(bad, "wb");
    fwrite(bytes, 1, size / 2, f);
    fclose(f);
    expect_refused(bad, "bad.exr: ");
    f = fopen(bad, "wb");
    fputs("PF\n1 1\n-1\n", f);
    fclose(f);
    expect_refused(bad, "bad.exr: not a readable OpenEXR file");
    expect_refused(in_dir("missing.exr"), "cannot open");
    /* Byte flips anywhere (fixed seed): refused or read, never a crash; messages to /dev/null. */
    fflush(stderr);
    int saved = dup(STDERR_FILENO), null = open("/dev/null", O_WRONLY);
    assert_true(saved >= 0 && null >= 0);
    dup2(null, STDERR_FILENO);
    uint32_t x = 12345;
    int wrong_size = 0;
    for (int m = 0; m < 300; m++) {
        unsigned char copy[65536];
        memcpy(copy, bytes, size);
        for (int k = 0; k < 3; k++) {
            x = x * 1664525u + 1013904223u;
            copy[(x >> 8) % size] ^= (unsigned char)(1u << (x >> 29));
        }
        f = fopen(bad, "wb");
        fwrite(copy, 1, size, f);
        fclose(f);
        float *got = NULL;
        int w = W, h = H;
        wrong_size += ao_image_read_linear(bad, &got, &w, &h) && (w != W || h != H);
        free(got);
    }
    fflush(stderr);
    dup2(saved, STDERR_FILENO);
    close(saved);
    close(null);
    assert_int_equal(wrong_size, 0);
    free(rgb);
}

int main(void)
{
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/aoview-exr-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir))
        return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_variants),
        cmocka_unit_test(test_malformed),
    };
    int failed = cmocka_run_group_tests(tests, NULL, NULL);
    char command[300];
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    if (system(command) != 0)
        failed++;
    return failed;
}
