/* What the unit tests share to read the core's messages: this thread's messages caught from
 * capture_begin to capture_end, each line ending in a newline, as stderr would show them. */
#ifndef AO_TEST_CAPTURE_H
#define AO_TEST_CAPTURE_H

#include <pthread.h>
#include <stddef.h>

#include "text.h"

/* One thread's messages under capture (with those of the threads the core starts for its calls,
 * which may come at once: under lock); the sink this thread is routed to while it lasts. */
struct capture {
    struct ao_text_sink sink;
    pthread_mutex_t lock;
    const struct ao_text_sink *before;   /* the route capture_end puts back */
    char text[16384];                    /* the lines, NUL-terminated; cut where they do not fit */
    size_t used;
    int notes, errors;                   /* lines of each level */
};

/* Routes this thread's messages into c (which must stay where it is until capture_end). */
void capture_begin(struct capture *c);

/* A sink's write that only counts the lines, in the atomic_int user points to (atomically: a job's
 * workers may write at once): the process's sink, where no line should come. */
void capture_count(void *user, enum ao_text_level level, const char *line);

/* Routes this thread back and copies what came, NUL-terminated and cut to err_size, into err
 * (NULL: nothing copied, c->text kept). */
void capture_end(struct capture *c, char *err, size_t err_size);

#endif
