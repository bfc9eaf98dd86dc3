/* The front ends' rooms' test fixture; see app_fixture.h. */
#include "app_fixture.h"

#include <dirent.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "app_load.h"
#include "program.h"

char scratch[4096];
char source_root[4096];

static FILE *caught;     /* where descriptor 2 goes between stderr_begin and stderr_end */
static int saved = -1;   /* descriptor 2 before it */

int app_fixture_setup(void **state)
{
    (void)state;
    ao_program_init();
    const char *root = getenv("AO_SOURCE_ROOT"), *tmp = getenv("TMPDIR");
    snprintf(source_root, sizeof source_root, "%s", root ? root : ".");
    snprintf(scratch, sizeof scratch, "%s/aoview-app-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    return mkdtemp(scratch) ? 0 : -1;
}

int app_fixture_teardown(void **state)
{
    (void)state;
    DIR *d = opendir(scratch);
    for (struct dirent *e; d && (e = readdir(d));)
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0)
            unlink(scratch_path(e->d_name));
    if (d)
        closedir(d);
    return rmdir(scratch) == 0 ? 0 : -1;
}

/* dir/name in the next of the rotating buffers. */
static const char *joined(const char *dir, const char *name)
{
    static char paths[8][8192];
    static int next;
    char *p = paths[next++ % 8];
    snprintf(p, sizeof paths[0], "%s/%s", dir, name);
    return p;
}

const char *scratch_path(const char *name)
{
    return joined(scratch, name);
}

const char *source_path(const char *name)
{
    return joined(source_root, name);
}

void stderr_begin(void)
{
    fflush(stderr);
    caught = tmpfile();
    saved = dup(STDERR_FILENO);
    if (caught && saved >= 0)
        dup2(fileno(caught), STDERR_FILENO);
}

const char *stderr_end(void)
{
    static char text[16384];
    text[0] = '\0';
    fflush(stderr);
    if (saved >= 0) {
        dup2(saved, STDERR_FILENO);
        close(saved);
        saved = -1;
    }
    if (caught) {
        rewind(caught);
        text[fread(text, 1, sizeof text - 1, caught)] = '\0';
        fclose(caught);
        caught = NULL;
    }
    return text;
}

char *read_file(const char *path, size_t *size_out)
{
    FILE *f = fopen(path, "rb");
    long size = f && fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    char *text = size >= 0 ? malloc((size_t)size + 1) : NULL;
    if (text) {
        rewind(f);
        text[fread(text, 1, (size_t)size, f)] = '\0';
    }
    if (f)
        fclose(f);
    if (size_out)
        *size_out = text ? (size_t)size : 0;
    return text;
}

bool write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return false;
    bool ok = fputs(text, f) >= 0;
    return fclose(f) == 0 && ok;
}

int load_line(struct loaded *l, const char *format, ...)
{
    static char words[16384];
    char *argv[64], message[512];
    int argc = 0;
    va_list args;
    va_start(args, format);
    vsnprintf(words, sizeof words, format, args);
    va_end(args);
    for (char *w = strtok(words, " "); w && argc < 63; w = strtok(NULL, " "))
        argv[argc++] = w;
    argv[argc] = NULL;
    if (!ao_cli_parse(argc, argv, &l->opts, message, sizeof message)) {
        fprintf(stderr, "%s\n", message);
        return -1;
    }
    return ao_app_load(&l->app, &l->opts, &l->config, &l->settings);
}
