/* The main of a unit test file whose tests need no group setup. Include after cmocka.h, stdio.h
 * and stdlib.h. */
#ifndef AO_TEST_UNIT_MAIN_H
#define AO_TEST_UNIT_MAIN_H

/* Defines main: runs the tests listed (cmocka_unit_test entries) as one group, returning how many
 * failed. */
#define UNIT_TEST_MAIN(...)                                                                                            \
    int main(void)                                                                                                     \
    {                                                                                                                  \
        const struct CMUnitTest tests[] = {__VA_ARGS__};                                                               \
        return cmocka_run_group_tests(tests, NULL, NULL);                                                              \
    }

/* Defines main as UNIT_TEST_MAIN does for tests that read the source tree: 77 without
 * AO_SOURCE_ROOT, said on stderr as `name: ...`. */
#define SOURCE_TEST_MAIN(name, ...)                                                                                    \
    int main(void)                                                                                                     \
    {                                                                                                                  \
        if (!getenv("AO_SOURCE_ROOT")) {                                                                               \
            fprintf(stderr, "%s: AO_SOURCE_ROOT is not set (run it through meson test)\n", name);                      \
            return 77;                                                                                                 \
        }                                                                                                              \
        const struct CMUnitTest tests[] = {__VA_ARGS__};                                                               \
        return cmocka_run_group_tests(tests, NULL, NULL);                                                              \
    }

#endif
