/* The numbers of text mesh files (load/common.c): parsed as strtod and strtof parse them, bit for
 * bit, the fast path for short decimals included. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loader.h"

/* Checks one token against strtod and strtof: the same bits, and the same verdict. */
static void assert_number_as_libc(const char *token)
{
    struct ao_load_span s = {token, token + strlen(token)};
    char *stop;
    double want = strtod(token, &stop), got = 0.0;
    bool ok = ao_load_parse_number(s, &got);
    assert_int_equal(ok, stop == s.end);
    if (ok && memcmp(&want, &got, sizeof want) != 0)
        fail_msg("'%s': strtod %.17g, parsed %.17g", token, want, got);
    float want_f = strtof(token, &stop), got_f = 0.0f;
    ok = ao_load_parse_float(s, &got_f);
    assert_int_equal(ok, stop == s.end && isfinite(want_f));
    if (ok && memcmp(&want_f, &got_f, sizeof want_f) != 0)
        fail_msg("'%s': strtof %.9g, parsed %.9g", token, want_f, got_f);
}

/* The numbers of text files parse as strtod and strtof parse them, bit for bit, the fast path for
 * short decimals included: random values in every notation and precision, the halfway points
 * between adjacent floats (where rounding twice would go wrong), extremes and malformed tokens. */
static void test_numbers_as_libc(void **state)
{
    (void)state;
    static const char *const fixed[] = {"0", "-0", "+1", "1.", ".5", "-.5", "1e5", "1E-5", "1e+5", "007", "0.000",
                                        "3.4028235e38", "3.4028236e38", "1e39", "-1e39", "1e-38", "1.17549435e-38",
                                        "1e-40", "1e-46", "9007199254740993", "123456789012345678901",
                                        "0.1234567890123456789", "1e22", "1e23", "1e-22", "1e-23", "inf", "nan",
                                        "0x1p3", "1e", "1e+", ".", "-", "1.2.3", "1e5.5", "12a", "1e99999", ""};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        assert_number_as_libc(fixed[i]);
    uint64_t seed = 99;
    char token[64];
    for (int i = 0; i < 200000; i++) {
        seed = seed * 6364136223846793005u + 1442695040888963407u;
        uint32_t bits = (uint32_t)(seed >> 32);
        float f;
        memcpy(&f, &bits, sizeof f);
        if (!isfinite(f))
            continue;
        static const char *const formats[] = {"%.9g", "%.6g", "%.17g", "%.3f", "%.9e", "%g"};
        snprintf(token, sizeof token, formats[i % 6], f);
        assert_number_as_libc(token);
        float next = nextafterf(f, INFINITY);
        snprintf(token, sizeof token, "%.17g", ((double)f + (double)next) / 2);
        assert_number_as_libc(token);
        snprintf(token, sizeof token, "%.9g", (double)(bits % 2000000) / 1000.0 - 1000.0);
        assert_number_as_libc(token);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_numbers_as_libc),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
