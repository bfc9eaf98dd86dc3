/* User-supplied text (file names, option values) made safe to quote inside a one-line message, and
 * the one-line reports on stderr that every failure prints. */
#ifndef AO_TEXT_H
#define AO_TEXT_H

#include <stddef.h>

/* A buffer size for ao_text_escape that holds most names whole. */
enum { AO_TEXT_SIZE = 1024 };

/* Copies s into out (size bytes, at least 8, NUL-terminated) with control characters, DEL, the
 * C1 controls (UTF-8 0xc2 0x80-0x9f) and backslash written as C escapes (\n, \r, \t, \\, \xNN),
 * so that a message quoting it stays one line and cannot drive the terminal; other bytes (UTF-8
 * names) as they are; ends in "..." where it does not fit. Returns out. Pure; any thread. */
const char *ao_text_escape(const char *s, char *out, size_t size);

/* Prints the printf-formatted text and a newline to stderr as one line: control characters (a
 * newline in a file name or a JSON string, an escape sequence in a scene token) are written as
 * \n, \r, \t or \xNN, so that a report never spans lines or drives the terminal. Any thread. */
void ao_text_report(const char *format, ...);

#endif
