/* PNG (through stb) and PFM files, and OpenEXR's chosen by extension (exr.h). Writes go to a
 * temporary file in the target's directory that is renamed into place, so a reader never sees a
 * partial image. The sRGB encoding is image_srgb.c's. */
/* realpath (XSI), for -o through a symbolic link. */
#define _XOPEN_SOURCE 700
#include "image.h"

#include <assert.h>
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <strings.h>

#include <stb_image.h>
#include <stb_image_write.h>

#include "exr.h"
#include "text.h"

static_assert(sizeof(float) == 4 && sizeof(uint32_t) == 4, "PFM needs 32-bit IEEE floats");

/* Pixels handed to a writer; its element type depends on the format. */
struct raster {
    const void *pixels;
    int width, height;
    const char *path;                    /* EXR: for the library's messages */
    const struct ao_image_note *notes;   /* EXR: header attributes */
    size_t note_count;
};

/* Why a read failed: a fixed reason and the errno behind it (0 for format errors). */
struct failure {
    const char *reason;
    int err;
};

static void report(const char *path, const char *reason, int err)
{
    if (err)
        ao_text_report("%s: %s (%s)", path, reason, strerror(err));
    else
        ao_text_report("%s: %s", path, reason);
}

static bool fail(struct failure *out, const char *reason, int err)
{
    out->reason = reason;
    out->err = err;
    return false;
}

/* The temporary files being written, which ao_image_discard_temporaries removes: a slot holds a
 * name from just before the file is created until it is renamed or removed, under temps_lock. */
enum { TEMP_SLOTS = 8 };
static pthread_mutex_t temps_lock = PTHREAD_MUTEX_INITIALIZER;
static char *temps[TEMP_SLOTS];
static atomic_uint written;   /* images renamed into place, under temps_lock */

/* The longest file name in the directory of path (NAME_MAX where it cannot be asked). */
static size_t name_max(const char *path)
{
    const char *slash = strrchr(path, '/');
    long max = -1;
    if (!slash) {
        max = pathconf(".", _PC_NAME_MAX);
    } else if (slash == path) {
        max = pathconf("/", _PC_NAME_MAX);
    } else {
        char *dir = strndup(path, (size_t)(slash - path));
        if (dir)
            max = pathconf(dir, _PC_NAME_MAX);
        free(dir);
    }
    return max > 0 ? (size_t)max : NAME_MAX;
}

/* "<path>.tmp.<pid>.<n>" in path's directory, its file name part cut (at a UTF-8 character) so
 * that the whole stays within name_max bytes; malloc'd, NULL when out of memory. */
static char *temp_name(const char *path, unsigned n)
{
    char suffix[48];
    int suffix_len = snprintf(suffix, sizeof suffix, ".tmp.%ld.%u", (long)getpid(), n);
    const char *slash = strrchr(path, '/');
    size_t dir = slash ? (size_t)(slash + 1 - path) : 0, base = strlen(path + dir), max = name_max(path);
    size_t keep = base + (size_t)suffix_len <= max ? base : max > (size_t)suffix_len ? max - (size_t)suffix_len : 0;
    while (keep > 0 && keep < base && ((unsigned char)path[dir + keep] & 0xc0) == 0x80)
        keep--;
    char *tmp = malloc(dir + keep + (size_t)suffix_len + 1);
    if (tmp)
        sprintf(tmp, "%.*s%s", (int)(dir + keep), path, suffix);
    return tmp;
}

/* Renames the temporary file in slot onto path (NULL: removes it) and forgets it; 0, or the errno
 * of a failed rename (the file is then removed). */
static int finish_temp(int slot, const char *path)
{
    pthread_mutex_lock(&temps_lock);
    char *tmp = temps[slot];
    int err = path && rename(tmp, path) != 0 ? errno : 0;
    if (!path || err)
        unlink(tmp);
    else
        atomic_fetch_add(&written, 1);
    temps[slot] = NULL;
    pthread_mutex_unlock(&temps_lock);
    free(tmp);
    return err;
}

/* Creates a temporary file for path (temp_name) exclusively with mode 0666 less the umask (mkstemp
 * would force 0600 onto the final file) and records it in *slot of temps; NULL with errno set. */
static FILE *create_temp(const char *path, int *slot)
{
    static atomic_uint counter;
    int fd = -1;
    pthread_mutex_lock(&temps_lock);
    for (*slot = 0; *slot < TEMP_SLOTS && temps[*slot]; ++*slot) {
    }
    int err = *slot < TEMP_SLOTS ? EEXIST : EBUSY;  /* EBUSY: more writes at once than aoview makes */
    for (int attempt = 0; fd < 0 && err == EEXIST && attempt < 100; attempt++) {
        char *tmp = temp_name(path, atomic_fetch_add(&counter, 1));
        if (!tmp) {
            err = ENOMEM;
            break;
        }
        temps[*slot] = tmp;
        if ((fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666)) < 0) {
            err = errno;
            temps[*slot] = NULL;
            free(tmp);
        }
    }
    pthread_mutex_unlock(&temps_lock);
    if (fd < 0) {
        errno = err;
        return NULL;
    }
    FILE *f = fdopen(fd, "wb");
    if (!f) {
        err = errno;
        close(fd);
        finish_temp(*slot, NULL);
        errno = err;
    }
    return f;
}

unsigned ao_image_written(void)
{
    return atomic_load(&written);
}

void ao_image_discard_temporaries(void)
{
    pthread_mutex_lock(&temps_lock); /* kept: no write may begin or end after this */
    for (int k = 0; k < TEMP_SLOTS; k++)
        if (temps[k])
            unlink(temps[k]);
}

/* The file an image written to path replaces: path itself, or, when path is a symbolic link, the
 * file it leads to (the link stays: the image is written through it, as a shell's > writes), as a
 * malloc'd name; NULL with errno (ENOENT: a link to nothing) when it cannot be resolved. */
static char *target_of(const char *path)
{
    struct stat st;
    if (lstat(path, &st) != 0 || !S_ISLNK(st.st_mode))
        return strdup(path);
    return realpath(path, NULL);
}

/* Why the existing file st (at target) may not be replaced by an image, or NULL: only a regular file
 * is (a FIFO, a device or a socket is not written into: an image is written whole and renamed into
 * place); not one this user may not write (also through the folder, by renaming), nor one nobody
 * may write (read-only: its mode keeps it so even from root), nor another user's, which the
 * replacement would make this user's (root gives it back its owner). */
static const char *unreplaceable(const char *target, const struct stat *st)
{
    if (S_ISDIR(st->st_mode))
        return "is a directory";
    if (S_ISFIFO(st->st_mode))
        return "is a FIFO, not a regular file (images are written whole and renamed into place)";
    if (S_ISCHR(st->st_mode) || S_ISBLK(st->st_mode))
        return "is a device, not a regular file (images are written whole and renamed into place)";
    if (!S_ISREG(st->st_mode))
        return "is not a regular file (images are written whole and renamed into place)";
    if (faccessat(AT_FDCWD, target, W_OK, AT_EACCESS) != 0)
        return "exists and this user may not write it: it is left as it is";
    if (!(st->st_mode & 0222))
        return "is read-only (no one may write it): it is left as it is";
    if (st->st_uid != geteuid() && geteuid() != 0)
        return "belongs to another user: replacing it would make it this user's, so it is left as it is";
    return NULL;
}

bool ao_image_check_output(const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t base = strlen(slash ? slash + 1 : path), max = name_max(path);
    struct stat st;
    if (base > max) {
        char reason[64];
        snprintf(reason, sizeof reason, "file name longer than %zu bytes", max);
        report(path, reason, 0);
        return false;
    }
    char *target = target_of(path);
    if (!target) {
        report(path, errno == ENOENT ? "is a symbolic link to a missing file" : "cannot follow its symbolic link",
               errno == ENOENT ? 0 : errno);
        return false;
    }
    const char *why = stat(target, &st) == 0 ? unreplaceable(target, &st) : NULL;
    int slot;
    FILE *f = why ? NULL : create_temp(target, &slot);
    int err = errno;
    free(target);
    if (why || !f) {
        report(path, why ? why : "cannot create a file in its directory", why ? 0 : err);
        return false;
    }
    fclose(f);
    finish_temp(slot, NULL);
    return true;
}

/* Runs emit on a temporary file, syncs it and renames it over path (through a symbolic link, over
 * the file it leads to; an existing file's mode and, where this user may set them, owner and group
 * kept); reports any failure once. */
static bool write_atomically(const char *path, bool (*emit)(FILE *f, const struct raster *r),
                             const struct raster *r)
{
    int slot;
    char *target = target_of(path);
    struct stat st;
    bool existed = target && stat(target, &st) == 0;
    const char *why = existed ? unreplaceable(target, &st) : NULL;
    FILE *f = target && !why ? create_temp(target, &slot) : NULL;
    if (!f) {
        report(path, why ? why : !target ? "cannot follow its symbolic link" : "cannot create temporary file",
               why ? 0 : errno);
        free(target);
        return false;
    }
    if (existed && (fchmod(fileno(f), st.st_mode & 07777) != 0 || fchown(fileno(f), st.st_uid, st.st_gid) != 0)) {
        /* kept as far as this user may: a group it is not in becomes its own */
    }
    bool ok = emit(f, r) && fflush(f) == 0 && fsync(fileno(f)) == 0;
    int err = errno;
    if (fclose(f) != 0 && ok) {
        ok = false;
        err = errno;
    }
    const char *reason = ok ? NULL : "cannot write";
    if (!ok)
        finish_temp(slot, NULL);
    else if ((err = finish_temp(slot, target)) != 0)
        reason = "cannot rename temporary file into place";
    free(target);
    if (reason)
        report(path, reason, err);
    return !reason;
}

static void fwrite_callback(void *f, void *data, int size)
{
    fwrite(data, 1, (size_t)size, f);
}

static bool emit_png(FILE *f, const struct raster *r)
{
    return stbi_write_png_to_func(fwrite_callback, f, r->width, r->height, 3, r->pixels,
                                  r->width * 3) && !ferror(f);
}

bool ao_image_write_png(const char *path, const uint8_t *rgb, int width, int height)
{
    assert(width > 0 && height > 0 && width <= AO_IMAGE_MAX_SIDE && height <= AO_IMAGE_MAX_SIDE);
    struct raster r = {rgb, width, height, path, NULL, 0};
    return write_atomically(path, emit_png, &r);
}

static void encode_le(float v, unsigned char *b)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    for (int i = 0; i < 4; i++)
        b[i] = (unsigned char)(u >> (8 * i));
}

static float decode(const unsigned char *b, bool little_endian)
{
    uint32_t u = 0;
    for (int i = 0; i < 4; i++)
        u |= (uint32_t)b[little_endian ? i : 3 - i] << (8 * i);
    float v;
    memcpy(&v, &u, sizeof v);
    return v;
}

/* Writes count floats little-endian, a chunk at a time. */
static bool put_floats(FILE *f, const float *v, size_t count)
{
    unsigned char chunk[4096];
    size_t n = 0;
    for (size_t i = 0; i < count; i++) {
        encode_le(v[i], chunk + n);
        n += 4;
        if (n == sizeof chunk || i + 1 == count) {
            if (fwrite(chunk, 1, n, f) != n)
                return false;
            n = 0;
        }
    }
    return true;
}

static bool emit_pfm(FILE *f, const struct raster *r)
{
    const float *rgb = r->pixels;
    size_t row_floats = (size_t)r->width * 3;
    if (fprintf(f, "PF\n%d %d\n-1.0\n", r->width, r->height) < 0)
        return false;
    for (int row = r->height - 1; row >= 0; row--)
        if (!put_floats(f, rgb + (size_t)row * row_floats, row_floats))
            return false;
    return true;
}

bool ao_image_write_pfm(const char *path, const float *rgb, int width, int height)
{
    assert(width > 0 && height > 0 && width <= AO_IMAGE_MAX_SIDE && height <= AO_IMAGE_MAX_SIDE);
    struct raster r = {rgb, width, height, path, NULL, 0};
    return write_atomically(path, emit_pfm, &r);
}

static bool emit_exr(FILE *f, const struct raster *r)
{
    return ao_exr_emit(f, r->path, r->pixels, r->width, r->height, r->notes, r->note_count);
}

bool ao_image_has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    return n >= e && strcasecmp(path + n - e, ext) == 0;
}

bool ao_image_write_linear(const char *path, const float *rgb, int width, int height,
                           const struct ao_image_note *notes, size_t note_count)
{
    assert(width > 0 && height > 0 && width <= AO_IMAGE_MAX_SIDE && height <= AO_IMAGE_MAX_SIDE);
    if (!ao_image_has_extension(path, ".exr"))
        return ao_image_write_pfm(path, rgb, width, height);
    struct raster r = {rgb, width, height, path, notes, note_count};
    return write_atomically(path, emit_exr, &r);
}

/* Reads one whitespace-delimited header token into buf and consumes the one whitespace
 * character after it, which *delimiter gets; false when the token is missing, too long or not
 * followed by whitespace. */
static bool read_token(FILE *f, char *buf, size_t size, int *delimiter)
{
    int c;
    while ((c = getc(f)) != EOF && isspace(c)) {
    }
    size_t n = 0;
    for (; c != EOF && !isspace(c); c = getc(f)) {
        if (n + 1 == size)
            return false;
        buf[n++] = (char)c;
    }
    buf[n] = '\0';
    *delimiter = c;
    return n > 0 && c != EOF;
}

static bool parse_side(const char *s, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (*end != '\0' || errno != 0 || v < 1 || v > AO_IMAGE_MAX_SIDE)
        return false;
    *out = (int)v;
    return true;
}

/* Parses "PF w h scale"; the scale's sign gives the byte order, its magnitude is ignored. *cr:
 * the scale ended at a carriage return, which may be the first half of a CRLF line end. */
static bool read_header(FILE *f, int *width, int *height, bool *little_endian, bool *cr,
                        struct failure *why)
{
    char magic[8], w[16], h[16], scale[64];
    int delimiter;
    if (!read_token(f, magic, sizeof magic, &delimiter))
        return fail(why, "not a PFM file", 0);
    if (strcmp(magic, "Pf") == 0)
        return fail(why, "greyscale PFM (Pf) is not supported, expected colour (PF)", 0);
    if (strcmp(magic, "PF") != 0)
        return fail(why, "not a PFM file", 0);
    if (!read_token(f, w, sizeof w, &delimiter) || !read_token(f, h, sizeof h, &delimiter) ||
        !read_token(f, scale, sizeof scale, &delimiter))
        return fail(why, "malformed header", 0);
    *cr = delimiter == '\r';
    if (!parse_side(w, width) || !parse_side(h, height) ||
        (int64_t)*width * *height > AO_IMAGE_MAX_PIXELS)
        return fail(why, "bad or too large width and height in header", 0);
    char *end;
    double s = strtod(scale, &end);
    if (*end != '\0' || !isfinite(s) || s == 0.0)
        return fail(why, "bad scale in header", 0);
    *little_endian = s < 0.0;
    return true;
}

/* Checks that exactly need bytes remain in f after the header. After a carriage return (cr), one
 * more byte that is a line feed ends a CRLF header line (files written on Windows) and is skipped:
 * the size decides, since a line feed may as well be a pixel's first byte after a lone CR. */
static bool check_payload_size(FILE *f, uint64_t need, bool cr, struct failure *why)
{
    struct stat st;
    long pos = ftell(f);
    if (pos < 0 || fstat(fileno(f), &st) != 0)
        return fail(why, "cannot read", errno);
    uint64_t left = st.st_size > pos ? (uint64_t)(st.st_size - pos) : 0;
    if (cr && left == need + 1) {
        int c = getc(f);
        if (c == '\n')
            left--;
        else if (c != EOF)
            ungetc(c, f);
    }
    if (left < need)
        return fail(why, "truncated pixel data", 0);
    if (left > need)
        return fail(why, "unexpected data after the pixels", 0);
    return true;
}

/* Reads the rows (stored bottom to top) into a malloc'd top-to-bottom buffer of finite floats. */
static float *read_pixels(FILE *f, int width, int height, bool little_endian, bool cr, struct failure *why)
{
    size_t row_floats = (size_t)width * 3, count = row_floats * (size_t)height;
    if (!check_payload_size(f, (uint64_t)count * 4, cr, why))
        return NULL;
    float *rgb = malloc(count * sizeof *rgb);
    if (!rgb) {
        fail(why, "cannot read", errno);
        return NULL;
    }
    for (int row = height - 1; row >= 0; row--) {
        if (fread(rgb + (size_t)row * row_floats, 4, row_floats, f) != row_floats) {
            fail(why, "cannot read", ferror(f) ? errno : 0);
            free(rgb);
            return NULL;
        }
    }
    for (size_t i = 0; i < count; i++) {
        unsigned char b[4];
        memcpy(b, rgb + i, 4);
        rgb[i] = decode(b, little_endian);
        if (!isfinite(rgb[i])) {
            fail(why, "non-finite pixel value", 0);
            free(rgb);
            return NULL;
        }
    }
    return rgb;
}

/* Reads a PFM file; when want_width is not 0, one of another size is refused after its header. */
static bool read_pfm(const char *path, int want_width, int want_height, float **rgb, int *width,
                     int *height)
{
    /* Non-blocking, so that opening a FIFO returns at once; only regular files are read. */
    int fd = open(path, O_RDONLY | O_NONBLOCK);
    FILE *f = fd >= 0 ? fdopen(fd, "rb") : NULL;
    if (!f) {
        int err = errno;
        if (fd >= 0)
            close(fd);
        report(path, "cannot open", err);
        return false;
    }
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        fclose(f);
        report(path, "not a regular file", 0);
        return false;
    }
    struct failure why = {NULL, 0};
    bool little_endian, cr;
    int w, h;
    float *pixels = NULL;
    if (read_header(f, &w, &h, &little_endian, &cr, &why)) {
        if (want_width && (w != want_width || h != want_height)) {
            fclose(f);
            ao_text_report("%s: the image is %dx%d, not the %dx%d needed", path, w, h,
                    want_width, want_height);
            return false;
        }
        pixels = read_pixels(f, w, h, little_endian, cr, &why);
    }
    fclose(f);
    if (!pixels) {
        report(path, why.reason, why.err);
        return false;
    }
    *rgb = pixels;
    *width = w;
    *height = h;
    return true;
}

bool ao_image_read_pfm(const char *path, float **rgb, int *width, int *height)
{
    return read_pfm(path, 0, 0, rgb, width, height);
}

bool ao_image_read_linear(const char *path, float **rgb, int *width, int *height)
{
    return ao_image_has_extension(path, ".exr") ? ao_exr_read(path, 0, 0, rgb, width, height)
                                                : read_pfm(path, 0, 0, rgb, width, height);
}

bool ao_image_read_linear_sized(const char *path, int width, int height, float **rgb)
{
    assert(width > 0 && height > 0);
    int w, h;
    return ao_image_has_extension(path, ".exr") ? ao_exr_read(path, width, height, rgb, &w, &h)
                                                : read_pfm(path, width, height, rgb, &w, &h);
}

bool ao_image_read_png(const char *path, uint8_t **rgb, int *width, int *height)
{
    int w, h, channels;
    uint8_t *pixels = stbi_load(path, &w, &h, &channels, 3);
    if (!pixels) {
        ao_text_report("%s: cannot read PNG (%s)", path, stbi_failure_reason());
        return false;
    }
    *rgb = pixels;
    *width = w;
    *height = h;
    return true;
}
