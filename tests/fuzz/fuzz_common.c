/* The scratch directory of the fuzz targets: under $TMPDIR (else /tmp), one per process. */
#include "fuzz.h"

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { MAX_FILES = 8, PATH_SIZE = 4096 };

static char dir[PATH_SIZE];
static char files[MAX_FILES][PATH_SIZE];
static int file_count;

/* Removes the remembered files and the directory (atexit). */
static void remove_temp_dir(void)
{
    for (int i = 0; i < file_count; i++)
        unlink(files[i]);
    rmdir(dir);
}

const char *fuzz_temp_dir(void)
{
    if (dir[0])
        return dir;
    const char *base = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/aoview-fuzz-XXXXXX", base && *base ? base : "/tmp");
    if (!mkdtemp(dir)) {
        perror("fuzz: mkdtemp");
        abort();
    }
    atexit(remove_temp_dir);
    return dir;
}

const char *fuzz_temp_path(const char *name)
{
    for (int i = 0; i < file_count; i++) {
        const char *slash = strrchr(files[i], '/');
        if (strcmp(slash + 1, name) == 0)
            return files[i];
    }
    if (file_count == MAX_FILES ||
        snprintf(files[file_count], PATH_SIZE, "%s/%s", fuzz_temp_dir(), name) >= PATH_SIZE) {
        fprintf(stderr, "fuzz: no room for scratch file %s\n", name);
        abort();
    }
    return files[file_count++];
}

void fuzz_write_file(const char *path, const void *data, size_t size)
{
    /* A new inode each time: rewriting a truncated file makes ext4 flush it on close. */
    unlink(path);
    int fd = open(path, O_WRONLY | O_CREAT | O_EXCL, 0600);
    const char *p = data;
    while (fd >= 0 && size > 0) {
        ssize_t n = write(fd, p, size);
        if (n <= 0)
            break;
        p += n;
        size -= (size_t)n;
    }
    if (fd < 0 || size > 0 || close(fd) != 0) {
        perror(path);
        abort();
    }
}
