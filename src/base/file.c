/* Whole-file reading; see file.h. */
#include "file.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
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

/* Reads exactly length bytes from fd into data; false on an error or an early end. */
static bool read_all(int fd, char *data, size_t length)
{
    while (length > 0) {
        ssize_t got = read(fd, data, length < ((size_t)1 << 30) ? length : (size_t)1 << 30);
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0)
            return false;
        data += got;
        length -= (size_t)got;
    }
    return true;
}

bool ao_file_read_prefix(int fd, size_t length, char **data, const char **why)
{
    struct stat st;
    *why = fstat(fd, &st) != 0 ? "cannot stat the file" : unreadable(&st);
    if (!*why && (uintmax_t)st.st_size < length)
        *why = "the file holds fewer bytes";
    if (!*why && length == SIZE_MAX)
        *why = "file too large";
    if (!*why && !(*data = malloc(length + 1)))
        *why = "out of memory";
    if (!*why && !read_all(fd, *data, length)) {
        free(*data);
        *why = "read error";
    }
    if (*why)
        return false;
    (*data)[length] = '\0';
    return true;
}

/* Whether ao_file_map_budget maps files (ao_file_set_mapping). */
static atomic_bool mapping = true;

/* The live mappings (from ao_file_map_budget to ao_file_unmap), each with the line a SIGBUS in it
 * says, for a program's SIGBUS handler (ao_file_mapped_line). Lock-free, so that several threads
 * may map at once and a signal handler may look: a slot is claimed by setting `used`, filled, then
 * published by storing its start; released by clearing start before the file is unmapped, so that
 * a published slot always names a live mapping. A file mapped while every slot is taken is read. */
enum { MAPPING_SLOTS = 64 };
static struct mapping {
    atomic_bool used;
    _Atomic uintptr_t start;   /* 0: not published */
    atomic_size_t length;      /* the file's bytes (its NUL lies in the same page) */
    size_t line_length;
    char line[AO_TEXT_SIZE + 64]; /* the escaped name and the message fit */
} mappings[MAPPING_SLOTS];

void ao_file_set_mapping(bool on)
{
    atomic_store(&mapping, on);
}

/* Publishes the mapping of path at bytes (length bytes) in a free slot; false when none is free. */
static bool publish_mapping(const char *path, const void *bytes, size_t length)
{
    for (size_t k = 0; k < MAPPING_SLOTS; k++) {
        struct mapping *m = &mappings[k];
        bool free_slot = false;
        if (!atomic_compare_exchange_strong(&m->used, &free_slot, true))
            continue;
        char name[AO_TEXT_SIZE];
        int n = snprintf(m->line, sizeof m->line, "%s: the file shrank while it was being read\n",
                         ao_text_escape(path, name, sizeof name));
        m->line_length = n > 0 && (size_t)n < sizeof m->line ? (size_t)n : strlen(m->line);
        atomic_store(&m->length, length);
        atomic_store(&m->start, (uintptr_t)bytes);
        return true;
    }
    return false;
}

/* Unpublishes the mapping at bytes, if it was published (before it is unmapped). */
static void withdraw_mapping(const void *bytes)
{
    for (size_t k = 0; k < MAPPING_SLOTS; k++) {
        struct mapping *m = &mappings[k];
        if (atomic_load(&m->start) == (uintptr_t)bytes) {
            atomic_store(&m->start, 0);
            atomic_store(&m->used, false);
            return;
        }
    }
}

const char *ao_file_mapped_line(const void *address, size_t *length)
{
    uintptr_t at = (uintptr_t)address;
    for (size_t k = 0; k < MAPPING_SLOTS; k++) {
        struct mapping *m = &mappings[k];
        uintptr_t start = atomic_load(&m->start);
        size_t bytes = atomic_load(&m->length);
        /* start read again: a slot refilled in between for another mapping reads as that mapping,
         * which does not hold the address of this thread's fault */
        if (start && start == atomic_load(&m->start) && at >= start && at - start <= bytes) {
            *length = m->line_length;
            return m->line;
        }
    }
    return NULL;
}

/* The first length bytes of the open file fd at path, a NUL after them, into *data: mapped
 * read-only (*mapped, published for ao_file_mapped_line) when the file ends inside a page, whose
 * rest the system fills with zeros (POSIX) so that the NUL is there; read when the host asked for
 * no mappings, the file ends at a page's end, or it cannot be mapped or published. False with the
 * reason in *why. */
static bool map_file(int fd, const char *path, size_t length, char **data, bool *mapped, const char **why)
{
    bool may = atomic_load(&mapping) && length % (size_t)sysconf(_SC_PAGESIZE) != 0;
    void *bytes = may ? mmap(NULL, length, PROT_READ, MAP_PRIVATE, fd, 0) : MAP_FAILED;
    if (bytes != MAP_FAILED && !publish_mapping(path, bytes, length)) {
        munmap(bytes, length);
        bytes = MAP_FAILED;
    }
    *mapped = bytes != MAP_FAILED;
    if (!*mapped)
        return ao_file_read_prefix(fd, length, data, why);
    posix_madvise(bytes, length, POSIX_MADV_SEQUENTIAL);
    *data = bytes;
    return true;
}

/* ao_file_read (or, given mapped, ao_file_map_budget), charging budget first when there is one. */
static bool read_file(const char *path, struct ao_budget *budget, bool *mapped, char **text, size_t *size)
{
    /* Non-blocking, so that opening a FIFO returns at once (to be refused below). */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        ao_text_report("%s: cannot open: %s", path, strerror(errno));
        return false;
    }
    struct stat st;
    const char *reason = fstat(fd, &st) != 0 ? "cannot stat the file" : unreadable(&st);
    uint64_t charge = reason ? 0 : (uint64_t)st.st_size + 1;
    char why[200] = "";
    bool taken = !reason && budget && ao_budget_take(budget, charge);
    if (!reason && budget && !taken) {
        ao_budget_explain(budget, charge, why, sizeof why);
        reason = why;
    }
    if (!reason && (mapped ? map_file(fd, path, (size_t)st.st_size, text, mapped, &reason)
                        : ao_file_read_prefix(fd, (size_t)st.st_size, text, &reason))) {
        *size = (size_t)st.st_size;
        ao_file_note_input(fd, path);
    }
    else if (taken)
        ao_budget_give(budget, charge);
    close(fd);
    if (reason == why)
        ao_text_report("%s: %llu bytes %s", path, (unsigned long long)st.st_size, why);
    else if (reason)
        ao_text_report("%s: %s", path, reason);
    return !reason;
}

bool ao_file_read(const char *path, char **text, size_t *size)
{
    return read_file(path, NULL, NULL, text, size);
}

bool ao_file_read_budget(const char *path, struct ao_budget *budget, char **text, size_t *size)
{
    return read_file(path, budget, NULL, text, size);
}

bool ao_file_map_budget(const char *path, struct ao_budget *budget, const char **text, size_t *size, bool *mapped)
{
    char *bytes = NULL;
    bool ok = read_file(path, budget, mapped, &bytes, size);
    *text = bytes;
    return ok;
}

void ao_file_unmap(const char *text, size_t size, bool mapped)
{
    if (mapped) {
        withdraw_mapping(text);
        munmap((void *)(uintptr_t)text, size);
    } else
        free((void *)(uintptr_t)text);
}

/* The inputs read so far (ao_file_note_input), under inputs_lock. */
static pthread_mutex_t inputs_lock = PTHREAD_MUTEX_INITIALIZER;
static struct input {
    dev_t dev;
    ino_t ino;
    char *name;
} *inputs;
static size_t input_count, input_capacity;
static atomic_bool remembering;

void ao_file_remember_inputs(void)
{
    atomic_store(&remembering, true);
}

void ao_file_note_input(int fd, const char *path)
{
    if (!atomic_load(&remembering))
        return;
    struct stat st;
    char *name = strdup(path);
    if (fstat(fd, &st) != 0 || !name) {
        free(name);
        return;
    }
    pthread_mutex_lock(&inputs_lock);
    if (input_count == input_capacity) {
        size_t capacity = input_capacity ? 2 * input_capacity : 16;
        struct input *grown = realloc(inputs, capacity * sizeof *grown);
        if (grown) {
            inputs = grown;
            input_capacity = capacity;
        }
    }
    if (input_count < input_capacity)
        inputs[input_count++] = (struct input){st.st_dev, st.st_ino, name};
    else
        free(name);
    pthread_mutex_unlock(&inputs_lock);
}

/* The name of the input read (ao_file_note_input) that is the file of identity (dev, ino), or NULL
 * when none is: the caller frees it. */
static char *input_name(dev_t dev, ino_t ino)
{
    char *name = NULL;
    pthread_mutex_lock(&inputs_lock);
    for (size_t i = 0; !name && i < input_count; i++)
        if (inputs[i].dev == dev && inputs[i].ino == ino)
            name = strdup(inputs[i].name);
    pthread_mutex_unlock(&inputs_lock);
    return name;
}

bool ao_file_check_not_read(const char *role, const char *path, int fd)
{
    struct stat st;
    char *input = (fd >= 0 ? fstat(fd, &st) : stat(path, &st)) == 0 ? input_name(st.st_dev, st.st_ino) : NULL;
    if (!input)
        return true;
    ao_text_report("%s: %s is a file the scene reads (%s): aoview does not overwrite its inputs", role, path, input);
    free(input);
    return false;
}

/* A file as the output checks compare it: an existing file by its identity (through links), one to
 * be made by its folder's identity and its name there. */
struct file_key {
    dev_t dev;
    ino_t ino;
    const char *name;   /* NULL for an existing file */
};

/* The key of path; false when neither it nor its folder exists (a write refuses it anyway). */
static bool key_of(const char *path, struct file_key *key)
{
    struct stat st;
    const char *slash = strrchr(path, '/');
    char folder[4096];
    *key = (struct file_key){0};
    if (stat(path, &st) != 0) {
        snprintf(folder, sizeof folder, "%.*s", slash ? (int)(slash - path + (slash == path)) : 1,
                 slash ? path : ".");
        if (stat(folder, &st) != 0)
            return false;
        key->name = slash ? slash + 1 : path;
    }
    key->dev = st.st_dev;
    key->ino = st.st_ino;
    return true;
}

bool ao_file_check_roles(const struct ao_file_role *files, size_t count)
{
    for (size_t i = 0; i < count; i++) {
        struct file_key a, b;
        if (!files[i].written || !key_of(files[i].path, &a))
            continue;
        for (size_t j = i + 1; j < count; j++) {
            if (!key_of(files[j].path, &b) || a.dev != b.dev || a.ino != b.ino ||
                (a.name || b.name ? !a.name || !b.name || strcmp(a.name, b.name) != 0 : false))
                continue;
            ao_text_report("%s: %s is also %s (%s): %s", files[i].role, files[i].path, files[j].role, files[j].path,
                           files[j].written ? "each output needs a file of its own"
                                            : "aoview does not overwrite its inputs");
            return false;
        }
    }
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
    struct stat st;
    if (fd >= 0 && fstat(fd, &st) == 0 && (S_ISBLK(st.st_mode) || (S_ISREG(st.st_mode) && !(st.st_mode & 0222)))) {
        close(fd);
        fd = -1;
        err = S_ISBLK(st.st_mode) ? ENOTSUP : EROFS;
    }
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
        ao_text_report("%s: cannot write %s: %s", what, path,
                err == ENXIO     ? "a FIFO that no process reads"
                : err == ENOTSUP ? "a block device (a FIFO, a terminal or /dev/null takes rows; a disk does not)"
                : err == EROFS   ? "it is read-only (no one may write it): it is left as it is"
                                 : strerror(err));
        *created = false;
    }
    return file;
}
