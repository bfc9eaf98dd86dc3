/* Command line parsing: a table of options, one switch that applies them, strict value checks. */
#include "cli.h"

#include "budget.h"
#include "image.h"
#include "mesh.h"
#include "sampling.h"
#include "text.h"

#include <assert.h>
#include <ctype.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

enum { MAX_SPP = 1 << 30, MAX_SPPPP = 65536, MAX_THREADS = 256 };

/* A value from argv as a message quotes it: escaped onto one line (text.h), in a buffer that lives
 * until the end of the enclosing block, cut to fit the message. */
#define SHOWN(value) ao_text_escape((value), (char[200]){0}, 200)

enum option_id {
    OPT_HEADLESS, OPT_OUTPUT, OPT_SPP, OPT_SPPPP, OPT_SAMPLING, OPT_AA, OPT_NO_AA, OPT_SIZE,
    OPT_THREADS, OPT_SEED, OPT_AO_DISTANCE, OPT_STATS, OPT_REFERENCE, OPT_QUIET, OPT_HELP,
    OPT_VERSION, OPT_SAMPLER, OPT_BELOW, OPT_ADAPTIVE, OPT_TARGET_ERROR, OPT_SAVE_FORMAT, OPT_TIME,
    OPT_VIEW, OPT_SHADING, OPT_COMPARE, OPT_PIXEL_SIZE, OPT_SCENE_BUDGET, OPT_GROUND, OPT_BVH,
    OPT_CREASE_ANGLE,
};

/* The longest --time: a year, far beyond any render, short of overflowing anything. */
static const double MAX_SECONDS = 365.0 * 24 * 3600;
/* --spp and --time when not given: the usual 256 spp without a time limit; with --compare, ten
 * seconds a side, long enough to tell estimators apart, with no spp limit to end a side early. */
enum { DEFAULT_SPP = 256 };
static const double COMPARE_SECONDS = 10.0;

/* Names of the --sampler and --below-surface values, in their enums' order. */
static const char *const sequences[] = {[AO_SEQUENCE_RANDOM] = "random", [AO_SEQUENCE_SOBOL] = "sobol", NULL};
static const char *const belows[] = {[AO_BELOW_REFLECT] = "reflect", [AO_BELOW_TRACE] = "trace", NULL};
static const char *const switches[] = {"off", "on", NULL};
/* Names of the --save-format values: false, true for opts->save_exr. */
static const char *const save_formats[] = {"pfm", "exr", NULL};
/* Names of the --view and --shading values, in their enums' order. */
static const char *const views[] = {[AO_VIEW_MODE_AO] = "ao", [AO_VIEW_MODE_NORMALS] = "normals",
                                    [AO_VIEW_MODE_DIFFERENCE] = "difference", NULL};
static const char *const shadings[] = {[AO_SHADING_PHONG] = "phong", [AO_SHADING_FLAT] = "flat", NULL};
static const char *const bvhs[] = {[AO_BVH_AUTO] = "auto", [AO_BVH_MEDIUM] = "medium",
                                   [AO_BVH_COMPACT] = "compact", [AO_BVH_LOW] = "low", NULL};
/* Names of the --pixel-size values: auto, then the pixel sizes 1, 2, 4, 8 (choice k is 2^(k-1)). */
static const char *const pixel_sizes[] = {"auto", "1", "2", "4", "8", NULL};

/* One row of the option table: long name, short name (or 0), whether it takes a value. */
struct option_spec {
    const char *name;
    char short_name;
    bool has_value;
    enum option_id id;
};

static const struct option_spec specs[] = {
    {"--headless", 0, false, OPT_HEADLESS},
    {"--output", 'o', true, OPT_OUTPUT},
    {"--spp", 0, true, OPT_SPP},
    {"--spppp", 0, true, OPT_SPPPP},
    {"--sampling", 0, true, OPT_SAMPLING},
    {"--aa", 0, false, OPT_AA},
    {"--no-aa", 0, false, OPT_NO_AA},
    {"--size", 0, true, OPT_SIZE},
    {"--pixel-size", 0, true, OPT_PIXEL_SIZE},
    {"--threads", 0, true, OPT_THREADS},
    {"--seed", 0, true, OPT_SEED},
    {"--ao-distance", 0, true, OPT_AO_DISTANCE},
    {"--stats", 0, true, OPT_STATS},
    {"--reference", 0, true, OPT_REFERENCE},
    {"--quiet", 'q', false, OPT_QUIET},
    {"--help", 'h', false, OPT_HELP},
    {"--version", 0, false, OPT_VERSION},
    {"--sampler", 0, true, OPT_SAMPLER},
    {"--below-surface", 0, true, OPT_BELOW},
    {"--adaptive", 0, true, OPT_ADAPTIVE},
    {"--target-error", 0, true, OPT_TARGET_ERROR},
    {"--save-format", 0, true, OPT_SAVE_FORMAT},
    {"--time", 0, true, OPT_TIME},
    {"--view", 0, true, OPT_VIEW},
    {"--shading", 0, true, OPT_SHADING},
    {"--crease-angle", 0, true, OPT_CREASE_ANGLE},
    {"--compare", 0, true, OPT_COMPARE},
    {"--scene-budget", 0, true, OPT_SCENE_BUDGET},
    {"--ground", 0, true, OPT_GROUND},
    {"--bvh", 0, true, OPT_BVH},
};

static const char usage[] =
    "usage: aoview [OPTIONS] [SCENE]\n"
    "Progressive Monte Carlo ambient occlusion. SCENE: a .scene file or a mesh\n"
    "(.obj, .ply, .stl, .gltf, .glb); default: the built-in bunny scene.\n"
    "\n"
    "  --headless            render without a window, write -o, exit\n"
    "  -o, --output FILE     .png (displayed image), .pfm or .exr (linear float);\n"
    "                        default aoview.png with --headless\n"
    "  --spp N               total AO samples per pixel (default 256)\n"
    "  --spppp N|auto        AO samples per pixel per pass; auto: 8, then doubling\n"
    "                        to about 2^22 samples a pass (at least 8), 8 per eye ray\n"
    "                        (default auto)\n"
    "  --adaptive on|off     samples go where the estimated error is (default on)\n"
    "  --target-error E      stop once the estimated RMSE is at most E times the\n"
    "                        image mean, e.g. 0.01 (default: run to --spp)\n"
    "  --time S              stop after S seconds of rendering, or at --spp if sooner\n"
    "  --view V              ao | normals (shading normals as (n + 1) / 2) |\n"
    "                        difference (|AO - reference|, needs --reference)\n"
    "                        (default ao)\n"
    "  --shading S           phong | flat mesh normals (default phong)\n"
    "  --crease-angle DEG    OBJ, PLY, STL without normals: smooth across edges\n"
    "                        flatter than DEG, 0 (flat) to 180 (default 40)\n"
    "  --compare A,B         two configurations for --time seconds each (default\n"
    "                        10): split live in the window, or with --headless side\n"
    "                        by side in one PNG, or FILE-A and FILE-B for .pfm/.exr;\n"
    "                        a configuration is a sampling mode with optional\n"
    "                        +random|+sobol, +aa|+noaa, e.g. uniform,cosine or\n"
    "                        cosine+random,cosine+sobol\n"
    "  --sampling M          uniform | hemisphere | cosine (default cosine)\n"
    "  --sampler S           random | sobol (Owen-scrambled) numbers for jitter and\n"
    "                        directions (default sobol)\n"
    "  --below-surface P     reflect | trace directions that point below the geometric\n"
    "                        surface (default reflect)\n"
    "  --aa, --no-aa         jittered eye rays on / off (default on)\n"
    "  --size WxH            image size; in a window its initial size (default: the\n"
    "                        scene's, else 640x480)\n"
    "  --pixel-size N        1|2|4|8|auto: the window renders 1/N of its pixels each\n"
    "                        way, shown as NxN blocks; auto: 2 on HiDPI screens, and\n"
    "                        the magnification of a --size smaller than the window\n"
    "                        (default auto)\n"
    "  --threads N           render threads, 1 to 256 (default: number of cores)\n"
    "  --seed N              random seed (default 1)\n"
    "  --ao-distance D       occlusion range (default: the scene's, else infinite)\n"
    "  --stats FILE          CSV row per finished pass (default none)\n"
    "  --reference FILE      add per-pass RMSE against this .pfm or .exr image\n"
    "                        (default none)\n"
    "  --save-format F       pfm | exr: the linear file the window's S key saves\n"
    "                        beside the PNG (default pfm)\n"
    "  --scene-budget SIZE   memory a scene may take: bytes, or with K, M, G or T\n"
    "                        (powers of 1024); larger scenes are refused before\n"
    "                        they are loaded (default: a quarter of the machine's\n"
    "                        memory, at least 1G)\n"
    "  --ground on|off       the ground quad under a bare mesh (default on; a .scene\n"
    "                        file has the quads it lists)\n"
    "  --bvh B               medium (fastest rays) | compact (half the memory,\n"
    "                        slower rays) | low (built 3x sooner, slower rays;\n"
    "                        compact too where only that fits the budget) |\n"
    "                        auto: medium, or compact if only that fits the scene\n"
    "                        budget; from 1M triangles low traces while medium is\n"
    "                        built beside it, where the budget holds both (default auto)\n"
    "  -q, --quiet           print nothing but errors\n"
    "  -h, --help            show this help\n"
    "  --version             show the version\n"
    "\n";

/* The window's keys and mouse, after the options (one string literal would pass C's 4095). */
static const char keys[] =
    "Window keys: U/H/C uniform sphere, hemisphere, cosine sampling; A anti-aliasing;\n"
    "Space pause; R restart; +/- samples per pass; G adaptive sampling; E error map;\n"
    "D difference from --reference; N normals view; F flat/Phong normals;\n"
    "V compare two configurations; B split/side by side; S save aoview-N.png and\n"
    ".pfm/.exr; [/] halve/double the pixel size; F1 or ? key help; F2 hide the\n"
    "overlay; Esc/Q quit. Mouse: left drag orbit (on the comparison's divider: move\n"
    "it), right drag pan, wheel zoom.\n";

const char *ao_cli_usage(void)
{
    static char text[sizeof usage + sizeof keys - 1];
    if (!text[0]) {
        memcpy(text, usage, sizeof usage - 1);
        memcpy(text + sizeof usage - 1, keys, sizeof keys);
    }
    return text;
}

/* Parses the digits in [s, end) as a decimal number without sign; false on anything else. */
static bool parse_u64(const char *s, const char *end, uint64_t *out)
{
    uint64_t v = 0;
    if (s == end)
        return false;
    for (; s < end; s++) {
        if (*s < '0' || *s > '9' || v > (UINT64_MAX - (uint64_t)(*s - '0')) / 10)
            return false;
        v = v * 10 + (uint64_t)(*s - '0');
    }
    *out = v;
    return true;
}

static bool parse_count(const char *name, const char *value, uint64_t lo, uint64_t hi,
                        uint64_t *out, char *msg, size_t msg_size)
{
    if (parse_u64(value, value + strlen(value), out) && *out >= lo && *out <= hi)
        return true;
    snprintf(msg, msg_size, "%s: expected a whole number from %" PRIu64 " to %" PRIu64 ", got '%s'",
             name, lo, hi, SHOWN(value));
    return false;
}

static bool parse_size(const char *name, const char *value, struct ao_options *opts, char *msg,
                       size_t msg_size)
{
    const char *x = strchr(value, 'x');
    uint64_t w, h;
    if (x && parse_u64(value, x, &w) && parse_u64(x + 1, x + 1 + strlen(x + 1), &h) &&
        w >= 1 && w <= AO_IMAGE_MAX_SIDE && h >= 1 && h <= AO_IMAGE_MAX_SIDE &&
        w * h <= AO_IMAGE_MAX_PIXELS) {
        opts->width = (int)w;
        opts->height = (int)h;
        return true;
    }
    snprintf(msg, msg_size,
             "%s: expected WxH with sides from 1 to %d and at most %d pixels, got '%s'", name,
             AO_IMAGE_MAX_SIDE, AO_IMAGE_MAX_PIXELS, SHOWN(value));
    return false;
}

/* True when strtod or strtof, reading value, ended at `end` having read all of it: a number, not an
 * empty string or blanks before one (which strtod skips). Every real-valued option checks this. */
static bool whole_number(const char *value, const char *end)
{
    return end != value && *end == '\0' && !isspace((unsigned char)*value);
}

static bool parse_distance(const char *name, const char *value, float *out, char *msg,
                           size_t msg_size)
{
    char *end;
    float d = strtof(value, &end);
    if (whole_number(value, end) && isfinite(d) && d > 0.0f) {
        *out = d;
        return true;
    }
    snprintf(msg, msg_size, "%s: expected a finite number greater than 0, got '%s'", name, SHOWN(value));
    return false;
}

/* --crease-angle: degrees from 0 to 180. */
static bool parse_degrees(const char *name, const char *value, double *out, char *msg, size_t msg_size)
{
    char *end;
    double d = strtod(value, &end);
    if (whole_number(value, end) && d >= 0.0 && d <= 180.0) {
        *out = d;
        return true;
    }
    snprintf(msg, msg_size, "%s: expected degrees from 0 to 180, got '%s'", name, SHOWN(value));
    return false;
}

/* A relative error: a finite number in (0, 1]. */
static bool parse_fraction(const char *name, const char *value, double *out, char *msg, size_t msg_size)
{
    char *end;
    double e = strtod(value, &end);
    if (whole_number(value, end) && e > 0.0 && e <= 1.0) {
        *out = e;
        return true;
    }
    snprintf(msg, msg_size, "%s: expected a relative error greater than 0 and at most 1, got '%s'", name, SHOWN(value));
    return false;
}

/* A duration in seconds: a finite number in (0, MAX_SECONDS]. */
static bool parse_seconds(const char *name, const char *value, double *out, char *msg, size_t msg_size)
{
    char *end;
    double t = strtod(value, &end);
    if (whole_number(value, end) && t > 0.0 && t <= MAX_SECONDS) {
        *out = t;
        return true;
    }
    snprintf(msg, msg_size, "%s: expected seconds greater than 0 and at most %.0f, got '%s'", name, MAX_SECONDS,
             SHOWN(value));
    return false;
}

/* --scene-budget: a whole number of bytes, or with a suffix K, M, G or T (powers of 1024), from
 * 1M to 1024T. */
static bool parse_budget(const char *name, const char *value, uint64_t *out, char *msg, size_t msg_size)
{
    static const char suffixes[] = "KMGT";
    size_t n = strlen(value);
    const char *unit = n ? strchr(suffixes, toupper((unsigned char)value[n - 1])) : NULL;
    uint64_t number, shift = unit && *unit ? 10 * (uint64_t)(unit - suffixes + 1) : 0;
    if (parse_u64(value, value + n - (shift ? 1 : 0), &number) && number <= (UINT64_C(1) << 50) >> shift &&
        number << shift >= UINT64_C(1) << 20) {
        *out = number << shift;
        return true;
    }
    snprintf(msg, msg_size, "%s: expected a size from 1M to 1024T (bytes, or a number with K, M, G or T), got "
             "'%s'", name, value);
    return false;
}

static bool has_suffix(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && strcasecmp(s + n - k, suffix) == 0;
}

static bool parse_path(const char *name, const char *value, bool image, const char **out,
                       char *msg, size_t msg_size)
{
    if (image ? has_suffix(value, ".png") || has_suffix(value, ".pfm") || has_suffix(value, ".exr")
              : *value != '\0') {
        *out = value;
        return true;
    }
    snprintf(msg, msg_size, "%s: expected a file name%s, got '%s'", name,
             image ? " ending in .png, .pfm or .exr" : "", SHOWN(value));
    return false;
}

static bool parse_sampling(const char *name, const char *value, enum ao_sampling *out, char *msg,
                           size_t msg_size)
{
    if (ao_sampling_parse(value, out))
        return true;
    snprintf(msg, msg_size, "%s: expected uniform, hemisphere or cosine, got '%s'", name, SHOWN(value));
    return false;
}

/* Finds value among the NULL-terminated choices and stores its index; else a message listing them
 * (none when msg is NULL). */
static bool parse_choice(const char *name, const char *value, const char *const *choices, int *out,
                         char *msg, size_t msg_size)
{
    int n = 0;
    for (; choices[n]; n++) {
        if (strcmp(value, choices[n]) == 0) {
            *out = n;
            return true;
        }
    }
    if (!msg)
        return false;
    size_t used = (size_t)snprintf(msg, msg_size, "%s: expected ", name);
    for (int k = 0; k < n && used < msg_size; k++)
        used += (size_t)snprintf(msg + used, msg_size - used, "%s%s", choices[k],
                                 k + 2 < n ? ", " : k + 2 == n ? " or " : "");
    if (used < msg_size)
        snprintf(msg + used, msg_size - used, ", got '%s'", SHOWN(value));
    return false;
}

/* Parses one --compare configuration in [s, end): a sampling mode, then each of +random|+sobol
 * and +aa|+noaa at most once; what it leaves out is --sampler's and --aa's. */
static bool parse_side(const char *s, const char *end, const struct ao_options *opts, struct ao_compare_side *side)
{
    char part[16];
    int sequence = -1, aa = -1;
    for (bool first = true; s <= end; first = false) {
        const char *plus = memchr(s, '+', (size_t)(end - s));
        const char *stop = plus ? plus : end;
        if ((size_t)(stop - s) >= sizeof part)
            return false;
        memcpy(part, s, (size_t)(stop - s));
        part[stop - s] = '\0';
        int choice;
        if (first) {
            if (!ao_sampling_parse(part, &side->sampling))
                return false;
        } else if (sequence < 0 && parse_choice("", part, sequences, &choice, NULL, 0)) {
            sequence = choice;
        } else if (aa < 0 && (strcmp(part, "aa") == 0 || strcmp(part, "noaa") == 0)) {
            aa = strcmp(part, "aa") == 0;
        } else {
            return false;
        }
        s = stop + 1;
    }
    side->sequence = sequence < 0 ? opts->sequence : (enum ao_sequence)sequence;
    side->aa = aa < 0 ? opts->aa : aa;
    return true;
}

/* --compare A,B into opts->sides, after the other options (which fill in what A and B leave out). */
static bool parse_compare(const char *name, const char *value, struct ao_options *opts, char *msg, size_t msg_size)
{
    const char *comma = strchr(value, ',');
    const char *end = value + strlen(value);
    if (comma && !strchr(comma + 1, ',') && parse_side(value, comma, opts, &opts->sides[0]) &&
        parse_side(comma + 1, end, opts, &opts->sides[1]))
        return true;
    snprintf(msg, msg_size,
             "%s: expected two configurations A,B, each a sampling mode with optional +random|+sobol and "
             "+aa|+noaa (e.g. uniform,cosine), got '%s'", name, SHOWN(value));
    return false;
}

void ao_cli_side_name(const struct ao_compare_side *side, char *out, size_t size)
{
    snprintf(out, size, "%s+%s+%s", ao_sampling_name(side->sampling), sequences[side->sequence],
             side->aa ? "aa" : "noaa");
}

/* The names an option that picks one of a list picks from; NULL for any other option. */
static const char *const *choices_of(enum option_id id)
{
    switch (id) {
    case OPT_SAMPLER: return sequences;
    case OPT_BELOW: return belows;
    case OPT_ADAPTIVE: case OPT_GROUND: return switches;
    case OPT_SAVE_FORMAT: return save_formats;
    case OPT_VIEW: return views;
    case OPT_SHADING: return shadings;
    case OPT_PIXEL_SIZE: return pixel_sizes;
    case OPT_BVH: return bvhs;
    default: return NULL;
    }
}

/* Stores the choice (an index into choices_of(id)) of a list option into opts. */
static void set_choice(enum option_id id, int choice, struct ao_options *opts)
{
    switch (id) {
    case OPT_SAMPLER: opts->sequence = (enum ao_sequence)choice; break;
    case OPT_BELOW: opts->below = (enum ao_below)choice; break;
    case OPT_ADAPTIVE: opts->adaptive = choice; break;
    case OPT_GROUND: opts->ground = choice; break;
    case OPT_SAVE_FORMAT: opts->save_exr = choice == 1; break;
    case OPT_VIEW: opts->view = (enum ao_view_mode)choice; break;
    case OPT_SHADING: opts->shading = (enum ao_shading)choice; break;
    case OPT_PIXEL_SIZE: opts->pixel_size = choice ? 1 << (choice - 1) : 0; break;
    case OPT_BVH: opts->bvh = (enum ao_bvh)choice; break;
    default: assert(!"not a list option"); break;
    }
}

/* Applies one option (value is NULL for flags) to opts. */
static bool apply(const struct option_spec *spec, const char *value, struct ao_options *opts,
                  char *msg, size_t msg_size)
{
    const char *name = spec->name;
    const char *const *choices = choices_of(spec->id);
    int choice;
    if (choices) {
        if (!parse_choice(name, value, choices, &choice, msg, msg_size))
            return false;
        set_choice(spec->id, choice, opts);
        return true;
    }
    uint64_t n;
    switch (spec->id) {
    case OPT_HEADLESS: opts->headless = true; return true;
    case OPT_AA: opts->aa = true; return true;
    case OPT_NO_AA: opts->aa = false; return true;
    case OPT_QUIET: opts->quiet = true; return true;
    case OPT_HELP: opts->help = true; return true;
    case OPT_VERSION: opts->version = true; return true;
    case OPT_OUTPUT: return parse_path(name, value, true, &opts->output, msg, msg_size);
    case OPT_STATS: return parse_path(name, value, false, &opts->stats_path, msg, msg_size);
    case OPT_REFERENCE: return parse_path(name, value, false, &opts->reference_path, msg, msg_size);
    case OPT_SAMPLING: return parse_sampling(name, value, &opts->sampling, msg, msg_size);
    case OPT_SIZE: return parse_size(name, value, opts, msg, msg_size);
    case OPT_AO_DISTANCE: return parse_distance(name, value, &opts->ao_distance, msg, msg_size);
    case OPT_SEED: return parse_count(name, value, 0, UINT64_MAX, &opts->seed, msg, msg_size);
    case OPT_TARGET_ERROR: return parse_fraction(name, value, &opts->target_error, msg, msg_size);
    case OPT_TIME: return parse_seconds(name, value, &opts->time_limit, msg, msg_size);
    case OPT_CREASE_ANGLE: return parse_degrees(name, value, &opts->crease, msg, msg_size);
    case OPT_COMPARE: opts->compare = value; return true;
    case OPT_SCENE_BUDGET: return parse_budget(name, value, &opts->scene_budget, msg, msg_size);
    case OPT_SPP:
        if (!parse_count(name, value, 1, MAX_SPP, &n, msg, msg_size))
            return false;
        opts->spp = (uint32_t)n;
        return true;
    case OPT_SPPPP:
        if (strcmp(value, "auto") == 0) {
            opts->spppp = 0;
            return true;
        }
        if (!parse_count(name, value, 1, MAX_SPPPP, &n, msg, msg_size))
            return false;
        opts->spppp = (uint32_t)n;
        return true;
    case OPT_THREADS:
        if (!parse_count(name, value, 1, MAX_THREADS, &n, msg, msg_size))
            return false;
        opts->threads = (int)n;
        return true;
    default: return false;   /* the list options, applied above */
    }
}

/* The table row for arg's first name_len characters ("--name" or "-c"), or NULL. */
static const struct option_spec *find_option(const char *arg, size_t name_len)
{
    for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++) {
        const struct option_spec *s = &specs[i];
        bool is_long = strlen(s->name) == name_len && strncmp(arg, s->name, name_len) == 0;
        bool is_short = s->short_name && name_len == 2 && arg[1] == s->short_name;
        if (is_long || is_short)
            return s;
    }
    return NULL;
}

/* Handles the option at argv[*i], taking its value from "=value" or the next argument. */
static bool parse_option(int argc, char **argv, int *i, struct ao_options *opts, char *msg,
                         size_t msg_size)
{
    const char *arg = argv[*i];
    const char *eq = arg[1] == '-' ? strchr(arg, '=') : NULL;
    size_t name_len = eq ? (size_t)(eq - arg) : strlen(arg);
    const struct option_spec *spec = find_option(arg, name_len);
    if (!spec) {
        char name[200];
        snprintf(name, sizeof name, "%.*s", (int)name_len, arg);
        snprintf(msg, msg_size, "unknown option '%s'", SHOWN(name));
        return false;
    }
    if (!spec->has_value && eq) {
        snprintf(msg, msg_size, "%s: takes no value, got '%s'", spec->name, SHOWN(eq + 1));
        return false;
    }
    const char *value = eq ? eq + 1 : NULL;
    if (spec->has_value && !value) {
        if (*i + 1 >= argc) {
            snprintf(msg, msg_size, "%s: missing value", spec->name);
            return false;
        }
        value = argv[++*i];
    }
    return apply(spec, value, opts, msg, msg_size);
}

bool ao_cli_parse(int argc, char **argv, struct ao_options *opts, char *msg, size_t msg_size)
{
    *opts = (struct ao_options){
        .spp = 0, .spppp = 0, .adaptive = true, .sampling = AO_SAMPLING_COSINE, .aa = true, .seed = 1,
        .sequence = AO_SEQUENCE_SOBOL, .below = AO_BELOW_REFLECT,
        .ao_distance = NAN, .scene_budget = ao_budget_default(), .ground = true, .crease = AO_MESH_CREASE_DEFAULT,
    };
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (arg[0] == '-' && arg[1] != '\0') {
            if (!parse_option(argc, argv, &i, opts, msg, msg_size))
                return false;
        } else if (opts->scene_path) {
            snprintf(msg, msg_size, "unexpected argument '%s': the scene is already '%s'", SHOWN(arg),
                     SHOWN(opts->scene_path));
            return false;
        } else {
            opts->scene_path = arg;
        }
    }
    if (opts->view == AO_VIEW_MODE_DIFFERENCE && !opts->reference_path) {
        snprintf(msg, msg_size, "--view difference: needs --reference FILE to compare against");
        return false;
    }
    if (opts->compare && !parse_compare("--compare", opts->compare, opts, msg, msg_size))
        return false;
    if (opts->compare && opts->view == AO_VIEW_MODE_DIFFERENCE) {
        snprintf(msg, msg_size, "--compare: shows the ao or normals view, not --view difference");
        return false;
    }
    if (!opts->spp)
        opts->spp = opts->compare ? MAX_SPP : DEFAULT_SPP;
    if (opts->compare && opts->time_limit == 0.0)
        opts->time_limit = COMPARE_SECONDS;
    return true;
}
