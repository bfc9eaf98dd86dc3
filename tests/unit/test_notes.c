/* What a saved linear image says about how it was made (notes.c): the EXR header's attributes of a
 * frame, each key once, in order, with the values the frame's facts give. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "config.h"
#include "notes.h"

/* The value of key, or NULL. */
static const char *value_of(const struct ao_notes *n, const char *key)
{
    for (size_t k = 0; k < n->count; k++)
        if (strcmp(n->notes[k].key, key) == 0)
            return n->notes[k].value;
    return NULL;
}

static void test_attributes(void **state)
{
    (void)state;
    struct ao_frame_info info = {.spp = 512, .sampling = AO_SAMPLING_HEMISPHERE, .aa = false,
                                 .output = AO_OUTPUT_NORMALS, .shading = AO_SHADING_FLAT, .seconds = 12.3456};
    struct ao_notes n;
    ao_notes_make(&n, &info, "bunny.scene", 18446744073709551615u);
    static const char *const keys[] = {"software", "aoview.scene", "aoview.spp", "aoview.sampling", "aoview.aa",
                                       "aoview.view", "aoview.shading", "aoview.seed", "aoview.seconds"};
    assert_int_equal(n.count, sizeof keys / sizeof keys[0]);
    for (size_t k = 0; k < n.count; k++)
        assert_string_equal(n.notes[k].key, keys[k]);
    assert_string_equal(value_of(&n, "software"), "aoview " AO_VERSION);
    assert_string_equal(value_of(&n, "aoview.scene"), "bunny.scene");
    assert_string_equal(value_of(&n, "aoview.spp"), "512");
    assert_string_equal(value_of(&n, "aoview.sampling"), "hemisphere");
    assert_string_equal(value_of(&n, "aoview.aa"), "off");
    assert_string_equal(value_of(&n, "aoview.view"), "normals");
    assert_string_equal(value_of(&n, "aoview.shading"), "flat");
    assert_string_equal(value_of(&n, "aoview.seed"), "18446744073709551615");
    assert_string_equal(value_of(&n, "aoview.seconds"), "12.346");
    /* The defaults' words, and a scene name too long for its slot cut, not overflowing. */
    info = (struct ao_frame_info){.sampling = AO_SAMPLING_COSINE, .aa = true};
    char name[400];
    memset(name, 'x', sizeof name - 1);
    name[sizeof name - 1] = '\0';
    ao_notes_make(&n, &info, name, 1);
    assert_string_equal(value_of(&n, "aoview.sampling"), "cosine");
    assert_string_equal(value_of(&n, "aoview.aa"), "on");
    assert_string_equal(value_of(&n, "aoview.view"), "ao");
    assert_string_equal(value_of(&n, "aoview.shading"), "phong");
    assert_int_equal(strlen(value_of(&n, "aoview.scene")), sizeof n.values[0] - 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_attributes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
