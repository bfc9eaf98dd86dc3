/* User-supplied text (file names, option values) made safe to quote inside a one-line message, and
 * the core's messages: one line each, escaped, handed to the sink its host installed (the programs:
 * stderr; the Python module: the call's exception or warnings). The core never writes to a
 * descriptor itself. */
#ifndef AO_TEXT_H
#define AO_TEXT_H

#include <stdarg.h>
#include <stddef.h>

/* A buffer size for ao_text_escape that holds most names whole. */
enum { AO_TEXT_SIZE = 1024 };

/* Copies s into out (size bytes, at least 8, NUL-terminated) with control characters, DEL, the
 * C1 controls (UTF-8 0xc2 0x80-0x9f) and backslash written as C escapes (\n, \r, \t, \\, \xNN),
 * so that a message quoting it stays one line and cannot drive the terminal; other bytes (UTF-8
 * names) as they are; ends in "..." where it does not fit. Returns out. Pure; any thread. */
const char *ao_text_escape(const char *s, char *out, size_t size);

/* How much a message matters to its host: a note (the call goes on: "read as decoded", a BVH kept)
 * or an error (the call fails, with this line as its reason). */
enum ao_text_level { AO_TEXT_NOTE, AO_TEXT_ERROR };

/* Where the core's messages go: write(user, level, line) gets one line, already escaped, without a
 * newline (write NULL: dropped). It runs on the thread that made the message: a call's own thread,
 * or one the core started for it (the workers of a job, the render thread), so several at once.
 * The host keeps the sink (and what user points to) alive while any thread is routed to it: for
 * a renderer, until ao_render_destroy; for a tracer building a second BVH, until
 * ao_tracer_destroy. */
struct ao_text_sink {
    void (*write)(void *user, enum ao_text_level level, const char *line);
    void *user;
};

/* Installs the process's sink, where every thread's messages go unless routed elsewhere (the
 * programs: stderr, ao_program_init); NULL, as before any call, drops them. Main thread, before
 * the threads that report start. */
void ao_text_set_sink(const struct ao_text_sink *sink);

/* Routes this thread's messages to sink (NULL: back to the process's) until it is routed again,
 * and returns the route it replaces (NULL: the process's), for the caller to put back. The threads
 * the core starts for a call (the thread team's workers during a job, the render thread, a
 * tracer's second build) are routed to their starter's sink. Any thread; this thread only. */
const struct ao_text_sink *ao_text_route(const struct ao_text_sink *sink);

/* The sink this thread's messages go to now: its route, else the process's (NULL: dropped). Any
 * thread. */
const struct ao_text_sink *ao_text_current(void);

/* One error line to this thread's sink: the printf-formatted text with control characters (a
 * newline in a file name or a JSON string, an escape sequence in a scene token) written as \n,
 * \r, \t or \xNN, so that a message never spans lines or drives the terminal. Any thread. */
void ao_text_report(const char *format, ...);

/* One error line naming where it happened: "path:line: message", or "path: message" when line is
 * 0, the message printf-formatted (its first 511 bytes) and the line escaped as ao_text_report's.
 * Any thread. */
void ao_text_report_at(const char *path, size_t line, const char *format, ...);

/* ao_text_report_at with the message's arguments as a va_list, for the readers' own report
 * functions. Any thread. */
void ao_text_vreport_at(const char *path, size_t line, const char *format, va_list args);

/* One note line, escaped as ao_text_report's: something the host may want to know that does not
 * fail the call. Any thread. */
void ao_text_note(const char *format, ...);

#endif
