/* OpenEXR through OpenEXRCore, the C API of OpenEXR 3; see exr.h. The only file that includes
 * openexr.h. The library reports through a callback: its first message is kept and printed as the
 * one line of a failed read. Reads go through memory (the file is read whole by ao_file_read,
 * which refuses FIFOs and devices), so the library sees the true size and can check the offsets a
 * header claims against it. */
#include "exr.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#include <openexr.h>

#include "file.h"
#include "text.h"

/* What the library's callbacks see through user_data. */
struct stream {
    FILE *file;                /* writing */
    const char *data;          /* reading: the whole file */
    size_t size;
    char message[256];         /* the library's first error message */
};

/* Keeps the library's first message, on one line, instead of its default print to stderr. */
static void on_error(exr_const_context_t ctxt, exr_result_t code, const char *message)
{
    void *user = NULL;
    if (exr_get_user_data(ctxt, &user) != EXR_ERR_SUCCESS || !user)
        return;
    struct stream *s = user;
    if (s->message[0])
        return;
    snprintf(s->message, sizeof s->message, "%s",
             message ? message : exr_get_default_error_message(code));
    for (char *c = s->message; *c; c++)
        if (*c == '\n' || *c == '\r')
            *c = ' ';
}

/* Writes at an offset of the FILE, as the library's pwrite-like callback. */
static int64_t write_at(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t size,
                        uint64_t offset, exr_stream_error_func_ptr_t error)
{
    (void)ctxt;
    (void)error;
    struct stream *s = user;
    if (offset > INT64_MAX || fseeko(s->file, (off_t)offset, SEEK_SET) != 0 ||
        fwrite(buffer, 1, size, s->file) != size)
        return -1;
    return (int64_t)size;
}

/* Reads from the in-memory file, as the library's pread-like callback. */
static int64_t read_at(exr_const_context_t ctxt, void *user, void *buffer, uint64_t size,
                       uint64_t offset, exr_stream_error_func_ptr_t error)
{
    (void)ctxt;
    (void)error;
    const struct stream *s = user;
    if (offset >= s->size)
        return 0;
    uint64_t n = size < s->size - offset ? size : s->size - offset;
    memcpy(buffer, s->data + offset, n);
    return (int64_t)n;
}

/* The in-memory file's size, so the library can check offsets against it. */
static int64_t size_of(exr_const_context_t ctxt, void *user)
{
    (void)ctxt;
    return (int64_t)((const struct stream *)user)->size;
}

/* ------------------------------------------------------------------ writing */

/* Points the pipeline's channels (B, G, R in the file's order) at the chunk's rows of rgb. */
static void point_channels(exr_encode_pipeline_t *encode, const float *rgb, int width)
{
    for (int c = 0; c < encode->channel_count; c++) {
        exr_coding_channel_info_t *channel = &encode->channels[c];
        int offset = channel->channel_name[0] == 'R' ? 0 : channel->channel_name[0] == 'G' ? 1 : 2;
        const float *row = rgb + (size_t)encode->chunk.start_y * (size_t)width * 3;
        channel->encode_from_ptr = (const uint8_t *)(row + offset);
        channel->user_pixel_stride = 3 * sizeof(float);
        channel->user_line_stride = width * 3 * (int32_t)sizeof(float);
        channel->user_bytes_per_element = sizeof(float);
        channel->user_data_type = EXR_PIXEL_FLOAT;
    }
}

/* The header: one scanline part, channels R, G, B as 32-bit floats, ZIP, the notes. */
static exr_result_t write_header(exr_context_t ctxt, int width, int height,
                                 const struct ao_image_note *notes, size_t note_count)
{
    int part;
    exr_result_t r = exr_add_part(ctxt, "aoview", EXR_STORAGE_SCANLINE, &part);
    if (r == EXR_ERR_SUCCESS)
        r = exr_initialize_required_attr_simple(ctxt, part, width, height, EXR_COMPRESSION_ZIP);
    for (const char *const *name = (const char *const[]){"R", "G", "B", NULL};
         r == EXR_ERR_SUCCESS && *name; name++)
        r = exr_add_channel(ctxt, part, *name, EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1);
    for (size_t i = 0; r == EXR_ERR_SUCCESS && i < note_count; i++)
        r = exr_attr_set_string(ctxt, part, notes[i].key, notes[i].value);
    return r == EXR_ERR_SUCCESS ? exr_write_header(ctxt) : r;
}

/* Every chunk of scanlines, through one encoding pipeline. */
static exr_result_t write_chunks(exr_context_t ctxt, const float *rgb, int width, int height)
{
    int32_t lines;
    exr_result_t r = exr_get_scanlines_per_chunk(ctxt, 0, &lines);
    exr_encode_pipeline_t encode = EXR_ENCODE_PIPELINE_INITIALIZER;
    bool started = false;
    for (int y = 0; r == EXR_ERR_SUCCESS && y < height; y += lines) {
        exr_chunk_info_t chunk;
        r = exr_write_scanline_chunk_info(ctxt, 0, y, &chunk);
        if (r == EXR_ERR_SUCCESS)
            r = started ? exr_encoding_update(ctxt, 0, &chunk, &encode)
                        : exr_encoding_initialize(ctxt, 0, &chunk, &encode);
        started |= r == EXR_ERR_SUCCESS;
        if (r == EXR_ERR_SUCCESS) {
            point_channels(&encode, rgb, width);
            r = exr_encoding_choose_default_routines(ctxt, 0, &encode);
        }
        if (r == EXR_ERR_SUCCESS)
            r = exr_encoding_run(ctxt, 0, &encode);
    }
    if (started)
        exr_encoding_destroy(ctxt, &encode);
    return r;
}

bool ao_exr_emit(FILE *f, const char *path, const float *rgb, int width, int height,
                 const struct ao_image_note *notes, size_t note_count)
{
    struct stream s = {.file = f};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_error;
    init.user_data = &s;
    init.write_fn = write_at;
    exr_context_t ctxt = NULL;
    errno = 0;
    exr_result_t r = exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (r == EXR_ERR_SUCCESS)
        r = write_header(ctxt, width, height, notes, note_count);
    if (r == EXR_ERR_SUCCESS)
        r = write_chunks(ctxt, rgb, width, height);
    /* exr_finish writes the chunk offset table, so its result counts too. */
    exr_result_t finished = ctxt ? exr_finish(&ctxt) : EXR_ERR_SUCCESS;
    if (r == EXR_ERR_SUCCESS)
        r = finished;
    if (r != EXR_ERR_SUCCESS && errno == 0)
        errno = r == EXR_ERR_OUT_OF_MEMORY ? ENOMEM : EIO;
    return r == EXR_ERR_SUCCESS;
}

/* ------------------------------------------------------------------ reading */

/* The compression's name as OpenEXR's tools spell it (exrheader, exrmaketiled -z). */
static const char *compression_name(exr_compression_t compression)
{
    static const char *const names[] = {"none", "rle", "zips", "zip", "piz",
                                        "pxr24", "b44", "b44a", "dwaa", "dwab"};
    return (unsigned)compression < sizeof names / sizeof *names ? names[compression] : "unknown";
}

/* Which of R, G, B (0, 1, 2) a channel name is, or -1 for any other channel (A, Z, layers). */
static int rgb_index(const char *name)
{
    return strcmp(name, "R") == 0 ? 0 : strcmp(name, "G") == 0 ? 1 : strcmp(name, "B") == 0 ? 2 : -1;
}

/* Checks that the part holds R, G and B, unsubsampled, as half or float; NULL or the reason. */
static const char *check_channels(exr_const_context_t ctxt)
{
    const exr_attr_chlist_t *channels;
    if (exr_get_channels(ctxt, 0, &channels) != EXR_ERR_SUCCESS)
        return "no channel list";
    int found = 0;
    for (int i = 0; i < channels->num_channels; i++) {
        const exr_attr_chlist_entry_t *e = &channels->entries[i];
        int c = rgb_index(e->name.str);
        if (c < 0)
            continue;
        if (e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT)
            return "R, G and B must be half or float channels";
        if (e->x_sampling != 1 || e->y_sampling != 1)
            return "subsampled R, G or B channels are not supported";
        found |= 1 << c;
    }
    return found == 7 ? NULL
                      : "no R, G and B channels (greyscale, YC and layered images are not supported)";
}

/* The part's chunks in file order: blocks of scanlines, or the tiles of level 0 row by row. */
struct layout {
    exr_storage_t storage;
    exr_compression_t compression;
    exr_attr_box2i_t window;
    int32_t step_x, step_y;      /* a tile's size, or the window's width and the lines per block */
    int64_t columns, count;      /* chunks per row of chunks, and in all */
};

/* Reads the layout from the header; false if the library cannot say. */
static bool get_layout(exr_const_context_t ctxt, exr_storage_t storage, exr_attr_box2i_t window,
                       struct layout *l)
{
    *l = (struct layout){.storage = storage, .window = window};
    int64_t width = (int64_t)window.max.x - window.min.x + 1;
    int64_t height = (int64_t)window.max.y - window.min.y + 1;
    if (exr_get_compression(ctxt, 0, &l->compression) != EXR_ERR_SUCCESS)
        return false;
    if (storage == EXR_STORAGE_SCANLINE) {
        l->step_x = (int32_t)width;
        if (exr_get_scanlines_per_chunk(ctxt, 0, &l->step_y) != EXR_ERR_SUCCESS)
            return false;
    } else if (exr_get_tile_sizes(ctxt, 0, 0, 0, &l->step_x, &l->step_y) != EXR_ERR_SUCCESS) {
        return false;
    }
    if (l->step_x < 1 || l->step_y < 1)
        return false;
    l->columns = (width + l->step_x - 1) / l->step_x;
    l->count = l->columns * ((height + l->step_y - 1) / l->step_y);
    return true;
}

/* Reads the header of chunk i (not its data) and the pixel position of its top-left corner (a
 * tile's chunk info gives tile numbers, not pixels). */
static exr_result_t chunk_info(exr_const_context_t ctxt, const struct layout *l, int64_t i,
                               exr_chunk_info_t *chunk, int64_t *x, int64_t *y)
{
    int64_t column = i % l->columns, row = i / l->columns;
    *x = l->window.min.x + column * l->step_x;
    *y = l->window.min.y + row * l->step_y;
    if (l->storage == EXR_STORAGE_SCANLINE)
        return exr_read_scanline_chunk_info(ctxt, 0, (int)*y, chunk);
    return exr_read_tile_chunk_info(ctxt, 0, (int)column, (int)row, 0, 0, chunk);
}

/* Checks every chunk's stored size, read from the chunk headers alone, against the bytes its
 * pixels take uncompressed (which the library derives from the header, not from the chunk): an
 * uncompressed chunk must store exactly that many, a compressed one from 1 to that many (as many
 * means stored uncompressed, as writers do when compression would not shrink a chunk). So no
 * pixel is decoded from bytes the file does not hold, and nothing is allocated for the pixels
 * before the file is known to hold them all. False with the reason in why. */
static bool check_chunks(exr_const_context_t ctxt, const struct layout *l, char *why,
                         size_t why_size, exr_result_t *result)
{
    for (int64_t i = 0; i < l->count; i++) {
        exr_chunk_info_t chunk;
        int64_t x, y;
        if ((*result = chunk_info(ctxt, l, i, &chunk, &x, &y)) != EXR_ERR_SUCCESS) {
            snprintf(why, why_size, "cannot decode the pixels");
            return false;
        }
        bool raw = l->compression == EXR_COMPRESSION_NONE;
        if (raw ? chunk.packed_size == chunk.unpacked_size
                : chunk.packed_size >= 1 && chunk.packed_size <= chunk.unpacked_size)
            continue;
        char where[64];
        if (l->storage == EXR_STORAGE_SCANLINE && chunk.height == 1)
            snprintf(where, sizeof where, "the chunk of row %d", chunk.start_y);
        else if (l->storage == EXR_STORAGE_SCANLINE)
            snprintf(where, sizeof where, "the chunk of rows %d to %d", chunk.start_y,
                     chunk.start_y + chunk.height - 1);
        else
            snprintf(where, sizeof where, "tile (%lld, %lld)", (long long)(i % l->columns),
                     (long long)(i / l->columns));
        snprintf(why, why_size, "%s stores %llu bytes%s%s%s where its pixels need %s%llu", where,
                 (unsigned long long)chunk.packed_size, raw ? "" : " of ",
                 raw ? "" : compression_name(l->compression), raw ? "" : " data",
                 raw ? "" : "1 to ", (unsigned long long)chunk.unpacked_size);
        return false;
    }
    return true;
}

/* The library's decompressor for the part, wrapped by decompress (through decoding_user_data). */
struct decompressor {
    exr_result_t (*run)(exr_decode_pipeline_t *decode);
};

/* Leaves a chunk stored uncompressed (as many bytes stored as its pixels take) as it is, and
 * decompresses any other. OpenEXRCore 3.1.5 points the unpacked buffer at such a chunk's bytes
 * but still runs its B44 and B44A decoders over them in place, which puts float channels' rows
 * (and any partial tile's pixels) in the wrong place; OpenEXR's C++ library, which writes such
 * chunks, reads them as they are. */
static exr_result_t decompress(exr_decode_pipeline_t *decode)
{
    const struct decompressor *d = decode->decoding_user_data;
    if (decode->chunk.packed_size == decode->chunk.unpacked_size &&
        decode->unpacked_buffer == decode->packed_buffer)
        return EXR_ERR_SUCCESS;
    return d->run(decode);
}

/* Decodes one chunk's R, G and B into rgb (the data window's top-left at rgb[0]), as floats; the
 * chunk's top-left pixel is (x, y). */
static exr_result_t decode_chunk(exr_const_context_t ctxt, const exr_chunk_info_t *chunk,
                                 int64_t x, int64_t y, exr_decode_pipeline_t *decode,
                                 struct decompressor *d, bool *started, float *rgb,
                                 exr_attr_box2i_t window)
{
    int width = window.max.x - window.min.x + 1;
    exr_result_t r = *started ? exr_decoding_update(ctxt, 0, chunk, decode)
                              : exr_decoding_initialize(ctxt, 0, chunk, decode);
    if (r != EXR_ERR_SUCCESS)
        return r;
    *started = true;
    size_t first = (size_t)(y - window.min.y) * (size_t)width + (size_t)(x - window.min.x);
    for (int c = 0; c < decode->channel_count; c++) {
        exr_coding_channel_info_t *channel = &decode->channels[c];
        int index = rgb_index(channel->channel_name);
        channel->decode_to_ptr = index < 0 ? NULL : (uint8_t *)(rgb + 3 * first + index);
        channel->user_pixel_stride = 3 * sizeof(float);
        channel->user_line_stride = width * 3 * (int32_t)sizeof(float);
        channel->user_bytes_per_element = sizeof(float);
        channel->user_data_type = EXR_PIXEL_FLOAT;
    }
    r = exr_decoding_choose_default_routines(ctxt, 0, decode);
    if (r == EXR_ERR_SUCCESS && decode->decompress_fn && decode->decompress_fn != decompress) {
        d->run = decode->decompress_fn;
        decode->decompress_fn = decompress;
        decode->decoding_user_data = d;
    }
    return r == EXR_ERR_SUCCESS ? exr_decoding_run(ctxt, 0, decode) : r;
}

/* Every chunk of the part into rgb. */
static exr_result_t read_chunks(exr_const_context_t ctxt, const struct layout *l, float *rgb)
{
    exr_decode_pipeline_t decode = EXR_DECODE_PIPELINE_INITIALIZER;
    struct decompressor d = {NULL};
    bool started = false;
    exr_result_t r = EXR_ERR_SUCCESS;
    for (int64_t i = 0; r == EXR_ERR_SUCCESS && i < l->count; i++) {
        exr_chunk_info_t chunk;
        int64_t x, y;
        r = chunk_info(ctxt, l, i, &chunk, &x, &y);
        if (r == EXR_ERR_SUCCESS)
            r = decode_chunk(ctxt, &chunk, x, l->storage == EXR_STORAGE_SCANLINE ? chunk.start_y : y,
                             &decode, &d, &started, rgb, l->window);
    }
    if (started)
        exr_decoding_destroy(ctxt, &decode);
    return r;
}

/* The header's data window as width and height, or false if it is empty or past the limits. */
static bool window_size(exr_attr_box2i_t window, int *width, int *height)
{
    int64_t w = (int64_t)window.max.x - window.min.x + 1, h = (int64_t)window.max.y - window.min.y + 1;
    if (w < 1 || w > AO_IMAGE_MAX_SIDE || h < 1 || h > AO_IMAGE_MAX_SIDE || w * h > AO_IMAGE_MAX_PIXELS)
        return false;
    *width = (int)w;
    *height = (int)h;
    return true;
}

/* Why a read failed: the reason, and whether the library's first message belongs after it. */
struct failure {
    char why[200];
    bool quote;
};

/* Sets the reason (a printf format) and returns false. */
static bool failed(struct failure *f, bool quote, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vsnprintf(f->why, sizeof f->why, format, args);
    va_end(args);
    f->quote = quote;
    return false;
}

/* Reads the first part of the opened file into a new buffer: the header's checks (the size
 * before any pixel buffer exists), every chunk's stored size, then the pixels. */
static bool read_part(exr_const_context_t ctxt, int want_width, int want_height, float **out,
                      int *width, int *height, struct failure *f)
{
    exr_storage_t storage;
    exr_attr_box2i_t window;
    struct layout layout;
    const char *reason;
    if (exr_get_storage(ctxt, 0, &storage) != EXR_ERR_SUCCESS ||
        (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED))
        return failed(f, true, "deep images are not supported");
    if (exr_get_data_window(ctxt, 0, &window) != EXR_ERR_SUCCESS)
        return failed(f, true, "no data window");
    if (!window_size(window, width, height))
        return failed(f, false, "bad or too large data window");
    if (want_width && (*width != want_width || *height != want_height))
        return failed(f, false, "the image is %dx%d, not the %dx%d needed", *width, *height,
                      want_width, want_height);
    if ((reason = check_channels(ctxt)) != NULL)
        return failed(f, false, "%s", reason);
    if (!get_layout(ctxt, storage, window, &layout))
        return failed(f, true, "bad compression or tile description");
    exr_result_t r = EXR_ERR_SUCCESS;
    if (!check_chunks(ctxt, &layout, f->why, sizeof f->why, &r)) {
        f->quote = r != EXR_ERR_SUCCESS;
        return false;
    }
    size_t count = (size_t)*width * (size_t)*height * 3;
    float *rgb = calloc(count, sizeof *rgb);
    if (!rgb)
        return failed(f, false, "out of memory");
    r = read_chunks(ctxt, &layout, rgb);
    bool ok = r == EXR_ERR_SUCCESS;
    if (r == EXR_ERR_FEATURE_NOT_IMPLEMENTED) {
        int major = 0, minor = 0, patch = 0;
        exr_get_library_version(&major, &minor, &patch, NULL);
        failed(f, false, "%s compression cannot be decoded by OpenEXR %d.%d.%d's C library",
               compression_name(layout.compression), major, minor, patch);
    } else if (!ok) {
        failed(f, true, "cannot decode the pixels");
    }
    for (size_t i = 0; ok && i < count; i++)
        if (!isfinite(rgb[i]))
            ok = failed(f, false, "non-finite pixel value");
    if (!ok) {
        free(rgb);
        return false;
    }
    *out = rgb;
    return true;
}

bool ao_exr_read(const char *path, int want_width, int want_height, float **rgb, int *width,
                 int *height)
{
    struct stream s = {.message = ""};
    char *data;
    if (!ao_file_read(path, &data, &s.size))
        return false;
    s.data = data;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_error;
    init.user_data = &s;
    init.read_fn = read_at;
    init.size_fn = size_of;
    init.max_image_width = init.max_image_height = AO_IMAGE_MAX_SIDE;
    init.max_tile_width = init.max_tile_height = AO_IMAGE_MAX_SIDE;
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    exr_context_t ctxt = NULL;
    struct failure f = {"", false};
    int w = 0, h = 0;
    /* A header attribute of a value OpenEXR does not define (compression 10 or 255, lineOrder 9) is
     * reported by the library, which then reads the file with its default in place (chunks stored
     * raw read as if uncompressed): refused, as OpenEXR's C++ library and exrcheck refuse it. */
    exr_result_t started = exr_start_read(&ctxt, path, &init);
    bool ok = started != EXR_ERR_SUCCESS ? failed(&f, true, "not a readable OpenEXR file")
              : s.message[0]             ? failed(&f, true, "its header holds a value OpenEXR does not define")
                                         : read_part(ctxt, want_width, want_height, rgb, &w, &h, &f);
    if (ctxt)
        exr_finish(&ctxt);
    free(data);
    if (!ok) {
        if (f.quote && s.message[0])
            ao_text_report("%s: %s (%s)", path, f.why, s.message);
        else
            ao_text_report("%s: %s", path, f.why);
        return false;
    }
    *width = w;
    *height = h;
    return true;
}
