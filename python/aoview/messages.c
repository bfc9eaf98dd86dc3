/* The Python module's sink for the core's messages; see messages.h. */
#include "messages.h"

#include <stdio.h>
#include <string.h>

/* Appends line to list (length *used of size bytes) after sep, or counts it as dropped where it
 * would not fit with room left for the count. */
static void append(char *list, size_t size, size_t *used, unsigned *dropped, const char *sep, const char *line)
{
    enum { ROOM = 32 };   /* for "; and 4294967295 more" */
    size_t s = *used ? strlen(sep) : 0, n = strlen(line);
    if (*dropped || *used + s + n + ROOM >= size) {
        (*dropped)++;
        return;
    }
    memcpy(list + *used, sep, s);
    memcpy(list + *used + s, line, n + 1);
    *used += s + n;
}

/* The sink's write: any thread routed to m. */
static void gather(void *user, enum ao_text_level level, const char *line)
{
    struct ao_messages *m = user;
    pthread_mutex_lock(&m->lock);
    if (level == AO_TEXT_ERROR)
        append(m->errors, sizeof m->errors, &m->error_length, &m->errors_dropped, "; ", line);
    else
        append(m->notes, sizeof m->notes, &m->note_length, &m->notes_dropped, "\n", line);
    pthread_mutex_unlock(&m->lock);
}

void ao_messages_begin(struct ao_messages *m)
{
    memset(m, 0, sizeof *m);
    pthread_mutex_init(&m->lock, NULL);
    m->sink = (struct ao_text_sink){.write = gather, .user = m};
    m->before = ao_text_route(&m->sink);
}

void ao_messages_end(struct ao_messages *m)
{
    ao_text_route(m->before);
}

/* Takes list's lines (size bytes, *used of them written) and the count of those dropped out of m
 * into out (size bytes), emptying it. */
static void take(struct ao_messages *m, char *list, size_t size, size_t *used, unsigned *dropped, const char *sep,
                 char *out)
{
    pthread_mutex_lock(&m->lock);
    if (*dropped)   /* append left room for this */
        snprintf(list + *used, size - *used, "%sand %u more", *used ? sep : "", *dropped);
    memcpy(out, list, size);
    list[0] = '\0';
    *used = 0;
    *dropped = 0;
    pthread_mutex_unlock(&m->lock);
}

bool ao_messages_warn(struct ao_messages *m, bool errors)
{
    char notes[sizeof m->notes], lines[sizeof m->errors];
    take(m, m->notes, sizeof m->notes, &m->note_length, &m->notes_dropped, "\n", notes);
    if (errors)
        take(m, m->errors, sizeof m->errors, &m->error_length, &m->errors_dropped, "; ", lines);
    for (char *line = notes, *end; *line; line = end) {
        end = strchr(line, '\n');
        end = end ? (*end = '\0', end + 1) : line + strlen(line);
        if (PyErr_WarnEx(PyExc_UserWarning, line, 2) < 0)
            return false;
    }
    return !errors || !lines[0] || PyErr_WarnEx(PyExc_UserWarning, lines, 2) == 0;
}

bool ao_messages_close(struct ao_messages *m, bool ok, PyObject *type, const char *fallback)
{
    ao_messages_end(m);
    char lines[sizeof m->errors];
    take(m, m->errors, sizeof m->errors, &m->error_length, &m->errors_dropped, "; ", lines);
    bool warned = ao_messages_warn(m, false);
    if (warned && !ok)
        PyErr_SetString(type, lines[0] ? lines : fallback);
    ao_messages_finish(m);
    return ok && warned;
}

void ao_messages_finish(struct ao_messages *m)
{
    pthread_mutex_destroy(&m->lock);
}
