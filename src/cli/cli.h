/* Command line: argv to an options struct, or one message naming the option at fault. No I/O. */
#ifndef AO_CLI_H
#define AO_CLI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "modes.h"

/* Everything aoview's command line can say (docs/contract.md); strings point into argv. */
struct ao_options {
    const char *scene_path;   /* NULL: the built-in default scene */
    bool headless;
    const char *output;       /* NULL: aoview.png when headless */
    uint32_t spp;             /* default 256; with --compare, unlimited (--time decides) */
    uint32_t spppp;           /* 0: auto, the default */
    bool adaptive;            /* --adaptive: default on */
    double target_error;      /* --target-error: 0 (none) by default */
    double time_limit;        /* --time: seconds, 0 (none) by default; with --compare, 10 */
    const char *compare;      /* --compare A,B as given, NULL: none; parsed into sides */
    struct ao_compare_side sides[2];
    enum ao_view_mode view;   /* --view: default ao */
    enum ao_shading shading;  /* --shading: default phong */
    double crease;            /* --crease-angle: degrees, default AO_MESH_CREASE_DEFAULT (mesh.h) */
    enum ao_sampling sampling;/* default cosine */
    enum ao_sequence sequence;/* --sampler: default sobol */
    enum ao_below below;      /* --below-surface: default reflect */
    bool aa;                  /* default on */
    int width, height;        /* 0: the scene's image size, else 640x480 */
    int pixel_size;           /* --pixel-size: 1, 2, 4 or 8; 0: auto */
    int threads;              /* 0: number of cores */
    uint64_t seed;            /* default 1 */
    float ao_distance;        /* NAN: the scene's, else infinite */
    const char *stats_path;
    const char *reference_path;
    bool save_exr;            /* --save-format exr: S saves EXR beside the PNG, not PFM */
    uint64_t scene_budget;    /* --scene-budget: bytes a scene may take to load (budget.h) */
    bool ground;              /* --ground: the ground quad under a bare mesh, default on */
    enum ao_bvh bvh;          /* --bvh: default auto (budget.h) */
    bool quiet, help, version;
};

/* Parses argv into *opts (defaults first); --size obeys image.h's AO_IMAGE_MAX_SIDE/_PIXELS;
 * --view difference needs --reference; --compare needs the AO or normals view. On a usage error writes one line naming the option into
 * msg and returns false. */
bool ao_cli_parse(int argc, char **argv, struct ao_options *opts, char *msg, size_t msg_size);

/* Writes side's name ("cosine+sobol+aa", the form --compare takes) into out, truncated to size. */
void ao_cli_side_name(const struct ao_compare_side *side, char *out, size_t size);

/* The --help text. */
const char *ao_cli_usage(void);

#endif
