/* The programs' side of the core's host interface; see program.h. */
#include "program.h"

#include <stdio.h>

#include "text.h"

/* A message as its own line on stderr, written with one call (stderr is unbuffered), so that the
 * lines of several threads do not interleave. */
static void write_line(void *user, enum ao_text_level level, const char *line)
{
    (void)user;
    (void)level;
    fprintf(stderr, "%s\n", line);
}

void ao_program_init(void)
{
    static const struct ao_text_sink to_stderr = {.write = write_line};
    ao_text_set_sink(&to_stderr);
}
