/* Affine maps of points in double precision, p' = L p + t: how a model places its meshes (mesh.h),
 * how a scene places a model, and, narrowed to float, how the tracer places an instance. Header
 * only; no allocation. */
#ifndef AO_AFFINE_H
#define AO_AFFINE_H

#include <math.h>
#include <stdbool.h>

#include "vec3.h"


/* An affine map, column major as glTF's matrices and Embree's FLOAT3X4_COLUMN_MAJOR lay it out:
 * m[0..2], m[3..5], m[6..8] are the columns of L, m[9..11] the translation t. */
struct ao_affine {
    double m[12];
};

/* The identity map. */
static inline struct ao_affine ao_affine_identity(void)
{
    struct ao_affine a = {{1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}};
    return a;
}

/* The map `outer` after `inner` (first inner, then outer). */
static inline struct ao_affine ao_affine_compose(const struct ao_affine *outer, const struct ao_affine *inner)
{
    struct ao_affine r;
    const double *a = outer->m, *b = inner->m;
    for (int c = 0; c < 4; c++)
        for (int k = 0; k < 3; k++)
            r.m[3 * c + k] = a[k] * b[3 * c] + a[3 + k] * b[3 * c + 1] + a[6 + k] * b[3 * c + 2] + (c == 3 ? a[9 + k] : 0.0);
    return r;
}

/* The image of the point (x, y, z). */
static inline struct ao_dvec3 ao_affine_point(const struct ao_affine *a, double x, double y, double z)
{
    double out[3];
    for (int k = 0; k < 3; k++)
        out[k] = a->m[k] * x + a->m[3 + k] * y + a->m[6 + k] * z + a->m[9 + k];
    return ao_dvec3_make(out[0], out[1], out[2]);
}

/* True when every entry is finite. */
static inline bool ao_affine_is_finite(const struct ao_affine *a)
{
    for (int k = 0; k < 12; k++)
        if (!isfinite(a->m[k]))
            return false;
    return true;
}

/* True when the map is the identity, exactly. */
static inline bool ao_affine_is_identity(const struct ao_affine *a)
{
    struct ao_affine id = ao_affine_identity();
    for (int k = 0; k < 12; k++)
        if (a->m[k] != id.m[k])
            return false;
    return true;
}

/* The matrix that maps normals as L's inverse transpose does, in the direction it gives them (the
 * cofactor matrix of L times the sign of det L), column major into n, with its largest entry 1
 * (0 for a zero L); returns a number with the sign of det L (negative where L mirrors, 0 where it
 * is singular). Computed from L divided by its largest entry: neither direction nor sign depends
 * on that scale, and no product of two entries can then overflow (a finite but huge matrix would
 * give inf - inf = NaN normals) or vanish together. A mirroring map applied to a mesh turns its
 * triangles round (their corners 1 and 2 swapped), so that they keep facing the way these
 * normals point. */
static inline double ao_affine_normals(const struct ao_affine *a, double n[9])
{
    double big = 0.0, l[9], cof[9];
    for (int k = 0; k < 9; k++)
        big = fmax(big, fabs(a->m[k]));
    for (int k = 0; k < 9; k++)
        l[k] = big > 0.0 ? a->m[k] / big : 0.0;
    /* cof(r, c) = L(r1, c1) L(r2, c2) - L(r1, c2) L(r2, c1), with L(r, c) = l[3c + r]. */
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
            cof[3 * c + r] = l[3 * c1 + r1] * l[3 * c2 + r2] - l[3 * c2 + r1] * l[3 * c1 + r2];
        }
    double det = l[0] * cof[0] + l[3] * cof[3] + l[6] * cof[6], sign = det < 0.0 ? -1.0 : 1.0, most = 0.0;
    for (int k = 0; k < 9; k++)
        most = fmax(most, fabs(cof[k]));
    for (int k = 0; k < 9; k++)
        n[k] = most > 0.0 ? sign * cof[k] / most : 0.0;
    return det;
}

#endif
