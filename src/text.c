/* Escaping user text for one-line messages, and the reports made of them; see text.h. */
#include "text.h"

#include <assert.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

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

void ao_text_report(const char *format, ...)
{
    /* Formatted, then escaped, and written with one call so that lines of several threads do not
     * interleave. */
    char text[1024], line[4 * sizeof text + 2];
    va_list args;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    fprintf(stderr, "%s\n", ao_text_escape(text, line, sizeof line));
}
