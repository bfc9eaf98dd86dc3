/* The Python module's sink for the core's messages (text.h), shared by its two extensions: a call
 * routes its thread to a sink of its own, so that its error lines become its own exception's text
 * and its notes Python warnings, whatever other threads do meanwhile; descriptor 2 is never
 * touched. A render keeps its sink for as long as its thread runs. */
#ifndef AO_PYTHON_MESSAGES_H
#define AO_PYTHON_MESSAGES_H

#include <Python.h>

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>

#include "text.h"

/* The lines of one call (or one render), written by any thread the core routes to it, under lock:
 * errors joined by "; ", notes one per line, each list cut short (with a count of the lines left
 * out) where it would not fit. */
struct ao_messages {
    struct ao_text_sink sink;
    pthread_mutex_t lock;
    char errors[2048], notes[4096];
    size_t error_length, note_length;
    unsigned errors_dropped, notes_dropped;
    const struct ao_text_sink *before;   /* the route that ao_messages_begin replaced */
};

/* Makes m empty and routes the calling thread (and the threads the core starts from it) to it,
 * until ao_messages_end; m must stay alive while any thread is routed to it. Any thread, with or
 * without the GIL. */
void ao_messages_begin(struct ao_messages *m);

/* Routes the calling thread back to where it was before ao_messages_begin (calls nest). The same
 * thread, with or without the GIL. */
void ao_messages_end(struct ao_messages *m);

/* Issues the notes gathered so far as Python warnings (UserWarning, at the caller of the module's
 * Python function) and forgets them; with errors (a render's thread reported one without the call
 * failing) as warnings too when `errors` is true. False with the exception set where a warning was
 * made an error. The GIL held. */
bool ao_messages_warn(struct ao_messages *m, bool errors);

/* Ends a call's messages: ao_messages_end, then where the call succeeded (ok) its notes as
 * warnings, where it failed `type` set with its error lines (or `fallback` where there were none)
 * after its notes, then ao_messages_finish. Returns ok, false too where a warning was made an
 * error (its exception set). The same thread as ao_messages_begin, the GIL held. */
bool ao_messages_close(struct ao_messages *m, bool ok, PyObject *type, const char *fallback);

/* Frees what ao_messages_begin made (after ao_messages_end, and once no thread is routed to m). */
void ao_messages_finish(struct ao_messages *m);

#endif
