/* Points and directions in double precision: scene coordinates before a scene is placed in its local
 * frame, and the exact-enough arithmetic of mesh normals and affine maps. Header only; no
 * allocation. Every operation rounds as the plain expression it writes out (no fused
 * multiply-adds: the build sets -ffp-contract=off), so results are the same bits everywhere. */
#ifndef AO_DVEC3_H
#define AO_DVEC3_H

#include <math.h>
#include <stdbool.h>

#include "vec3.h"

/* A 3-vector of doubles. */
struct ao_dvec3 {
    double x, y, z;
};

/* (x, y, z). */
static inline struct ao_dvec3 ao_dvec3_make(double x, double y, double z)
{
    struct ao_dvec3 v = {x, y, z};
    return v;
}

/* v widened from float, exactly. */
static inline struct ao_dvec3 ao_dvec3_of(struct ao_vec3 v)
{
    return ao_dvec3_make(v.x, v.y, v.z);
}

/* v narrowed to float, each component rounded once. */
static inline struct ao_vec3 ao_dvec3_narrow(struct ao_dvec3 v)
{
    return ao_vec3_make((float)v.x, (float)v.y, (float)v.z);
}

/* a + b. */
static inline struct ao_dvec3 ao_dvec3_add(struct ao_dvec3 a, struct ao_dvec3 b)
{
    return ao_dvec3_make(a.x + b.x, a.y + b.y, a.z + b.z);
}

/* a - b. */
static inline struct ao_dvec3 ao_dvec3_sub(struct ao_dvec3 a, struct ao_dvec3 b)
{
    return ao_dvec3_make(a.x - b.x, a.y - b.y, a.z - b.z);
}

/* a s. */
static inline struct ao_dvec3 ao_dvec3_scale(struct ao_dvec3 a, double s)
{
    return ao_dvec3_make(a.x * s, a.y * s, a.z * s);
}

/* a x b. */
static inline struct ao_dvec3 ao_dvec3_cross(struct ao_dvec3 a, struct ao_dvec3 b)
{
    return ao_dvec3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/* a . b. */
static inline double ao_dvec3_dot(struct ao_dvec3 a, struct ao_dvec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

/* The unit vector along v into *out; false when v is zero or not finite. Divided first by its
 * largest component, so that no square overflows or vanishes. */
static inline bool ao_dvec3_unit(struct ao_dvec3 v, struct ao_dvec3 *out)
{
    double big = fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z)));
    if (!(big > 0.0) || !isfinite(v.x) || !isfinite(v.y) || !isfinite(v.z))
        return false;
    v = ao_dvec3_scale(v, 1.0 / big);
    *out = ao_dvec3_scale(v, 1.0 / sqrt(ao_dvec3_dot(v, v)));
    return true;
}

#endif
