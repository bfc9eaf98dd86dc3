/* Inline 3-vector math: in single precision (the renderer's points, directions and colours, and
 * orthonormal bases), and in double (struct ao_dvec3: scene coordinates before a scene is placed in
 * its local frame, the exact-enough arithmetic of mesh normals and affine maps). Header only, used
 * by every module. Every operation rounds as the plain expression it writes out (no fused
 * multiply-adds: the build sets -ffp-contract=off), so results are the same bits everywhere. */
#ifndef AO_VEC3_H
#define AO_VEC3_H

#include <math.h>
#include <stdbool.h>

/* A point, direction or RGB triple in single precision. */
struct ao_vec3 {
    float x, y, z;
};

/* An orthonormal basis whose third axis is a given unit normal. */
struct ao_basis {
    struct ao_vec3 t, b, n;
};

/* Builds a vector from its components. */
static inline struct ao_vec3 ao_vec3_make(float x, float y, float z)
{
    struct ao_vec3 v = {x, y, z};
    return v;
}

/* Component-wise a + b. */
static inline struct ao_vec3 ao_vec3_add(struct ao_vec3 a, struct ao_vec3 b)
{
    return ao_vec3_make(a.x + b.x, a.y + b.y, a.z + b.z);
}

/* Component-wise a - b. */
static inline struct ao_vec3 ao_vec3_sub(struct ao_vec3 a, struct ao_vec3 b)
{
    return ao_vec3_make(a.x - b.x, a.y - b.y, a.z - b.z);
}

/* a scaled by s. */
static inline struct ao_vec3 ao_vec3_scale(struct ao_vec3 a, float s)
{
    return ao_vec3_make(a.x * s, a.y * s, a.z * s);
}

/* Dot product. */
static inline float ao_vec3_dot(struct ao_vec3 a, struct ao_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

/* Cross product a x b. */
static inline struct ao_vec3 ao_vec3_cross(struct ao_vec3 a, struct ao_vec3 b)
{
    return ao_vec3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/* Euclidean length. */
static inline float ao_vec3_length(struct ao_vec3 a)
{
    return sqrtf(ao_vec3_dot(a, a));
}

/* a where c holds, b elsewhere: a choice between values already computed, which a loop over lanes
 * vectorizes (no branch, nothing computed on one side only). */
static inline struct ao_vec3 ao_vec3_pick(bool c, struct ao_vec3 a, struct ao_vec3 b)
{
    return ao_vec3_make(c ? a.x : b.x, c ? a.y : b.y, c ? a.z : b.z);
}

/* a / |a|; the zero vector stays zero (callers that need a direction check the length). */
static inline struct ao_vec3 ao_vec3_normalize(struct ao_vec3 a)
{
    float len2 = ao_vec3_dot(a, a);
    return ao_vec3_pick(len2 > 0.0f, ao_vec3_scale(a, 1.0f / sqrtf(len2)), a);
}

/* Component-wise |a|. */
static inline struct ao_vec3 ao_vec3_abs(struct ao_vec3 a)
{
    return ao_vec3_make(fabsf(a.x), fabsf(a.y), fabsf(a.z));
}

/* Largest absolute component of a finite vector, the scale of a position's rounding error
 * (comparisons rather than fmaxf, which gcc leaves to a libm call). */
static inline float ao_vec3_max_abs(struct ao_vec3 a)
{
    float x = fabsf(a.x), y = fabsf(a.y), z = fabsf(a.z), xy = x > y ? x : y;
    return xy > z ? xy : z;
}

/* True when every component is finite. */
static inline int ao_vec3_is_finite(struct ao_vec3 a)
{
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}

/* Orthonormal basis around unit n without a branch on the axis (Duff et al., JCGT 2017). */
static inline struct ao_basis ao_basis_from_normal(struct ao_vec3 n)
{
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    struct ao_basis f;
    f.t = ao_vec3_make(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    f.b = ao_vec3_make(b, sign + n.y * n.y * a, -n.y);
    f.n = n;
    return f;
}

/* The world direction of local coordinates (x, y, z) in basis f. */
static inline struct ao_vec3 ao_basis_to_world(const struct ao_basis *f, float x, float y, float z)
{
    return ao_vec3_make(f->t.x * x + f->b.x * y + f->n.x * z,
                        f->t.y * x + f->b.y * y + f->n.y * z,
                        f->t.z * x + f->b.z * y + f->n.z * z);
}

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
