/* The main of a unit test file whose tests need no group setup. Include after cmocka.h. */
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

#endif
