/* exr.c through image.h: aoview's EXR round trip and header attributes, and reading what other
 * tools write — half or float, scanline or tiled, RGB or RGBA, a data window not at the origin,
 * every compression — made here with OpenEXRCore itself; malformed files each refused in one
 * line; a reference of the wrong size refused from its header. With the argument "tools", the
 * same files and exrmaketiled's (OpenEXR's C++ library) are checked against that library's own
 * decoding instead (exit 77 when exrmaketiled is not installed). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <openexr.h>

#include "capture.h"
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

/* How a test file is made: storage, pixel type of R, G, B (and A), compression, the channels'
 * perceptual flag, an A channel (constant 0.5) or not, the data window's origin and size. Tiles
 * are 16x8 pixels. */
struct spec {
    exr_storage_t storage;
    exr_pixel_type_t type;
    exr_compression_t compression;
    exr_perceptual_treatment_t linear;
    bool alpha;
    int x0, y0, width, height;
    exr_pixel_type_t alpha_type;   /* the A channel's type, when alpha */
    bool constant;                 /* rgb is one value for every pixel and channel */
};

/* The library's compressor, run by compress_or_store. */
static exr_result_t (*library_compress)(exr_encode_pipeline_t *encode);

/* Compresses a chunk, or stores it uncompressed when compressing does not shrink it, as the format
 * says and OpenEXR's C++ library does (OpenEXRCore 3.1.5's B44 writer does not: it stores a
 * partial tile's 168 bytes of blocks for 150 bytes of pixels, and float channels as planes). */
static exr_result_t compress_or_store(exr_encode_pipeline_t *encode)
{
    exr_result_t r = library_compress(encode);
    if (r == EXR_ERR_SUCCESS && encode->compressed_bytes >= encode->packed_bytes) {
        assert_true(encode->compressed_alloc_size >= encode->packed_bytes);
        memcpy(encode->compressed_buffer, encode->packed_buffer, encode->packed_bytes);
        encode->compressed_bytes = encode->packed_bytes;
    }
    return r;
}

/* Prints the library's messages, but not that it has no encoder for a compression (DWA). */
static void on_write_error(exr_const_context_t ctxt, exr_result_t code, const char *message)
{
    (void)ctxt;
    if (code != EXR_ERR_FEATURE_NOT_IMPLEMENTED)
        fprintf(stderr, "OpenEXRCore: %s\n",
                message ? message : exr_get_default_error_message(code));
}

/* Writes rgb (sp->width x sp->height) with OpenEXRCore as another tool would. A compression the
 * library cannot encode (DWAA and DWAB in 3.1.5) has every chunk stored uncompressed, which is a
 * valid file of that compression; false then, true when the chunks went through the library's
 * compressor (or there is none). */
static bool write_exr(const char *path, const float *rgb, const struct spec *sp)
{
    exr_context_t ctxt;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_write_error;
    assert_int_equal(exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init), EXR_ERR_SUCCESS);
    int part;
    assert_int_equal(exr_add_part(ctxt, NULL, sp->storage, &part), EXR_ERR_SUCCESS);
    exr_attr_box2i_t box;
    box.min.x = sp->x0;
    box.min.y = sp->y0;
    box.max.x = sp->x0 + sp->width - 1;
    box.max.y = sp->y0 + sp->height - 1;
    exr_attr_v2f_t centre;
    centre.x = centre.y = 0.0f;
    assert_int_equal(exr_initialize_required_attr(ctxt, part, &box, &box, 1.0f, &centre, 1.0f,
                                                  EXR_LINEORDER_INCREASING_Y, sp->compression),
                     EXR_ERR_SUCCESS);
    if (sp->storage == EXR_STORAGE_TILED)
        assert_int_equal(exr_set_tile_descriptor(ctxt, part, 16, 8, EXR_TILE_ONE_LEVEL,
                                                 EXR_TILE_ROUND_DOWN), EXR_ERR_SUCCESS);
    const char *names[] = {"A", "B", "G", "R"};
    for (int c = sp->alpha ? 0 : 1; c < 4; c++)
        assert_int_equal(exr_add_channel(ctxt, part, names[c], c ? sp->type : sp->alpha_type,
                                         sp->linear, 1, 1), EXR_ERR_SUCCESS);
    assert_int_equal(exr_write_header(ctxt), EXR_ERR_SUCCESS);
    static const float half = 0.5f;
    int lines = 1, width = sp->width, height = sp->height;
    if (sp->storage == EXR_STORAGE_SCANLINE)
        assert_int_equal(exr_get_scanlines_per_chunk(ctxt, part, &lines), EXR_ERR_SUCCESS);
    int tiles_x = sp->storage == EXR_STORAGE_TILED ? (width + 15) / 16 : 1;
    int tiles_y = sp->storage == EXR_STORAGE_TILED ? (height + 7) / 8
                                                   : (height + lines - 1) / lines;
    bool compressed = true;
    exr_encode_pipeline_t encode = EXR_ENCODE_PIPELINE_INITIALIZER;
    for (int ty = 0; ty < tiles_y; ty++) {
        for (int tx = 0; tx < tiles_x; tx++) {
            exr_chunk_info_t chunk;
            if (sp->storage == EXR_STORAGE_TILED)
                assert_int_equal(exr_write_tile_chunk_info(ctxt, part, tx, ty, 0, 0, &chunk), 0);
            else
                assert_int_equal(exr_write_scanline_chunk_info(ctxt, part, sp->y0 + ty * lines,
                                                               &chunk), 0);
            if (tx == 0 && ty == 0)
                assert_int_equal(exr_encoding_initialize(ctxt, part, &chunk, &encode), 0);
            else
                assert_int_equal(exr_encoding_update(ctxt, part, &chunk, &encode), 0);
            for (int c = 0; c < encode.channel_count; c++) {
                exr_coding_channel_info_t *ch = &encode.channels[c];
                const char *name = ch->channel_name;
                int k = name[0] == 'R' ? 0 : name[0] == 'G' ? 1 : 2;
                /* A tile's chunk info gives its tile numbers; a scanline block's, its first row. */
                size_t first = sp->storage == EXR_STORAGE_TILED
                                   ? (size_t)ty * 8 * width + (size_t)tx * 16
                                   : (size_t)(chunk.start_y - sp->y0) * width;
                ch->encode_from_ptr = name[0] == 'A' ? (const uint8_t *)&half
                                      : sp->constant ? (const uint8_t *)rgb
                                                     : (const uint8_t *)(rgb + 3 * first + k);
                ch->user_pixel_stride = name[0] == 'A' || sp->constant ? 0 : 12;
                ch->user_line_stride = name[0] == 'A' || sp->constant ? 0 : 12 * width;
                ch->user_bytes_per_element = 4;
                ch->user_data_type = EXR_PIXEL_FLOAT;
            }
            assert_int_equal(exr_encoding_choose_default_routines(ctxt, part, &encode), 0);
            if (!compressed) {
                encode.compress_fn = NULL;
            } else if (encode.compress_fn) {
                library_compress = encode.compress_fn;
                encode.compress_fn = compress_or_store;
            }
            exr_result_t r = exr_encoding_run(ctxt, part, &encode);
            if (r == EXR_ERR_FEATURE_NOT_IMPLEMENTED && (sp->compression == EXR_COMPRESSION_DWAA ||
                                                         sp->compression == EXR_COMPRESSION_DWAB)) {
                compressed = false;
                encode.compress_fn = NULL;
                r = exr_encoding_run(ctxt, part, &encode);
            }
            assert_int_equal(r, EXR_ERR_SUCCESS);
        }
    }
    exr_encoding_destroy(ctxt, &encode);
    assert_int_equal(exr_finish(&ctxt), EXR_ERR_SUCCESS);
    return compressed;
}

/* Writes rgb (W x H) as another tool would: PIZ, the given storage and pixel type, an A channel
 * when alpha, data window origin (x0, y0). */
static void write_variant(const char *path, const float *rgb, exr_storage_t storage,
                          exr_pixel_type_t type, bool alpha, int x0, int y0)
{
    struct spec sp = {.storage = storage, .type = type, .compression = EXR_COMPRESSION_PIZ,
                      .linear = EXR_PERCEPTUALLY_LINEAR, .alpha = alpha, .x0 = x0, .y0 = y0,
                      .width = W, .height = H, .alpha_type = type};
    write_exr(path, rgb, &sp);
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

/* Reads path (at width x height when width is not 0) with its messages captured: it must fail with
 * one error line holding message. */
static void expect_refused_sized(const char *path, int width, int height, const char *message)
{
    struct capture c;
    capture_begin(&c);
    float *rgb = NULL;
    int w, h;
    bool ok = width ? ao_image_read_linear_sized(path, width, height, &rgb)
                    : ao_image_read_linear(path, &rgb, &w, &h);
    char err[1024];
    capture_end(&c, err, sizeof err);
    size_t n = strlen(err);
    if (c.errors != 1 || ok || !strstr(err, message) || strchr(err, '\n') != err + n - 1)
        fail_msg("%s: expected one line with '%s', got ok=%d '%s'", path, message, ok, err);
    free(rgb);
}

/* Reads path with its messages captured: it must fail with one error line holding message. */
static void expect_refused(const char *path, const char *message)
{
    expect_refused_sized(path, 0, 0, message);
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
    /* Byte flips anywhere (fixed seed): refused or read, never a crash (the messages dropped: no
     * sink). */
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
    assert_int_equal(wrong_size, 0);
    free(rgb);
}

/* ------------------------------------------------------------------ every compression */

enum { CW = 70, CH = 45 };   /* partial 16x8 tiles, scanline blocks and 4x4 B44 blocks */

/* A cheap hash of a pixel's channel, for noise. */
static uint32_t noise(int x, int y, int c)
{
    uint32_t h = (uint32_t)x * 73856093u ^ (uint32_t)y * 19349663u ^ (uint32_t)c * 83492791u;
    return h * 2654435761u;
}

/* A smooth CW x CH image with a little noise, of values exact in half precision (multiples of
 * 1/256 from 0.28 to 1.72); with full, its values get full float mantissas (noise below 2^-10),
 * which only a float file keeps. */
static float *smooth(bool full)
{
    float *rgb = malloc(sizeof(float) * CW * CH * 3);
    assert_non_null(rgb);
    for (int y = 0; y < CH; y++)
        for (int x = 0; x < CW; x++)
            for (int c = 0; c < 3; c++) {
                long k = 256 + lround(180.0 * sin(x * 0.15 + c) * cos(y * 0.11)) +
                         (long)(noise(x, y, c) % 5) - 2;
                double v = (double)k / 256.0;
                if (full)
                    v += (double)(noise(x, y, c) >> 8) / 16777216.0 / 1024.0;
                rgb[(y * CW + x) * 3 + c] = (float)v;
            }
    return rgb;
}

/* The bits of a half that holds v exactly (a normal half or zero). */
static uint16_t half_bits(float v)
{
    uint32_t f;
    memcpy(&f, &v, sizeof f);
    uint32_t sign = f >> 16 & 0x8000;
    if ((f & 0x7fffffff) == 0)
        return (uint16_t)sign;
    int e = (int)(f >> 23 & 0xff) - 127 + 15;
    if (e < 1 || e > 30 || (f & 0x1fff) != 0)
        fail_msg("%g is not a normal half", (double)v);
    return (uint16_t)(sign | (uint32_t)e << 10 | (f >> 13 & 0x3ff));
}

/* B44's order of half bit patterns: the larger number, the larger value. */
static int ordered(uint16_t h)
{
    return h & 0x8000 ? (uint16_t)~h : h | 0x8000;
}

/* How far B44 may move a half in a 4x4 block whose values span range in ordered bit patterns,
 * for channels not marked perceptually linear (their values are packed as they are). B44 keeps
 * the block's largest value t_max exactly and codes each t as d = round((t_max - t) / 2^s), with
 * the smallest shift s for which all 15 differences between neighbouring d (each within
 * range / 2^s + 1, two roundings of at most 1/2) fit in [-32, 31]. Any s with 2^s >= range / 30
 * fits, so the chosen s is at most the smallest such s*; decoding gives t_max - d 2^s, within
 * 2^(s - 1) <= 2^(s* - 1) of t, and exact when s* = 0 (range <= 30). */
static int b44_bound(int range)
{
    if (range <= 30)
        return 0;
    int s = 0;
    while ((30 << s) < range)
        s++;
    return 1 << (s - 1);
}

/* Checks the decoded image got (CW x CH) against the known one: exact where the compression keeps
 * the pixel type's values, within a derived bound where it does not. */
static void check_decoded(const char *path, const float *known, const float *got,
                          exr_compression_t compression, exr_pixel_type_t type)
{
    bool b44 = compression == EXR_COMPRESSION_B44 || compression == EXR_COMPRESSION_B44A;
    bool pxr24 = compression == EXR_COMPRESSION_PXR24;
    int range[(CW + 3) / 4 * ((CH + 3) / 4) * 3];
    if (b44 && type == EXR_PIXEL_HALF) {
        /* The blocks: 16x8 tiles and 32-row scanline blocks start on the 4x4 grid. */
        for (int b = 0; b < (int)(sizeof range / sizeof *range); b++) {
            int bx = b / 3 % ((CW + 3) / 4), by = b / 3 / ((CW + 3) / 4), c = b % 3;
            int lo = 65536, hi = -1;
            for (int y = 4 * by; y < 4 * by + 4 && y < CH; y++)
                for (int x = 4 * bx; x < 4 * bx + 4 && x < CW; x++) {
                    int t = ordered(half_bits(known[(y * CW + x) * 3 + c]));
                    lo = t < lo ? t : lo;
                    hi = t > hi ? t : hi;
                }
            range[b] = hi - lo;
        }
    }
    for (int i = 0; i < CW * CH * 3; i++) {
        int x = i / 3 % CW, y = i / 3 / CW, c = i % 3;
        if (b44 && type == EXR_PIXEL_HALF) {
            int bound = b44_bound(range[((y / 4) * ((CW + 3) / 4) + x / 4) * 3 + c]);
            int moved = abs(ordered(half_bits(got[i])) - ordered(half_bits(known[i])));
            if (moved > bound)
                fail_msg("%s: value %d (%d, %d) is %g, expected %g within %d half steps, moved %d",
                         path, i, x, y, (double)got[i], (double)known[i], bound, moved);
        } else if (pxr24 && type == EXR_PIXEL_FLOAT) {
            /* PXR24 rounds a float's 23 mantissa bits to 15, adding half of the dropped range:
             * the error is at most 2^(e - 16) <= |v| 2^-16 for 2^e <= |v|. */
            if (fabsf(got[i] - known[i]) > fabsf(known[i]) * 0x1p-16f)
                fail_msg("%s: value %d is %.9g, expected %.9g within 2^-16 of it", path, i,
                         (double)got[i], (double)known[i]);
        } else if (got[i] != known[i]) {
            fail_msg("%s: value %d (%d, %d) is %.9g, expected %.9g exactly", path, i, x, y,
                     (double)got[i], (double)known[i]);
        }
    }
}

/* The size of a file, in bytes. */
static long file_size(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fclose(f);
    return size;
}

static const char *const compression_names[] = {"none", "rle", "zips", "zip", "piz",
                                                "pxr24", "b44", "b44a", "dwaa", "dwab"};

/* The name of the test file of one combination. */
static const char *compression_file(exr_compression_t compression, exr_storage_t storage,
                                    exr_pixel_type_t type, bool alpha)
{
    static char name[64];
    snprintf(name, sizeof name, "%s_%s_%s%s.exr", compression_names[compression],
             storage == EXR_STORAGE_TILED ? "tiled" : "scan",
             type == EXR_PIXEL_HALF ? "half" : "float", alpha ? "_a" : "");
    return in_dir(name);
}

/* Combination v (0 to 7) of test_compressions: tiled when bit 0 is set, float when bit 1 is, a
 * half A when bit 2 is; CW x CH at the origin, channels not marked perceptually linear. */
static struct spec compression_spec(exr_compression_t compression, int v)
{
    return (struct spec){.storage = v & 1 ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE,
                         .type = v & 2 ? EXR_PIXEL_FLOAT : EXR_PIXEL_HALF,
                         .compression = compression, .linear = EXR_PERCEPTUALLY_LOGARITHMIC,
                         .alpha = v & 4, .width = CW, .height = CH, .alpha_type = EXR_PIXEL_HALF};
}

/* Every compression the library knows, scanline and tiled, half and float, RGB and RGB with a
 * half A: each file read back exactly, or within the bound its compression's loss allows. Half
 * images are exact in half, float images use full mantissas; the channels are not marked
 * perceptually linear (the B44 bound is derived for values packed as they are). B44 and B44A
 * files hold chunks stored uncompressed (float channels, which B44 does not compress; partial
 * tiles, which its blocks would not shrink) beside compressed ones. */
static void test_compressions(void **state)
{
    (void)state;
    float *known[2] = {smooth(false), smooth(true)};
    for (int compression = 0; compression < EXR_COMPRESSION_LAST_TYPE; compression++) {
        for (int v = 0; v < 8; v++) {
            struct spec sp = compression_spec((exr_compression_t)compression, v);
            const float *rgb = known[sp.type == EXR_PIXEL_FLOAT];
            const char *path = compression_file(sp.compression, sp.storage, sp.type, sp.alpha);
            bool compressed = write_exr(path, rgb, &sp);
            bool dwa = compression == EXR_COMPRESSION_DWAA || compression == EXR_COMPRESSION_DWAB;
            /* OpenEXRCore 3.1.5 has no DWA encoder (nor decoder): its chunks are stored raw here,
             * and a real DWA chunk must be refused (below). A library with them fails here, to be
             * given a derived bound for DWA's loss. */
            if (dwa && compressed)
                fail_msg("%s: this OpenEXR library encodes DWA; the test has no bound for it",
                         path);
            float *got = NULL;
            int w = 0, h = 0;
            if (!ao_image_read_linear(path, &got, &w, &h))
                fail_msg("%s: not read", path);
            assert_int_equal(w, CW);
            assert_int_equal(h, CH);
            check_decoded(path, rgb, got, sp.compression, sp.type);
            free(got);
            /* Lossy packing of halves happened (so the bound was exercised), not raw storage. */
            if ((compression == EXR_COMPRESSION_B44 || compression == EXR_COMPRESSION_B44A) &&
                sp.type == EXR_PIXEL_HALF)
                assert_true(file_size(path) * 10 <
                            file_size(compression_file(EXR_COMPRESSION_NONE, sp.storage, sp.type,
                                                       sp.alpha)) * 7);
        }
    }
    free(known[0]);
    free(known[1]);
}

/* A DWAA and a DWAB chunk that is compressed (stores fewer bytes than its pixels take): refused in
 * one line naming the compression, since OpenEXRCore 3.1.5 cannot decode DWA. */
static void test_dwa_refused(void **state)
{
    (void)state;
    for (int compression = EXR_COMPRESSION_DWAA; compression <= EXR_COMPRESSION_DWAB;
         compression++) {
        const char *path = in_dir("dwa_chunk.exr");
        exr_context_t ctxt;
        exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
        assert_int_equal(exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init), 0);
        int part;
        assert_int_equal(exr_add_part(ctxt, NULL, EXR_STORAGE_SCANLINE, &part), 0);
        assert_int_equal(exr_initialize_required_attr_simple(ctxt, part, 8, 4,
                                                             (exr_compression_t)compression), 0);
        for (const char *const *name = (const char *const[]){"B", "G", "R", NULL}; *name; name++)
            assert_int_equal(exr_add_channel(ctxt, part, *name, EXR_PIXEL_FLOAT,
                                             EXR_PERCEPTUALLY_LINEAR, 1, 1), 0);
        assert_int_equal(exr_write_header(ctxt), 0);
        unsigned char bytes[8 * 4 * 3 * 4 - 1];
        memset(bytes, 0x11, sizeof bytes);
        assert_int_equal(exr_write_scanline_chunk(ctxt, part, 0, bytes, sizeof bytes), 0);
        assert_int_equal(exr_finish(&ctxt), 0);
        char message[80];
        snprintf(message, sizeof message,
                 "dwa_chunk.exr: %s compression cannot be decoded by OpenEXR",
                 compression_names[compression]);
        expect_refused(path, message);
    }
}

/* ------------------------------------------------------------------ the size a caller needs */

/* ao_image_read_linear_sized: the right size reads; another is refused in one line naming both
 * sizes, for EXR and PFM; and a 16384x4096 ZIP EXR of about 800 KB (800 MB of pixels) is refused
 * from its header alone, its peak memory growing by less than 64 MB (a child process measures). */
static void test_sized(void **state)
{
    (void)state;
    float *rgb = pattern(), *got = NULL;
    char exr[512], pfm[512];
    snprintf(exr, sizeof exr, "%s", in_dir("sized.exr"));
    snprintf(pfm, sizeof pfm, "%s", in_dir("sized.pfm"));
    assert_true(ao_image_write_linear(exr, rgb, W, H, NULL, 0));
    assert_true(ao_image_write_pfm(pfm, rgb, W, H));
    assert_true(ao_image_read_linear_sized(exr, W, H, &got));
    free(got);
    assert_true(ao_image_read_linear_sized(pfm, W, H, &got));
    free(got);
    expect_refused_sized(exr, W + 1, H, "sized.exr: the image is 37x21, not the 38x21 needed");
    expect_refused_sized(pfm, W, H - 1, "sized.pfm: the image is 37x21, not the 37x20 needed");
    free(rgb);

    /* The large file: 256 ZIP blocks of 16 constant rows, one shared value. */
    const char *big = in_dir("big.exr");
    static const float grey = 0.25f;
    struct spec sp = {.storage = EXR_STORAGE_SCANLINE, .type = EXR_PIXEL_HALF,
                      .compression = EXR_COMPRESSION_ZIP, .linear = EXR_PERCEPTUALLY_LINEAR,
                      .width = 16384, .height = 4096, .constant = true};
    write_exr(big, &grey, &sp);
    long size = file_size(big);
    assert_true(size < 2 * 1024 * 1024);
    fflush(stderr);
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) {
        struct rusage before, after;
        getrusage(RUSAGE_SELF, &before);
        float *pixels = NULL;
        bool read = ao_image_read_linear_sized(big, 640, 480, &pixels);
        getrusage(RUSAGE_SELF, &after);
        _exit(read ? 2 : after.ru_maxrss - before.ru_maxrss < 64 * 1024 ? 0 : 3);
    }
    int status;
    assert_int_equal(waitpid(child, &status, 0), child);
    assert_true(WIFEXITED(status));
    if (WEXITSTATUS(status) != 0)
        fail_msg("%s (%ld bytes): %s", big, size,
                 WEXITSTATUS(status) == 2 ? "read at 640x480" : "peak memory grew by 64 MB or more");
    expect_refused_sized(big, 640, 480, "big.exr: the image is 16384x4096, not the 640x480 needed");
}

/* ------------------------------------------------------ against OpenEXR's C++ library */

/* Runs a shell command made from format; its exit status. */
static int run(const char *format, ...)
{
    char command[1200];
    va_list args;
    va_start(args, format);
    vsnprintf(command, sizeof command, format, args);
    va_end(args);
    int status = system(command);
    return status == -1 || !WIFEXITED(status) ? -1 : WEXITSTATUS(status);
}

/* Path as OpenEXR's C++ library decodes it: exrmaketiled rewrites it uncompressed, and that copy
 * is read here (exact for any compression). */
static float *cpp_decoded(const char *path)
{
    char copy[600];
    snprintf(copy, sizeof copy, "%s.cpp.exr", path);
    if (run("exrmaketiled -z none '%s' '%s' >/dev/null 2>&1", path, copy) != 0)
        fail_msg("exrmaketiled cannot read %s", path);
    float *rgb = NULL;
    int w = 0, h = 0;
    if (!ao_image_read_linear(copy, &rgb, &w, &h) || w != CW || h != CH)
        fail_msg("%s: the C++ library's copy is not read as %dx%d", path, CW, CH);
    remove(copy);
    return rgb;
}

/* Fails unless a and b (CW x CH) are equal value for value. */
static void assert_same(const char *path, const float *a, const float *b)
{
    for (int i = 0; i < CW * CH * 3; i++)
        if (a[i] != b[i])
            fail_msg("%s: value %d (%d, %d) is %.9g here, %.9g by the C++ library", path, i,
                     i / 3 % CW, i / 3 / CW, (double)a[i], (double)b[i]);
}

/* test_compressions' files, read here exactly as OpenEXR's C++ library reads them (so they are
 * valid files of their compression, chunks stored uncompressed included). */
static void test_tools_own_files(void **state)
{
    (void)state;
    float *known[2] = {smooth(false), smooth(true)};
    for (int compression = 0; compression < EXR_COMPRESSION_LAST_TYPE; compression++) {
        for (int v = 0; v < 8; v++) {
            struct spec sp = compression_spec((exr_compression_t)compression, v);
            const char *path = compression_file(sp.compression, sp.storage, sp.type, sp.alpha);
            write_exr(path, known[sp.type == EXR_PIXEL_FLOAT], &sp);
            float *got = NULL;
            int w, h;
            if (!ao_image_read_linear(path, &got, &w, &h))
                fail_msg("%s: not read", path);
            float *cpp = cpp_decoded(path);
            assert_same(path, got, cpp);
            free(got);
            free(cpp);
        }
    }
    free(known[0]);
    free(known[1]);
}

/* exrmaketiled's files (the C++ library's writer), every compression it offers, half and float,
 * RGB and RGB with a half A, in 16x8 tiles: read here exactly as the C++ library reads them, and
 * as the known image within each compression's bound. DWAA and DWAB, which OpenEXRCore 3.1.5
 * cannot decode, are refused in one line naming the compression (at least one file each; a chunk
 * the writer stored uncompressed could still be read). */
static void test_tools_cpp_files(void **state)
{
    (void)state;
    float *known[2] = {smooth(false), smooth(true)};
    static const char *const offered[] = {"none", "rle", "zip", "piz", "pxr24",
                                          "b44", "b44a", "dwaa", "dwab"};
    for (size_t z = 0; z < sizeof offered / sizeof *offered; z++) {
        exr_compression_t compression = EXR_COMPRESSION_NONE;
        while (strcmp(compression_names[compression], offered[z]) != 0)
            compression++;
        bool dwa = compression == EXR_COMPRESSION_DWAA || compression == EXR_COMPRESSION_DWAB;
        int refused = 0;
        for (int v = 0; v < 4; v++) {
            struct spec sp = compression_spec(EXR_COMPRESSION_NONE, (v & 1) << 1 | (v & 2) << 1);
            const float *rgb = known[sp.type == EXR_PIXEL_FLOAT];
            const char *source = in_dir("source.exr");
            write_exr(source, rgb, &sp);
            char path[600];
            snprintf(path, sizeof path, "%s/cpp_%s_%s%s.exr", dir, offered[z],
                     v & 1 ? "float" : "half", v & 2 ? "_a" : "");
            if (run("exrmaketiled -t 16 8 -z %s '%s' '%s' >/dev/null 2>&1", offered[z], source,
                    path) != 0)
                fail_msg("exrmaketiled -z %s failed", offered[z]);
            float *cpp = cpp_decoded(path), *got = NULL;
            int w, h;
            bool read = ao_image_read_linear(path, &got, &w, &h);
            if (read) {
                assert_same(path, got, cpp);
                check_decoded(path, rgb, got, compression, sp.type);
            } else if (dwa) {
                char message[100];
                snprintf(message, sizeof message, "%s compression cannot be decoded by OpenEXR",
                         offered[z]);
                expect_refused(path, message);
                refused++;
            } else {
                fail_msg("%s: not read", path);
            }
            free(got);
            free(cpp);
        }
        if (dwa && refused == 0)
            fail_msg("no %s file needed decoding: the refusal went untested", offered[z]);
    }
    free(known[0]);
    free(known[1]);
}

int main(int argc, char **argv)
{
    bool tools = argc > 1 && strcmp(argv[1], "tools") == 0;
    if (tools && run("command -v exrmaketiled >/dev/null 2>&1") != 0) {
        printf("SKIP: exrmaketiled (Debian package openexr) is not installed\n");
        return 77;
    }
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/aoview-exr-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir))
        return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_variants),
        cmocka_unit_test(test_malformed),
        cmocka_unit_test(test_compressions),
        cmocka_unit_test(test_dwa_refused),
        cmocka_unit_test(test_sized),
    };
    const struct CMUnitTest tool_tests[] = {
        cmocka_unit_test(test_tools_own_files),
        cmocka_unit_test(test_tools_cpp_files),
    };
    int failed = tools ? cmocka_run_group_tests(tool_tests, NULL, NULL)
                       : cmocka_run_group_tests(tests, NULL, NULL);
    char command[300];
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    if (system(command) != 0)
        failed++;
    return failed;
}
