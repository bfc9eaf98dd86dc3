/* The files a glTF's buffer URIs name, kept inside the model's folder (see load.h).
 *
 * A URI is percent-decoded first (so "%2e%2e" is ".." and "%2F" a separator), then refused when
 * it is empty, has a scheme (data: URIs never get here), is absolute, or climbs out of the folder
 * ("a/../../b"; "." and ".." are resolved by name, never through the file system). The rest is
 * opened one component at a time with openat(O_NOFOLLOW) from a descriptor of the model's folder,
 * so a symbolic link anywhere on the way is refused rather than followed, and no path is looked up
 * twice: what is checked is what is opened. (realpath and a prefix comparison would allow links
 * that stay inside, but the file could change between the check and the open.) */
#include "loader.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The value of a hexadecimal digit, or -1. */
static int hex_digit(char c)
{
    const char *digits = "0123456789abcdef";
    const char *at = c ? strchr(digits, c | 0x20) : NULL;
    return at ? (int)(at - digits) : -1;
}

/* RFC 3986's scheme: a letter, then letters, digits, '+', '-' or '.', then ':'. Its length (up to
 * the colon), or 0 when the URI has none (a relative reference whose first segment holds a colon
 * must be written "./a:b"). */
static size_t scheme_length(const char *uri)
{
    size_t n = 0;
    if (!((uri[0] | 0x20) >= 'a' && (uri[0] | 0x20) <= 'z'))
        return 0;
    while (uri[n] && (((uri[n] | 0x20) >= 'a' && (uri[n] | 0x20) <= 'z') ||
                      (uri[n] >= '0' && uri[n] <= '9') || strchr("+-.", uri[n])))
        n++;
    return uri[n] == ':' ? n : 0;
}

bool ao_load_uri_decode(const char *uri, char *out, size_t size, char *why, size_t why_size)
{
    size_t n = 0, scheme = scheme_length(uri);
    if (scheme) {
        snprintf(why, why_size, "the URI scheme '%.*s:' is not supported (only data: and relative "
                 "file names)", (int)(scheme < 20 ? scheme : 20), uri);
        return false;
    }
    for (const char *p = uri; *p; p++) {
        int hi = p[0] == '%' ? hex_digit(p[1]) : 0, lo = p[0] == '%' && hi >= 0 ? hex_digit(p[2]) : 0;
        if (hi < 0 || lo < 0) {
            snprintf(why, why_size, "'%%' at byte %zu is not followed by two hexadecimal digits",
                     (size_t)(p - uri));
            return false;
        }
        char c = p[0] == '%' ? (char)(hi << 4 | lo) : p[0];
        p += p[0] == '%' ? 2 : 0;
        if (c == '\0') {
            snprintf(why, why_size, "the URI holds an encoded NUL byte (%%00)");
            return false;
        }
        if (n + 1 >= size) {
            snprintf(why, why_size, "the decoded file name is longer than %zu bytes", size - 1);
            return false;
        }
        out[n++] = c;
    }
    out[n] = '\0';
    if (n == 0)
        snprintf(why, why_size, "the URI is empty");
    else if (out[0] == '/')
        snprintf(why, why_size, "an absolute path (buffers must lie in the model's folder)");
    return n > 0 && out[0] != '/';
}

/* Rewrites the relative path in place without "." and ".." segments or empty ones ("a//b"),
 * resolving ".." by name. Returns -1 when it climbs above the start, 0 when nothing is left (it
 * names the start itself), 1 otherwise. */
static int resolve_dots(char *path)
{
    size_t kept = 0;   /* length of the resolved prefix written at path */
    for (char *p = path; *p;) {
        char *end = strchr(p, '/');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        char *next = end ? end + 1 : p + n;
        if (n == 2 && p[0] == '.' && p[1] == '.') {
            if (kept == 0)
                return -1;
            while (kept > 0 && path[kept - 1] != '/')
                kept--;
            kept -= kept > 0;   /* the slash before the dropped segment */
        } else if (n > 0 && !(n == 1 && p[0] == '.')) {
            if (kept)
                path[kept++] = '/';
            memmove(path + kept, p, n);
            kept += n;
        }
        p = next;
    }
    path[kept] = '\0';
    return kept > 0;
}

/* Why openat(dir, name) failed, in words: O_NOFOLLOW makes a link ELOOP, or ENOTDIR where a
 * directory was asked for, so a link is recognized by looking at it. */
static const char *open_error(int dir, const char *name, int error)
{
    struct stat st;
    if ((error == ELOOP || error == ENOTDIR) && fstatat(dir, name, &st, AT_SYMLINK_NOFOLLOW) == 0 &&
        S_ISLNK(st.st_mode))
        return "a symbolic link (links are not followed, out of the model's folder or within it)";
    return error == ENOTDIR ? "a directory on the way is not a directory" : strerror(error);
}

bool ao_load_uri_open(const char *model_path, const char *relative, int *fd, char *why, size_t why_size)
{
    /* The model's folder, as the user named the model (links there are the user's choice). */
    const char *slash = strrchr(model_path, '/');
    char *folder = slash ? strndup(model_path, slash == model_path ? 1 : (size_t)(slash - model_path))
                         : strdup(".");
    char *path = strdup(relative);
    int dir = folder ? open(folder, O_RDONLY | O_DIRECTORY | O_CLOEXEC) : -1;
    int error = errno, resolved;
    *fd = -1;
    if (!folder || !path) {
        snprintf(why, why_size, "out of memory");
    } else if (dir < 0) {
        snprintf(why, why_size, "cannot open the model's folder: %s", strerror(error));
    } else if ((resolved = resolve_dots(path)) <= 0) {
        snprintf(why, why_size, resolved < 0 ? "it leaves the model's folder"
                                             : "it names the model's folder, not a file");
    } else {
        /* One component at a time, never following a link; each directory is closed once the
         * next is open. O_NONBLOCK: a FIFO opens at once, for the reader to refuse. */
        for (char *p = path; p && dir >= 0;) {
            char *end = strchr(p, '/');
            if (end)
                *end = '\0';
            int flags = O_RDONLY | O_NOFOLLOW | O_CLOEXEC | (end ? O_DIRECTORY : O_NONBLOCK);
            int next = openat(dir, p, flags);
            if (next < 0)
                snprintf(why, why_size, "cannot open '%s': %s", p, open_error(dir, p, errno));
            close(dir);
            dir = -1;
            if (next >= 0 && end)
                dir = next;
            else if (next >= 0)
                *fd = next;
            p = end ? end + 1 : NULL;
        }
    }
    if (dir >= 0)
        close(dir);
    free(folder);
    free(path);
    return *fd >= 0;
}
