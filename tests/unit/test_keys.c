/* The window's keys (keys.c): each character's settings change or action, by character in either
 * case; + and - leaving auto from the samples per pass on screen and keeping within 1 to 65536;
 * what is not a key changes nothing; the help names every key. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "keys.h"
#include "unit_main.h"

/* Settings as a run starts with them. */
static struct ao_settings start(void)
{
    return (struct ao_settings){.width = 640, .height = 480, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                .spppp = 0, .adaptive = true, .output = AO_OUTPUT_AO, .shading = AO_SHADING_PHONG};
}

static void test_settings_keys(void **state)
{
    (void)state;
    struct ao_settings s = start();
    assert_int_equal(ao_keys_typed('u', &s, 0), AO_KEY_SETTINGS);
    assert_int_equal(s.sampling, AO_SAMPLING_UNIFORM);
    assert_int_equal(ao_keys_typed('H', &s, 0), AO_KEY_SETTINGS);
    assert_int_equal(s.sampling, AO_SAMPLING_HEMISPHERE);
    assert_int_equal(ao_keys_typed('c', &s, 0), AO_KEY_SETTINGS);
    assert_int_equal(s.sampling, AO_SAMPLING_COSINE);
    ao_keys_typed('a', &s, 0);
    assert_false(s.aa);
    ao_keys_typed(' ', &s, 0);
    assert_true(s.paused);
    ao_keys_typed('g', &s, 0);
    assert_false(s.adaptive);
    ao_keys_typed('n', &s, 0);
    assert_int_equal(s.output, AO_OUTPUT_NORMALS);
    ao_keys_typed('N', &s, 0);
    assert_int_equal(s.output, AO_OUTPUT_AO);
    ao_keys_typed('f', &s, 0);
    assert_int_equal(s.shading, AO_SHADING_FLAT);
    /* Nothing else changed: width, height and the camera stay. */
    assert_int_equal(s.width, 640);
    assert_int_equal(s.height, 480);
}

/* + and - from auto start from the pass on screen (1 before any), then double and halve within
 * 1..65536; '=' is the unshifted '+'. */
static void test_samples_per_pass(void **state)
{
    (void)state;
    struct ao_settings s = start();
    assert_int_equal(ao_keys_typed('+', &s, 8), AO_KEY_SETTINGS);
    assert_int_equal(s.spppp, 16);
    ao_keys_typed('=', &s, 8);
    assert_int_equal(s.spppp, 32);
    ao_keys_typed('-', &s, 8);
    assert_int_equal(s.spppp, 16);
    s.spppp = 0;
    ao_keys_typed('-', &s, 0);
    assert_int_equal(s.spppp, 1);
    ao_keys_typed('-', &s, 0);
    assert_int_equal(s.spppp, 1);
    s.spppp = 65536;
    ao_keys_typed('+', &s, 0);
    assert_int_equal(s.spppp, 65536);
}

/* The viewer's own actions leave the settings as they were. */
static void test_actions(void **state)
{
    (void)state;
    static const struct {
        unsigned int key;
        enum ao_key_action action;
    } keys[] = {{'e', AO_KEY_ERROR_VIEW}, {'D', AO_KEY_DIFFERENCE_VIEW}, {'r', AO_KEY_RESTART}, {'v', AO_KEY_COMPARE},
                {'b', AO_KEY_LAYOUT},     {'S', AO_KEY_SAVE},            {'[', AO_KEY_FINER},   {']', AO_KEY_COARSER},
                {'?', AO_KEY_HELP},       {'q', AO_KEY_QUIT},            {'x', AO_KEY_NONE},    {'1', AO_KEY_NONE},
                {0x263a, AO_KEY_NONE}};
    for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++) {
        struct ao_settings s = start(), before = s;
        assert_int_equal(ao_keys_typed(keys[k].key, &s, 8), keys[k].action);
        assert_memory_equal(&s, &before, sizeof s);
    }
}

/* The help lists every key the viewer takes. */
static void test_help(void **state)
{
    (void)state;
    static const char *const lines[] = {"U ", "H ", "C ", "A ", "Space", "R ", "+ -", "G ", "E ", "D ", "N ", "F ",
                                        "V ", "B ", "S ", "[ ]", "left drag", "right drag", "wheel", "F1 or ?", "F2",
                                        "Esc or Q"};
    for (size_t k = 0; k < sizeof lines / sizeof lines[0]; k++)
        if (!strstr(ao_keys_help(), lines[k]))
            fail_msg("the help lacks '%s'", lines[k]);
}

UNIT_TEST_MAIN(cmocka_unit_test(test_settings_keys), cmocka_unit_test(test_samples_per_pass),
               cmocka_unit_test(test_actions), cmocka_unit_test(test_help))
