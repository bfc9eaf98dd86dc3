/* cli.c: defaults, every option in both spellings, and every kind of bad value. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "budget.h"
#include "cli.h"
#include "mesh.h"

static char msg[256];

/* Parses a NULL-terminated argument list (argv[0] is added). */
static bool parse(struct ao_options *o, char **args)
{
    char *argv[32] = {"aoview"};
    int argc = 1;
    for (; args[argc - 1]; argc++)
        argv[argc] = args[argc - 1];
    msg[0] = '\0';
    return ao_cli_parse(argc, argv, o, msg, sizeof msg);
}

#define PARSE(o, ...) parse(o, (char *[]){__VA_ARGS__, NULL})
#define PARSE_NONE(o) parse(o, (char *[]){NULL})

/* The arguments must fail with one message line that contains both needles. */
#define REJECT(needle, value, ...)                                                         \
    do {                                                                                   \
        struct ao_options o_;                                                              \
        assert_false(PARSE(&o_, __VA_ARGS__));                                             \
        assert_non_null(strstr(msg, needle));                                              \
        assert_non_null(strstr(msg, value));                                               \
        assert_null(strchr(msg, '\n'));                                                    \
    } while (0)

static void test_defaults(void **state)
{
    (void)state;
    struct ao_options o;
    assert_true(PARSE_NONE(&o));
    assert_null(o.scene_path);
    assert_false(o.headless);
    assert_null(o.output);
    assert_int_equal(o.spp, 256);
    assert_int_equal(o.spppp, 0);     /* auto */
    assert_true(o.adaptive);
    assert_int_equal(o.sequence, AO_SEQUENCE_SOBOL);
    assert_int_equal(o.sampling, AO_SAMPLING_COSINE);
    assert_true(o.aa);
    assert_int_equal(o.width, 0);
    assert_int_equal(o.height, 0);
    assert_int_equal(o.threads, 0);
    assert_int_equal(o.seed, 1);
    assert_true(isnan(o.ao_distance));
    assert_null(o.stats_path);
    assert_null(o.reference_path);
    assert_false(o.quiet || o.help || o.version);
    assert_true(o.scene_budget == ao_budget_default());
    assert_true(o.ground);
    assert_int_equal(o.bvh, AO_BVH_AUTO);
}

static void test_every_option(void **state)
{
    (void)state;
    struct ao_options o;
    assert_true(PARSE(&o, "--headless", "-o", "out.PNG", "--spp", "1073741824", "--spppp",
                      "65536", "--sampling", "uniform", "--no-aa", "--size", "16384x4096",
                      "--threads", "256", "--seed", "18446744073709551615", "--ao-distance",
                      "2.5", "--stats", "s.csv", "--reference", "r.pfm", "-q", "-h",
                      "--version", "scene.scene"));
    assert_true(o.headless);
    assert_string_equal(o.output, "out.PNG");
    assert_int_equal(o.spp, 1u << 30);
    assert_int_equal(o.spppp, 65536);
    assert_int_equal(o.sampling, AO_SAMPLING_UNIFORM);
    assert_false(o.aa);
    assert_int_equal(o.width, 16384);
    assert_int_equal(o.height, 4096);
    assert_int_equal(o.threads, 256);
    assert_true(o.seed == UINT64_MAX);
    assert_float_equal(o.ao_distance, 2.5f, 0.0f);
    assert_string_equal(o.stats_path, "s.csv");
    assert_string_equal(o.reference_path, "r.pfm");
    assert_true(o.quiet && o.help && o.version);
    assert_string_equal(o.scene_path, "scene.scene");
}

static void test_equals_and_long_forms(void **state)
{
    (void)state;
    struct ao_options o;
    assert_true(PARSE(&o, "--output=a.pfm", "--spp=7", "--spppp=100", "--sampling=hemisphere",
                      "--no-aa", "--aa", "--size=1x1", "--threads=3", "--seed=0",
                      "--ao-distance=1e-3", "--stats=x", "--reference=y.pfm", "--quiet",
                      "--help", "m.obj"));
    assert_string_equal(o.output, "a.pfm");
    assert_int_equal(o.spp, 7);
    assert_int_equal(o.spppp, 100); /* more per pass than in total is fine: one pass */
    assert_int_equal(o.sampling, AO_SAMPLING_HEMISPHERE);
    assert_true(o.aa);                /* the last of --aa / --no-aa wins */
    assert_int_equal(o.width, 1);
    assert_int_equal(o.height, 1);
    assert_int_equal(o.threads, 3);
    assert_true(o.seed == 0);
    assert_float_equal(o.ao_distance, 1e-3f, 0.0f);
    assert_string_equal(o.stats_path, "x");
    assert_string_equal(o.reference_path, "y.pfm");
    assert_true(o.quiet && o.help);
    assert_string_equal(o.scene_path, "m.obj");
    assert_true(PARSE(&o, "--output", "x.Pfm", "--sampling", "cosine", "-"));
    assert_string_equal(o.output, "x.Pfm");
    assert_int_equal(o.sampling, AO_SAMPLING_COSINE);
    assert_string_equal(o.scene_path, "-");
}

static void test_bad_counts(void **state)
{
    (void)state;
    const char *bad[] = {"0", "-1", "+5", "", "abc", "12abc", " 5", "1.5", "1e3",
                         "99999999999", "18446744073709551616", "1073741825"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        REJECT("--spp: expected a whole number from 1 to 1073741824", bad[i], "--spp",
               (char *)bad[i]);
    REJECT("--spp: expected a whole number from 1 to 1073741824, got '0'", "'0'", "--spp=0");
    REJECT("--spppp: expected a whole number from 1 to 65536", "65537", "--spppp", "65537");
    REJECT("--spppp", "'0'", "--spppp", "0");
    REJECT("--threads: expected a whole number from 1 to 256", "257", "--threads", "257");
    REJECT("--threads", "'0'", "--threads=0");
    REJECT("--threads", "'-4'", "--threads", "-4");
    REJECT("--seed: expected a whole number from 0 to 18446744073709551615",
           "18446744073709551616", "--seed", "18446744073709551616");
    REJECT("--seed", "'-1'", "--seed", "-1");
    REJECT("--seed", "'0x10'", "--seed", "0x10");
}

static void test_bad_sizes(void **state)
{
    (void)state;
    const char *bad[] = {"0x5", "5x0", "100000x100000", "16385x1", "16384x16384", "12x", "x3",
                         "5x5x5", "5X5", "", "x", "-5x5", "5 x5", "640*480", "99999999999999999999x1"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        REJECT("--size: expected WxH", bad[i], "--size", (char *)bad[i]);
}

/* --pixel-size: auto (0) by default, the four sizes, nothing else. */
static void test_pixel_size(void **state)
{
    (void)state;
    struct ao_options o;
    assert_true(PARSE_NONE(&o));
    assert_int_equal(o.pixel_size, 0);
    const char *good[] = {"1", "2", "4", "8", "auto"};
    const int sizes[] = {1, 2, 4, 8, 0};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        assert_true(PARSE(&o, "--pixel-size", (char *)good[i]));
        assert_int_equal(o.pixel_size, sizes[i]);
    }
    const char *bad[] = {"3", "0", "x", "16", "", "-2", "2.0", "Auto"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        REJECT("--pixel-size: expected auto, 1, 2, 4 or 8", bad[i], "--pixel-size", (char *)bad[i]);
}

static void test_bad_strings(void **state)
{
    (void)state;
    REJECT("--output: expected a file name ending in .png, .pfm or .exr", "'a.jpg'", "-o", "a.jpg");
    REJECT("--output", "'png'", "--output=png");
    REJECT("--output", "''", "--output=");
    REJECT("--sampling: expected uniform, hemisphere or cosine", "'Cosine'", "--sampling",
           "Cosine");
    REJECT("--sampling", "''", "--sampling=");
    REJECT("--stats: expected a file name", "''", "--stats", "");
    REJECT("--reference: expected a file name", "''", "--reference=");
}

static void test_bad_distances(void **state)
{
    (void)state;
    const char *bad[] = {"0", "-1", "inf", "nan", "1e39", "1e-50", "abc", "", " 1", "1x"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        REJECT("--ao-distance: expected a finite number greater than 0", bad[i],
               "--ao-distance", (char *)bad[i]);
}

static void test_bad_structure(void **state)
{
    (void)state;
    REJECT("unknown option", "'--frobnicate'", "--frobnicate");
    REJECT("unknown option", "'--frob'", "--frob=1");
    REJECT("unknown option", "'-x'", "-x");
    REJECT("unknown option", "'--sp'", "--sp", "5");
    REJECT("--spp: missing value", "--spp", "--spp");
    REJECT("--output: missing value", "--output", "a.scene", "-o");
    REJECT("--headless: takes no value", "'yes'", "--headless=yes");
    REJECT("--aa", "''", "--aa=");
    REJECT("unexpected argument 'b.scene'", "'a.scene'", "a.scene", "b.scene");
    /* A value is taken verbatim, even when it looks like an option. */
    REJECT("--spp", "'--headless'", "--spp", "--headless");
}

static void test_adaptive_options(void **state)
{
    (void)state;
    struct ao_options o;
    assert_true(PARSE(&o, "--spppp", "auto", "--adaptive", "on", "--target-error", "0.01"));
    assert_int_equal(o.spppp, 0);
    assert_true(o.adaptive);
    assert_true(o.target_error == 0.01);
    assert_true(PARSE(&o, "--adaptive=off", "--target-error=1", "--spppp=auto", "--spppp=3"));
    assert_false(o.adaptive);
    assert_true(o.target_error == 1.0);
    assert_int_equal(o.spppp, 3);
    const char *errors[] = {"0", "-0.1", "1.5", "nan", "inf", "", "0.01x", " 0.1", "1e-400"};
    for (size_t i = 0; i < sizeof errors / sizeof errors[0]; i++)
        REJECT("--target-error", errors[i], "--target-error", (char *)errors[i]);
    REJECT("--adaptive", "yes", "--adaptive", "yes");
    REJECT("--spppp", "Auto", "--spppp", "Auto");
}

/* EXR output, and the linear format the window's S key saves. */
static void test_exr_and_save_format(void **state)
{
    (void)state;
    struct ao_options o;
    assert_true(PARSE_NONE(&o));
    assert_false(o.save_exr);
    assert_true(PARSE(&o, "-o", "out.EXR", "--save-format", "exr", "--reference", "r.exr"));
    assert_string_equal(o.output, "out.EXR");
    assert_true(o.save_exr);
    assert_true(PARSE(&o, "--save-format=pfm"));
    assert_false(o.save_exr);
    REJECT("--save-format: expected pfm or exr", "'png'", "--save-format", "png");
}

/* --time, --view and --shading: values, defaults, and difference's need of a reference. */
static void test_view_options(void **state)
{
    (void)state;
    struct ao_options o;
    assert_true(PARSE_NONE(&o));
    assert_true(o.time_limit == 0.0);
    assert_int_equal(o.view, AO_VIEW_MODE_AO);
    assert_int_equal(o.shading, AO_SHADING_PHONG);
    assert_true(PARSE(&o, "--time", "2.5", "--view", "normals", "--shading", "flat"));
    assert_true(o.time_limit == 2.5);
    assert_int_equal(o.view, AO_VIEW_MODE_NORMALS);
    assert_int_equal(o.shading, AO_SHADING_FLAT);
    assert_true(PARSE(&o, "--view=difference", "--reference=r.pfm", "--shading=phong", "--view=ao", "--time=1e-3"));
    assert_int_equal(o.view, AO_VIEW_MODE_AO);
    assert_int_equal(o.shading, AO_SHADING_PHONG);
    assert_true(o.time_limit == 1e-3);
    assert_true(PARSE(&o, "--reference", "r.pfm", "--view", "difference"));
    assert_int_equal(o.view, AO_VIEW_MODE_DIFFERENCE);
    const char *times[] = {"0", "-1", "nan", "inf", "", "1s", " 1", "1e9", "1e-400"};
    for (size_t i = 0; i < sizeof times / sizeof times[0]; i++)
        REJECT("--time", times[i], "--time", (char *)times[i]);
    REJECT("--view: expected ao, normals or difference", "'Normals'", "--view", "Normals");
    REJECT("--shading: expected phong or flat", "'smooth'", "--shading", "smooth");
    REJECT("--view difference", "--reference", "--view", "difference");
    REJECT("--view", "missing value", "--view");
}

/* --compare: each side's parts, what the other options fill in, its defaults for --spp and
 * --time, and every malformed or unsupported use. */
static void test_compare_options(void **state)
{
    (void)state;
    struct ao_options o;
    assert_true(PARSE_NONE(&o));
    assert_null(o.compare);
    assert_true(PARSE(&o, "--headless", "--compare", "uniform,cosine"));
    assert_non_null(o.compare);
    assert_int_equal(o.sides[0].sampling, AO_SAMPLING_UNIFORM);
    assert_int_equal(o.sides[1].sampling, AO_SAMPLING_COSINE);
    assert_int_equal(o.sides[0].sequence, AO_SEQUENCE_SOBOL);
    assert_true(o.sides[0].aa && o.sides[1].aa);
    assert_true(o.time_limit == 10.0);          /* time decides, not spp */
    assert_int_equal(o.spp, 1 << 30);
    /* The other options fill in what a side leaves out, wherever they stand. */
    assert_true(PARSE(&o, "--compare=cosine+noaa,hemisphere+sobol", "--headless", "--sampler", "random",
                      "--time", "3", "--spp", "64"));
    assert_int_equal(o.sides[0].sampling, AO_SAMPLING_COSINE);
    assert_false(o.sides[0].aa);
    assert_int_equal(o.sides[0].sequence, AO_SEQUENCE_RANDOM);
    assert_int_equal(o.sides[1].sampling, AO_SAMPLING_HEMISPHERE);
    assert_true(o.sides[1].aa);
    assert_int_equal(o.sides[1].sequence, AO_SEQUENCE_SOBOL);
    assert_true(o.time_limit == 3.0);
    assert_int_equal(o.spp, 64);
    assert_true(PARSE(&o, "--headless", "--no-aa", "--compare", "cosine+aa+random,cosine"));
    assert_true(o.sides[0].aa);
    assert_false(o.sides[1].aa);
    char name[64];
    ao_cli_side_name(&o.sides[0], name, sizeof name);
    assert_string_equal(name, "cosine+random+aa");
    const char *bad[] = {"uniform", "a,b,c", "uniform,cosine,cosine", "foo,cosine", "cosine+foo,cosine",
                         "cosine,", ",cosine", "cosine+,cosine", "cosine+aa+noaa,cosine",
                         "cosine+sobol+random,cosine", "Cosine,uniform", "cosine+sobol+aa+aa,cosine",
                         "cosine+averyveryverylongpart,cosine", ""};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        REJECT("--compare: expected two configurations", bad[i], "--headless", "--compare", (char *)bad[i]);
    /* Without --headless the window compares live, with the same defaults. */
    assert_true(PARSE(&o, "--compare", "uniform,cosine"));
    assert_false(o.headless);
    assert_true(o.time_limit == 10.0);
    REJECT("--compare", "--view difference", "--headless", "--compare", "uniform,cosine", "--reference", "r.pfm",
           "--view", "difference");
    REJECT("--compare", "missing value", "--headless", "--compare");
}

/* --scene-budget: bytes, or K, M, G, T as powers of 1024, from 1M to 1024T. */
static void test_scene_budget(void **state)
{
    (void)state;
    struct ao_options o;
    static const struct {
        const char *value;
        uint64_t bytes;
    } good[] = {{"4G", UINT64_C(4) << 30}, {"4g", UINT64_C(4) << 30}, {"512M", UINT64_C(512) << 20},
                {"1048576", UINT64_C(1) << 20}, {"1024K", UINT64_C(1) << 20}, {"3T", UINT64_C(3) << 40},
                {"1024T", UINT64_C(1) << 50}, {"1M", UINT64_C(1) << 20}};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        assert_true(PARSE(&o, "--scene-budget", (char *)good[i].value));
        assert_true(o.scene_budget == good[i].bytes);
    }
    assert_true(PARSE(&o, "--scene-budget=2G"));
    assert_true(o.scene_budget == UINT64_C(2) << 30);
    const char *bad[] = {"", "G", "0", "1023K", "1048575", "1025T", "4P", "4GB", "4 G", "-4G", "4.5G", "0x10M",
                         "18446744073709551616", "17592186044416K"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        REJECT("--scene-budget: expected a size from 1M to 1024T", bad[i], "--scene-budget", (char *)bad[i]);
    REJECT("--scene-budget", "missing value", "--scene-budget");
}

/* --ground on|off: the ground quad under a bare mesh. */
static void test_ground(void **state)
{
    (void)state;
    struct ao_options o;
    assert_true(PARSE(&o, "--ground", "off", "model.obj"));
    assert_false(o.ground);
    assert_true(PARSE(&o, "--ground=off", "--ground=on"));
    assert_true(o.ground);
    REJECT("--ground: expected off or on", "'no'", "--ground", "no");
    REJECT("--ground: expected off or on", "''", "--ground=");
    REJECT("--ground", "missing value", "--ground");
}

/* --bvh auto|medium|compact|low: how the tracer builds its BVHs (budget.h). */
static void test_bvh(void **state)
{
    (void)state;
    struct ao_options o;
    assert_true(PARSE(&o, "--bvh", "compact", "model.obj"));
    assert_int_equal(o.bvh, AO_BVH_COMPACT);
    assert_true(PARSE(&o, "--bvh=low"));
    assert_int_equal(o.bvh, AO_BVH_LOW);
    assert_true(PARSE(&o, "--bvh=low", "--bvh=medium"));
    assert_int_equal(o.bvh, AO_BVH_MEDIUM);
    REJECT("--bvh: expected auto, medium, compact or low", "'fast'", "--bvh", "fast");
    REJECT("--bvh", "missing value", "--bvh");
}

/* --crease-angle DEG: degrees from 0 to 180 (mesh.h's default). */
static void test_crease_angle(void **state)
{
    (void)state;
    struct ao_options o;
    assert_true(PARSE(&o, "model.obj"));
    assert_true(o.crease == AO_MESH_CREASE_DEFAULT);
    assert_true(PARSE(&o, "--crease-angle", "0", "model.obj"));
    assert_true(o.crease == 0.0);
    assert_true(PARSE(&o, "--crease-angle=180"));
    assert_true(o.crease == 180.0);
    assert_true(PARSE(&o, "--crease-angle=22.5"));
    assert_true(o.crease == 22.5);
    REJECT("--crease-angle: expected degrees from 0 to 180", "'181'", "--crease-angle", "181");
    REJECT("--crease-angle: expected degrees from 0 to 180", "'-1'", "--crease-angle", "-1");
    REJECT("--crease-angle: expected degrees from 0 to 180", "'nan'", "--crease-angle", "nan");
    REJECT("--crease-angle: expected degrees from 0 to 180", "'40deg'", "--crease-angle", "40deg");
    REJECT("--crease-angle", "missing value", "--crease-angle");
}

/* Every option that takes a real number refuses an empty value and blanks before one, as it
 * refuses any other value that is not a number (strtod reads '' as 0 and skips blanks). */
static void test_real_options_refuse_empty_values(void **state)
{
    (void)state;
    static char *const names[] = {"--crease-angle", "--ao-distance", "--target-error", "--time"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        REJECT(names[i], "got ''", names[i], "");
        REJECT(names[i], "got ' 1'", names[i], " 1");
        REJECT(names[i], "got ' '", names[i], " ");
    }
}

static void test_usage_lists_every_option(void **state)
{
    (void)state;
    const char *u = ao_cli_usage();
    const char *names[] = {"--headless", "-o, --output", "--spp", "--spppp", "--sampling",
                           "--aa", "--no-aa", "--size", "--threads", "--seed", "--ao-distance",
                           "--stats", "--reference", "-q, --quiet", "-h, --help", "--version",
                           "--time", "--view", "--shading", "--compare A,B", "--scene-budget SIZE", "a quarter of the machine's\n", "memory, at least 1G", "--ground on|off", "--crease-angle DEG", "N normals", "F flat/Phong", "D difference",
                           "default 256", "default cosine", "640x480", "Esc",
                           /* every window key and the mouse buttons */
                           "U/H/C", "A anti-aliasing", "Space pause", "R restart", "+/- samples per pass",
                           "G adaptive", "E error map", "V compare", "B split", "S save", "[/] halve/double",
                           "F1 or ?", "F2 hide", "Esc/Q quit", "left drag orbit", "divider", "right drag pan",
                           "wheel zoom"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        assert_non_null(strstr(u, names[i]));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_every_option),
        cmocka_unit_test(test_equals_and_long_forms),
        cmocka_unit_test(test_bad_counts),
        cmocka_unit_test(test_bad_sizes),
        cmocka_unit_test(test_pixel_size),
        cmocka_unit_test(test_bad_strings),
        cmocka_unit_test(test_bad_distances),
        cmocka_unit_test(test_bad_structure),
        cmocka_unit_test(test_adaptive_options),
        cmocka_unit_test(test_exr_and_save_format),
        cmocka_unit_test(test_view_options),
        cmocka_unit_test(test_compare_options),
        cmocka_unit_test(test_scene_budget),
        cmocka_unit_test(test_ground),
        cmocka_unit_test(test_bvh),
        cmocka_unit_test(test_crease_angle),
        cmocka_unit_test(test_real_options_refuse_empty_values),
        cmocka_unit_test(test_usage_lists_every_option),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
