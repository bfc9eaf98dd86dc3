/* Escaping user text for one-line messages, and the messages' way to the host's sink; see text.h. */
#include "text.h"

#include <assert.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>

/* The process's sink (ao_text_set_sink), and this thread's route (ao_text_route; NULL: the
 * process's). */
static _Atomic(const struct ao_text_sink *) process_sink;
static _Thread_local const struct ao_text_sink *route;

/* The escape for the character at s, written into esc where it is not a constant, and the bytes
 * it stands for in *used (1, or 2 for a UTF-8 C1 control); NULL when the byte is kept as it is. */
static const char *escape(const unsigned char *s, size_t *used, char esc[9])
{
    *used = 1;
    switch (s[0]) {
    case '\n': return "\\n";
    case '\r': return "\\r";
    case '\t': return "\\t";
    case '\\': return "\\\\";
    default: break;
    }
    if (s[0] < 0x20 || s[0] == 0x7f) {
        snprintf(esc, 9, "\\x%02x", s[0]);
        return esc;
    }
    if (s[0] == 0xc2 && s[1] >= 0x80 && s[1] <= 0x9f) {
        *used = 2;
        snprintf(esc, 9, "\\xc2\\x%02x", s[1]);
        return esc;
    }
    return NULL;
}

/* The length of s escaped. */
static size_t escaped_length(const unsigned char *p)
{
    size_t n = 0, used;
    for (char buffer[9]; *p; p += used) {
        const char *esc = escape(p, &used, buffer);
        n += esc ? strlen(esc) : 1;
    }
    return n;
}

const char *ao_text_escape(const char *s, char *out, size_t size)
{
    assert(size >= 8);
    const unsigned char *p = (const unsigned char *)s;
    /* All of it, or what leaves room for "..." and the NUL. */
    size_t room = escaped_length(p) < size ? size - 1 : size - 4, n = 0, used;
    for (char buffer[9]; *p; p += used) {
        const char *esc = escape(p, &used, buffer);
        size_t len = esc ? strlen(esc) : 1;
        if (n + len > room)
            break;
        memcpy(out + n, esc ? esc : (const char *)p, len);
        n += len;
    }
    strcpy(out + n, *p ? "..." : "");
    return out;
}

void ao_text_set_sink(const struct ao_text_sink *sink)
{
    atomic_store(&process_sink, sink);
}

const struct ao_text_sink *ao_text_route(const struct ao_text_sink *sink)
{
    const struct ao_text_sink *before = route;
    route = sink;
    return before;
}

const struct ao_text_sink *ao_text_current(void)
{
    return route ? route : atomic_load(&process_sink);
}

/* Formats, escapes and hands the line to this thread's sink. */
static void emit(enum ao_text_level level, const char *format, va_list args)
{
    char text[AO_TEXT_SIZE + 4096], line[4 * sizeof text]; /* a path of PATH_MAX and its reason */
    vsnprintf(text, sizeof text, format, args);
    ao_text_escape(text, line, sizeof line);
    const struct ao_text_sink *sink = ao_text_current();
    if (sink && sink->write)
        sink->write(sink->user, level, line);
}

void ao_text_report(const char *format, ...)
{
    va_list args;
    va_start(args, format);
    emit(AO_TEXT_ERROR, format, args);
    va_end(args);
}

void ao_text_vreport_at(const char *path, size_t line, const char *format, va_list args)
{
    char message[512];
    vsnprintf(message, sizeof message, format, args);
    if (line)
        ao_text_report("%s:%zu: %s", path, line, message);
    else
        ao_text_report("%s: %s", path, message);
}

void ao_text_report_at(const char *path, size_t line, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    ao_text_vreport_at(path, line, format, args);
    va_end(args);
}

void ao_text_note(const char *format, ...)
{
    va_list args;
    va_start(args, format);
    emit(AO_TEXT_NOTE, format, args);
    va_end(args);
}
