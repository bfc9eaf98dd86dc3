/* Whole-file reading; see file.h. */
#include "file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "text.h"

/* How long ao_file_open_output waits for a FIFO's reader, and how often it looks. */
enum { READER_WAIT_MS = 2000, READER_POLL_MS = 10 };

/* Why st cannot be read as a file, or NULL when it can. */
static const char *unreadable(const struct stat *st)
{
    if (S_ISDIR(st->st_mode))
        return "is a directory";
    if (!S_ISREG(st->st_mode))
        return "not a regular file";
    if ((uintmax_t)st->st_size >= SIZE_MAX)
        return "file too large";
    return NULL;
}

bool ao_file_read(const char *path, char **text, size_t *size)
{
    /* Non-blocking, so that opening a FIFO returns at once (to be refused below). */
    int fd = open(path, O_RDONLY | O_NONBLOCK);
    if (fd < 0) {
        fprintf(stderr, "%s: cannot open: %s\n", path, strerror(errno));
        return false;
    }
    struct stat st;
    const char *reason = fstat(fd, &st) != 0 ? "cannot stat the file" : unreadable(&st);
    FILE *file = reason ? NULL : fdopen(fd, "rb");
    if (!reason && !file)
        reason = "cannot open";
    if (!reason && !(*text = malloc((size_t)st.st_size + 1)))
        reason = "out of memory";
    if (!reason && fread(*text, 1, (size_t)st.st_size, file) != (size_t)st.st_size) {
        free(*text);
        reason = "read error";
    }
    if (file)
        fclose(file);
    else
        close(fd);
    if (reason) {
        fprintf(stderr, "%s: %s\n", path, reason);
        return false;
    }
    *size = (size_t)st.st_size;
    (*text)[*size] = '\0';
    return true;
}

/* One attempt at opening path for writing without blocking: created exclusively (*created), else
 * as it is, else (a link to a missing file) its target; -1 with errno. */
static int open_output(const char *path, bool *created)
{
    int flags = O_WRONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC;
    int fd = open(path, flags | O_CREAT | O_EXCL, 0666);
    *created = fd >= 0;
    if (fd < 0 && errno == EEXIST)
        fd = open(path, flags);
    if (fd < 0 && errno == ENOENT)
        fd = open(path, flags | O_CREAT, 0666);
    return fd;
}

FILE *ao_file_open_output(const char *path, const char *what, bool *created)
{
    int fd = open_output(path, created);
    for (int waited = 0; fd < 0 && errno == ENXIO && waited < READER_WAIT_MS; waited += READER_POLL_MS) {
        nanosleep(&(struct timespec){.tv_nsec = READER_POLL_MS * 1000000L}, NULL);
        fd = open_output(path, created);
    }
    int err = errno;
    FILE *file = NULL;
    if (fd >= 0) {
        int flags = fcntl(fd, F_GETFL);
        file = flags >= 0 && fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) == 0 ? fdopen(fd, "w") : NULL;
        err = errno;
        if (!file) {
            close(fd);
            if (*created)
                unlink(path);
        }
    }
    if (!file) {
        char name[AO_TEXT_SIZE];
        fprintf(stderr, "%s: cannot write %s: %s\n", what, ao_text_escape(path, name, sizeof name),
                err == ENXIO ? "a FIFO that no process reads" : strerror(err));
        *created = false;
    }
    return file;
}
