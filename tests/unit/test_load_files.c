/* What every mesh load shares about its file: the extension chooses the format in any case; a
 * missing file, a directory, an unknown extension, an unreadable file each refused with one line;
 * a mapped file shrunk under the parser ends a program (its SIGBUS handler, program.c) with one
 * line, and the core alone installs no handler; mappings of several threads at once, each found
 * by its address; mapping turned off; random changes to valid files load or fail cleanly. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "file.h"
#include "program.h"

#include "mesh_fixture.h"

/* The extension decides the format, in any case. */
static void test_extension_case(void **state)
{
    (void)state;
    static const char *const pairs[][2] = {{"tri.obj", "UPPER.OBJ"}, {"cube.ply", "Mixed.Ply"}};
    for (int i = 0; i < 2; i++) {
        size_t size;
        unsigned char *text = slurp(fixture(pairs[i][0]), &size);
        struct ao_mesh mesh;
        load_ok(&mesh, temp_file(pairs[i][1], text, size));
        assert_mesh_valid(&mesh);
        ao_mesh_finish(&mesh);
        free(text);
    }
}

/* A missing file, a directory, an unknown or absent extension. */
static void test_file_errors(void **state)
{
    (void)state;
    char *dir = path_buffer();
    snprintf(dir, 4200, "%s/dir.obj", temp_dir);
    assert_int_equal(mkdir(dir, 0700), 0);
    expect_failure(fixture("missing.obj"), ": ", "cannot open: No such file");
    expect_failure(dir, ": ", "is a directory");
    expect_failure(fixture("tri.3ds"), ": ", "unknown mesh format");
    expect_failure(data_dir, ": ", "unknown mesh format");
    expect_failure("dir.obj/file", ": ", "unknown mesh format");
}

/* A file without read permission (not testable as root, who may read anything). */
static void test_unreadable_file(void **state)
{
    (void)state;
    const char *path = temp_file("locked.obj", "v 0 0 0\n", 8);
    assert_int_equal(chmod(path, 0), 0);
    FILE *probe = fopen(path, "rb");
    if (probe) {
        fclose(probe);
        skip();
    }
    expect_failure(path, ": ", "cannot open: Permission denied");
}

/* Runs a child that maps a file of 3 pages and more, shrinks it to 10 bytes and reads its last
 * byte, after ao_program_init when `program`, else with SIGBUS as by default (not cmocka's
 * handler, which would run the other tests in the child); its status in *status, and what it
 * wrote on stderr in line. */
static void shrink_in_child(bool program, int *status, char *line, size_t size)
{
    static char bytes[3 * 4096 + 100];
    memset(bytes, '#', sizeof bytes);
    const char *path = temp_file("shrinks.obj", bytes, sizeof bytes);
    int err[2];
    assert_int_equal(pipe(err), 0);
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) {
        if (program)
            ao_program_init();
        else
            signal(SIGBUS, SIG_DFL);
        dup2(err[1], STDERR_FILENO);
        const char *text;
        size_t size;
        bool mapped;
        if (!ao_file_map_budget(path, NULL, &text, &size, &mapped) || !mapped || truncate(path, 10) != 0)
            _exit(3);
        volatile char last = text[size - 1]; /* on a page past the new end */
        (void)last;
        _exit(0);
    }
    close(err[1]);
    ssize_t got = read(err[0], line, size - 1);
    line[got > 0 ? got : 0] = '\0';
    close(err[0]);
    assert_int_equal(waitpid(child, status, 0), child);
}

/* A mapped file that another process shrinks under the parser: in a program, reading past its new
 * end ends the process with the file's one line and status 1, not a crash (run in a child, which
 * it ends). */
static void test_file_shrunk_while_mapped(void **state)
{
    (void)state;
    int status;
    char line[256];
    shrink_in_child(true, &status, line, sizeof line);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 1);
    if (!strstr(line, "shrinks.obj: the file shrank while it was being read\n"))
        fail_msg("stderr: %s", line);
}

/* The core alone (a library's host that installed no handler) neither catches the SIGBUS nor ends
 * the process itself: SIGBUS's default, and nothing written. */
static void test_core_installs_no_handler(void **state)
{
    (void)state;
    int status;
    char line[256];
    shrink_in_child(false, &status, line, sizeof line);
    assert_true(WIFSIGNALED(status));
    assert_int_equal(WTERMSIG(status), SIGBUS);
    assert_string_equal(line, "");
}

/* One thread's mapping for test_mappings_of_threads: its file's name and what the lookups found. */
struct mapper {
    pthread_barrier_t *together;
    char name[4300];
    bool mapped, own_found, others_missed, gone_after;
};

/* Maps the file, waits until every thread holds its own, looks its first byte, its NUL, a byte a
 * page past its end (another thread's mapping, or none) and a byte of its stack up, then releases
 * it and looks again. */
static void *map_and_look(void *arg)
{
    struct mapper *m = arg;
    const char *text;
    size_t size, length;
    ao_file_map_budget(m->name, NULL, &text, &size, &m->mapped);
    pthread_barrier_wait(m->together);
    const char *line = ao_file_mapped_line(text, &length), *end = ao_file_mapped_line(text + size, &length);
    char expected[4400];
    snprintf(expected, sizeof expected, "%s: the file shrank while it was being read\n", m->name);
    m->own_found = line && end == line && strcmp(line, expected) == 0 && length == strlen(expected);
    m->others_missed = ao_file_mapped_line(text + size + 4096, &length) != line &&
                       !ao_file_mapped_line(expected, &length);
    pthread_barrier_wait(m->together);
    ao_file_unmap(text, size, m->mapped);
    m->gone_after = !ao_file_mapped_line(text, &length);
    return NULL;
}

/* Four threads map four files at once: each address finds its own file's line, none after the
 * release. With mapping turned off, the same file is read. */
static void test_mappings_of_threads(void **state)
{
    (void)state;
    enum { THREADS = 4 };
    static char bytes[4096 + 100];
    memset(bytes, '#', sizeof bytes);
    pthread_barrier_t together;
    pthread_barrier_init(&together, NULL, THREADS);
    struct mapper mappers[THREADS];
    pthread_t ids[THREADS];
    for (int k = 0; k < THREADS; k++) {
        char file[8];
        snprintf(file, sizeof file, "m%d", k);
        mappers[k] = (struct mapper){.together = &together};
        snprintf(mappers[k].name, sizeof mappers[k].name, "%s", temp_file(file, bytes, sizeof bytes));
    }
    for (int k = 0; k < THREADS; k++)
        assert_int_equal(pthread_create(&ids[k], NULL, map_and_look, &mappers[k]), 0);
    for (int k = 0; k < THREADS; k++) {
        pthread_join(ids[k], NULL);
        assert_true(mappers[k].mapped && mappers[k].own_found && mappers[k].others_missed && mappers[k].gone_after);
    }
    pthread_barrier_destroy(&together);

    const char *text;
    size_t size, length;
    bool mapped;
    ao_file_set_mapping(false);
    assert_true(ao_file_map_budget(mappers[0].name, NULL, &text, &size, &mapped));
    /* the same file, its own mapping released above */
    ao_file_set_mapping(true);
    assert_false(mapped);
    assert_int_equal(size, sizeof bytes);
    assert_null(ao_file_mapped_line(text, &length));
    ao_file_unmap(text, size, mapped);
}

/* Random byte changes to valid files (fixed seed) load or fail cleanly, never anything else. */
static void test_mutations(void **state)
{
    (void)state;
    static const char *const names[] = {"cube.ply", "normals.ply", "mixed.obj", "negative.obj"};
    static const char alphabet[] = "0123456789-+./ \n#eExvfn\r";
    const size_t letters = sizeof alphabet - 1;
    uint64_t rng = 0x2545f4914f6cdd1dULL;
    struct bytes binary = binary_square();
    for (int f = 0; f < 5; f++) {
        size_t size = binary.size;
        unsigned char *original = f < 4 ? slurp(fixture(names[f]), &size) : binary.data;
        unsigned char *text = malloc(size);
        assert_non_null(text);
        for (int m = 0; m < 400; m++) {
            memcpy(text, original, size);
            for (int k = 0; k < 1 + m % 3; k++) {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                text[(rng >> 8) % size] = (rng & 1) ? (unsigned char)(rng >> 40)
                                                    : (unsigned char)alphabet[(rng >> 40) % letters];
            }
            struct ao_mesh mesh;
            char err[1024];
            const char *path = temp_file(f < 4 ? names[f] : "square.ply", text, size);
            if (load_captured(&mesh, path, err, sizeof err)) {
                assert_string_equal(err, "");
                assert_mesh_valid(&mesh);
                ao_mesh_finish(&mesh);
            } else {
                assert_mesh_empty(&mesh);
                assert_true(strchr(err, '\n') == err + strlen(err) - 1);
            }
        }
        free(text);
        if (f < 4)
            free(original);
    }
}

MESH_FIXTURE_MAIN("test_load_files", cmocka_unit_test(test_extension_case), cmocka_unit_test(test_file_errors),
                                     cmocka_unit_test(test_unreadable_file),
                                     cmocka_unit_test(test_file_shrunk_while_mapped),
                                     cmocka_unit_test(test_core_installs_no_handler),
                                     cmocka_unit_test(test_mappings_of_threads), cmocka_unit_test(test_mutations))
