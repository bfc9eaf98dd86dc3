/* The choices a user makes about how an image is estimated, traced and shown: the enums that the
 * command line, the renderer, the tracer and the viewers share. Header only; includes nothing of
 * aoview's, so that any room may name a mode without pulling in the room that acts on it. */
#ifndef AO_MODES_H
#define AO_MODES_H

#include <stdbool.h>

/* Which distribution occlusion directions are drawn from (sampling.h draws them). */
enum ao_sampling {
    AO_SAMPLING_UNIFORM,     /* uniform over the whole sphere, p = 1/4pi */
    AO_SAMPLING_HEMISPHERE,  /* uniform over the hemisphere about n, p = 1/2pi */
    AO_SAMPLING_COSINE,      /* cosine-weighted about n, p = cos(theta)/pi */
};

/* How a stream's numbers are drawn (rng.h): independent random pairs, or an Owen-scrambled Sobol
 * sequence whose first 2^k points (of any pixel, from index 0) stratify the unit square. */
enum ao_sequence {
    AO_SEQUENCE_RANDOM,
    AO_SEQUENCE_SOBOL,
};

/* What happens to sampled directions that point below the geometric surface (possible where the
 * interpolated shading normal differs from it). */
enum ao_below {
    AO_BELOW_REFLECT,        /* mirrored across the geometric surface, then traced */
    AO_BELOW_TRACE,          /* traced as they are: they hit the surface itself and count occluded */
};

/* What a pixel sample's value is: the AO estimate, or the shading normal n the estimate uses
 * (turned to face the eye) as the colour (n + 1) / 2, black where the eye ray misses. */
enum ao_output {
    AO_OUTPUT_AO,
    AO_OUTPUT_NORMALS,
};

/* The shading normal of a mesh point: the vertex normals Phong-interpolated, or the face normal.
 * Spheres use their exact normal either way. */
enum ao_shading {
    AO_SHADING_PHONG,
    AO_SHADING_FLAT,
};

/* How the tracer builds the scene's BVHs (measured in docs/formats.md): MEDIUM, Embree's SAH build,
 * traces fastest; COMPACT, the same build with leaves that index the shared vertices, takes half
 * the memory and reaches 1 % RMSE 18-35 % later; LOW, Embree's Morton build, builds 3x sooner and
 * reaches 1 % up to 14 % later. AUTO is MEDIUM where the whole scene fits the scene budget so,
 * else COMPACT (budget.h); LOW_COMPACT, the Morton build with compact leaves, is what LOW becomes
 * where only COMPACT's charges fit (not a choice of --bvh). */
enum ao_bvh { AO_BVH_AUTO, AO_BVH_MEDIUM, AO_BVH_COMPACT, AO_BVH_LOW, AO_BVH_LOW_COMPACT };

/* What --view shows: the AO image, the shading normals (both estimates the renderer accumulates),
 * or |AO - reference| as a heat map (a display of the AO image; needs --reference). */
enum ao_view_mode {
    AO_VIEW_MODE_AO,
    AO_VIEW_MODE_NORMALS,
    AO_VIEW_MODE_DIFFERENCE,
};

/* One side of --compare: a sampling mode with the sampler and AA it names, the rest from the
 * other options. */
struct ao_compare_side {
    enum ao_sampling sampling;
    enum ao_sequence sequence;
    bool aa;
};

/* How the window shows the two sides of a comparison: one image split at a divider (A left of it,
 * B right), or the two images side by side (A left, B right), twice as wide. */
enum ao_compare_layout {
    AO_COMPARE_SPLIT,
    AO_COMPARE_SIDE_BY_SIDE,
};

#endif
