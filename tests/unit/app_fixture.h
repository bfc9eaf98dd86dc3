/* What the unit tests of the front ends' rooms share (test_app_report.c, test_app_output.c,
 * test_app_signals.c, test_app_load.c): a scratch folder, stderr caught as the programs write it
 * (their own lines, and the core's through ao_program_init's sink), a file read whole, and a run
 * loaded from a command line. */
#ifndef AO_TEST_APP_FIXTURE_H
#define AO_TEST_APP_FIXTURE_H

#include <stdbool.h>
#include <stddef.h>

#include "app.h"
#include "cli.h"
#include "frame.h"
#include "render_config.h"

/* The scratch folder of this run (app_fixture_setup) and the source tree (AO_SOURCE_ROOT). */
extern char scratch[4096];
extern char source_root[4096];

/* cmocka group setup: installs the programs' stderr sink (ao_program_init), reads AO_SOURCE_ROOT
 * and makes the scratch folder under $TMPDIR (or /tmp); teardown removes it with its files. */
int app_fixture_setup(void **state);
int app_fixture_teardown(void **state);

/* A path in the scratch folder (or, with source_path, the source tree), in the next of 8 rotating
 * buffers: a test holds at most 8 at once. */
const char *scratch_path(const char *name);
const char *source_path(const char *name);

/* Sends descriptor 2 into a fresh temporary file until stderr_end. */
void stderr_begin(void);

/* Puts descriptor 2 back and returns what came while it was caught, NUL-terminated (a static
 * buffer, valid until the next stderr_end; cut at 16 KiB). */
const char *stderr_end(void);

/* The whole of a file, NUL-terminated, malloc'd, its size in *size (NULL: not wanted); NULL when it
 * cannot be read. */
char *read_file(const char *path, size_t *size);

/* Writes text to path (replacing it); false when it cannot. */
bool write_text(const char *path, const char *text);

/* What a test loads: the options, from a command line, and what ao_app_load makes of them. */
struct loaded {
    struct ao_options opts;
    struct ao_app app;   /* zero-initialised by the test, released with ao_app_finish */
    struct ao_render_config config;
    struct ao_settings settings;
};

/* Parses the command line `format` (printf-style; words separated by spaces, no quoting) into
 * l->opts as aoview's main does, then loads it into l->app (ao_app_load); returns its status, or -1
 * after a line on stderr when ao_cli_parse refuses the line. l->opts points into a static copy of
 * the words, valid until the next call. */
int load_line(struct loaded *l, const char *format, ...);

#endif
