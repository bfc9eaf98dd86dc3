/* text.c: what a one-line message may quote of user text. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "text.h"

static void test_plain_text_is_kept(void **state)
{
    (void)state;
    char out[64];
    assert_string_equal(ao_text_escape("out.png", out, sizeof out), "out.png");
    assert_string_equal(ao_text_escape("", out, sizeof out), "");
    /* UTF-8 names stay readable */
    assert_string_equal(ao_text_escape("bild-\xc3\xa4\xe2\x82\xac.png", out, sizeof out), "bild-\xc3\xa4\xe2\x82\xac.png");
}

static void test_controls_become_escapes(void **state)
{
    (void)state;
    char out[64];
    assert_string_equal(ao_text_escape("a\nb\rc\td", out, sizeof out), "a\\nb\\rc\\td");
    assert_string_equal(ao_text_escape("back\\slash", out, sizeof out), "back\\\\slash");
    assert_string_equal(ao_text_escape("\x1b[31mred\x7f", out, sizeof out), "\\x1b[31mred\\x7f");
    /* U+009B, the one-character CSI, in UTF-8; a lone 0xc2 before other bytes is kept */
    assert_string_equal(ao_text_escape("x\xc2\x9by", out, sizeof out), "x\\xc2\\x9by");
    assert_string_equal(ao_text_escape("\xc2\xa0", out, sizeof out), "\xc2\xa0");
}

/* Cut with "..." where it does not fit, never in the middle of an escape, always NUL-terminated. */
static void test_long_text_is_cut(void **state)
{
    (void)state;
    char out[8];
    assert_string_equal(ao_text_escape("1234567", out, sizeof out), "1234567");
    assert_string_equal(ao_text_escape("12345678", out, sizeof out), "1234...");
    assert_string_equal(ao_text_escape("1\n345678", out, sizeof out), "1\\n3...");
    assert_string_equal(ao_text_escape("123\n", out, sizeof out), "123\\n");
    assert_string_equal(ao_text_escape("12345\n", out, sizeof out), "12345\\n");
    assert_string_equal(ao_text_escape("123456\n", out, sizeof out), "1234...");
    char big[AO_TEXT_SIZE];
    char name[3000];
    memset(name, '\n', sizeof name - 1);
    name[sizeof name - 1] = '\0';
    ao_text_escape(name, big, sizeof big);
    assert_true(strlen(big) < sizeof big);
    assert_null(strchr(big, '\n'));
    assert_string_equal(big + strlen(big) - 5, "\\n...");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plain_text_is_kept),
        cmocka_unit_test(test_controls_become_escapes),
        cmocka_unit_test(test_long_text_is_cut),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
