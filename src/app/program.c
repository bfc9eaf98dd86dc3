/* The programs' side of the core's host interface; see program.h. */
#include "program.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "file.h"
#include "text.h"

/* A message as its own line on stderr, written with one call (stderr is unbuffered), so that the
 * lines of several threads do not interleave. */
static void write_line(void *user, enum ao_text_level level, const char *line)
{
    (void)user;
    (void)level;
    fprintf(stderr, "%s\n", line);
}

/* SIGBUS in a file the core mapped: its one line and status 1, as any runtime error, at once (no
 * way back into a parser reading a page that is gone); write(2) and _exit are async-signal-safe.
 * Any other SIGBUS: the default's, once this handler returns. */
static void on_bus(int sig, siginfo_t *info, void *context)
{
    (void)context;
    size_t length;
    const char *line = ao_file_mapped_line(info->si_addr, &length);
    if (!line) {
        signal(sig, SIG_DFL);
        raise(sig);
        return;
    }
    if (write(STDERR_FILENO, line, length) < 0) {
        /* nowhere left to say it */
    }
    _exit(EXIT_FAILURE);
}

void ao_program_init(void)
{
    static const struct ao_text_sink to_stderr = {.write = write_line};
    ao_text_set_sink(&to_stderr);
    struct sigaction action = {.sa_sigaction = on_bus, .sa_flags = SA_SIGINFO};
    sigemptyset(&action.sa_mask);
    sigaction(SIGBUS, &action, NULL);
}
