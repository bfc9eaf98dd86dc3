/* The core's messages caught for a test; see capture.h. */
#include "capture.h"

#include <stdatomic.h>
#include <stdio.h>
#include <string.h>

/* The sink: appends the line and a newline. */
static void append(void *user, enum ao_text_level level, const char *line)
{
    struct capture *c = user;
    pthread_mutex_lock(&c->lock);
    *(level == AO_TEXT_NOTE ? &c->notes : &c->errors) += 1;
    int n = snprintf(c->text + c->used, sizeof c->text - c->used, "%s\n", line);
    if (n > 0)
        c->used += (size_t)n < sizeof c->text - c->used ? (size_t)n : sizeof c->text - c->used - 1;
    pthread_mutex_unlock(&c->lock);
}

void capture_count(void *user, enum ao_text_level level, const char *line)
{
    (void)level;
    (void)line;
    atomic_fetch_add((atomic_int *)user, 1);
}

void capture_begin(struct capture *c)
{
    memset(c, 0, sizeof *c);
    pthread_mutex_init(&c->lock, NULL);
    c->sink = (struct ao_text_sink){.write = append, .user = c};
    c->before = ao_text_route(&c->sink);
}

void capture_end(struct capture *c, char *err, size_t err_size)
{
    ao_text_route(c->before);
    pthread_mutex_destroy(&c->lock);
    if (err)
        snprintf(err, err_size, "%s", c->text);
}
