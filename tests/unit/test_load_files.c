/* What every mesh load shares about its file: the extension chooses the format in any case; a
 * missing file, a directory, an unknown extension, an unreadable file each refused with one line;
 * a mapped file shrunk under the parser ends the process with one line; random changes to valid
 * files load or fail cleanly. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "file.h"

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

/* A mapped file that another process shrinks under the parser: reading past its new end ends the
 * process with the file's one line and status 1, not a crash (run in a child, which it ends). */
static void test_file_shrunk_while_mapped(void **state)
{
    (void)state;
    static char bytes[3 * 4096 + 100];
    memset(bytes, '#', sizeof bytes);
    const char *path = temp_file("shrinks.obj", bytes, sizeof bytes);
    int err[2];
    assert_int_equal(pipe(err), 0);
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) {
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
    char line[256] = "";
    ssize_t got = read(err[0], line, sizeof line - 1);
    close(err[0]);
    int status;
    assert_int_equal(waitpid(child, &status, 0), child);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 1);
    assert_true(got > 0);
    if (!strstr(line, "shrinks.obj: the file shrank while it was being read\n"))
        fail_msg("stderr: %s", line);
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

int main(void)
{
    if (!mesh_fixture_begin("test_load_files"))
        return 77;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_extension_case),
        cmocka_unit_test(test_file_errors),
        cmocka_unit_test(test_unreadable_file),
        cmocka_unit_test(test_file_shrunk_while_mapped),
        cmocka_unit_test(test_mutations),
    };
    return cmocka_run_group_tests(tests, mesh_fixture_setup, mesh_fixture_teardown);
}
