/* Whole-file reading; see file.h. */
#include "file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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
