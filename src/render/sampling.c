/* Direction samplers and their densities; see sampling.h. */
#include "sampling.h"

#include <string.h>

#include "simd.h"

static const float PI = 3.14159265358979323846f;

static const char *const NAMES[] = {
    [AO_SAMPLING_UNIFORM] = "uniform",
    [AO_SAMPLING_HEMISPHERE] = "hemisphere",
    [AO_SAMPLING_COSINE] = "cosine",
};

const char *ao_sampling_name(enum ao_sampling mode)
{
    return NAMES[mode];
}

bool ao_sampling_parse(const char *name, enum ao_sampling *mode)
{
    for (int m = 0; m < (int)(sizeof NAMES / sizeof NAMES[0]); m++) {
        if (strcmp(name, NAMES[m]) == 0) {
            *mode = (enum ao_sampling)m;
            return true;
        }
    }
    return false;
}

/* max(0, x), exact for finite x, without the comparison that keeps the compiler from vectorizing
 * the sampling loops. */
static inline float positive(float x)
{
    return 0.5f * (x + fabsf(x));
}

/* cos and sin of 2 pi u for u in [0, 1), without libm (a third of a sample's cost otherwise) and
 * without branches: the quadrant comes from 4u, the rest a in [-pi/4, pi/4) is handled by Taylor
 * polynomials (truncation error below 2e-9, far under float rounding), rotated by pi/4 and then
 * by the quadrant. */
static inline void cos_sin_2pi(float u, float *c, float *s)
{
    float v = 4.0f * u;
    int quadrant = (int)v;
    float a = (v - (float)quadrant - 0.5f) * (0.5f * PI), a2 = a * a;
    float sin_a = a * (1.0f + a2 * (-1.0f / 6 + a2 * (1.0f / 120 + a2 * (-1.0f / 5040 + a2 * (1.0f / 362880)))));
    float cos_a = 1.0f + a2 * (-0.5f + a2 * (1.0f / 24 + a2 * (-1.0f / 720 + a2 * (1.0f / 40320 + a2 * (-1.0f / 3628800)))));
    const float half_sqrt2 = 0.70710678118654752f;
    float cq = (cos_a - sin_a) * half_sqrt2, sq = (sin_a + cos_a) * half_sqrt2;
    /* Rotation by the quadrant, as arithmetic rather than branches: odd quadrants swap
     * (c, s) -> (-s, c), quadrants 2 and 3 negate both. */
    float odd = (float)(quadrant & 1), sign = 1.0f - (float)(quadrant & 2);
    *c = sign * (cq - odd * (cq + sq));
    *s = sign * (sq + odd * (cq - sq));
}

static inline struct ao_vec3 uniform_sphere(float u1, float u2)
{
    float z = 2.0f * u1 - 1.0f;
    float r = sqrtf(1.0f - z * z); /* |z| <= 1, so z * z rounds to at most 1 */
    float c, s;
    cos_sin_2pi(u2, &c, &s);
    return ao_vec3_make(r * c, r * s, z);
}

struct ao_vec3 ao_sample_uniform_sphere(float u1, float u2)
{
    return uniform_sphere(u1, u2);
}

float ao_uniform_sphere_pdf(void)
{
    return 1.0f / (4.0f * PI);
}

static inline struct ao_vec3 hemisphere(const struct ao_basis *f, float u1, float u2)
{
    /* cos(theta) uniform in (0, 1]: 1 - u1 keeps the direction off the horizon at u1 = 0. */
    float z = 1.0f - u1;
    float r = sqrtf(1.0f - z * z); /* |z| <= 1, so z * z rounds to at most 1 */
    float c, s;
    cos_sin_2pi(u2, &c, &s);
    return ao_basis_to_world(f, r * c, r * s, z);
}

float ao_hemisphere_pdf(struct ao_vec3 n, struct ao_vec3 w)
{
    return ao_vec3_dot(n, w) > 0.0f ? 1.0f / (2.0f * PI) : 0.0f;
}

static inline struct ao_vec3 cosine(const struct ao_basis *f, float u1, float u2)
{
    /* normalize(n + s) for s = (r cos phi, r sin phi, z), z = 2 u1 - 1, in the basis of n:
     * |n + s|^2 = r^2 + (1 + z)^2 = 2 (1 + z) = 4 u1, so the sum's components divided by 2 sqrt(u1)
     * are (sqrt(1 - u1) cos phi, sqrt(1 - u1) sin phi, sqrt(u1)). Evaluated that way the
     * construction cancels nothing: at s = -n (u1 = 0) it yields a unit horizon direction, the
     * limit of its neighbours, instead of 0/0. The density is cos(theta)/pi (Malley's method). */
    float z = sqrtf(u1);
    float r = sqrtf(1.0f - u1);
    float c, s;
    cos_sin_2pi(u2, &c, &s);
    return ao_basis_to_world(f, r * c, r * s, z);
}

float ao_cosine_pdf(struct ao_vec3 n, struct ao_vec3 w)
{
    return fmaxf(0.0f, ao_vec3_dot(n, w)) / PI;
}

AO_VECTOR_CLONES
void ao_sample_directions(enum ao_sampling mode, int n, const float *restrict nx, const float *restrict ny,
                          const float *restrict nz, const float *restrict u1, const float *restrict u2,
                          float *restrict x, float *restrict y, float *restrict z, float *restrict weight)
{
    /* Weights have each pdf substituted by hand, so that cosine sampling's weight is exactly 1
     * rather than a rounded cos/(pi cos/pi). */
    switch (mode) {
    case AO_SAMPLING_UNIFORM:
        for (int k = 0; k < n; k++) {
            struct ao_vec3 w = uniform_sphere(u1[k], u2[k]);
            x[k] = w.x, y[k] = w.y, z[k] = w.z;
            weight[k] = 4.0f * positive(nx[k] * w.x + ny[k] * w.y + nz[k] * w.z);
        }
        break;
    case AO_SAMPLING_HEMISPHERE:
        for (int k = 0; k < n; k++) {
            struct ao_basis f = ao_basis_from_normal(ao_vec3_make(nx[k], ny[k], nz[k]));
            struct ao_vec3 w = hemisphere(&f, u1[k], u2[k]);
            x[k] = w.x, y[k] = w.y, z[k] = w.z;
            weight[k] = 2.0f * positive(ao_vec3_dot(f.n, w));
        }
        break;
    case AO_SAMPLING_COSINE:
        for (int k = 0; k < n; k++) {
            struct ao_basis f = ao_basis_from_normal(ao_vec3_make(nx[k], ny[k], nz[k]));
            struct ao_vec3 w = cosine(&f, u1[k], u2[k]);
            x[k] = w.x, y[k] = w.y, z[k] = w.z;
            weight[k] = 1.0f;
        }
        break;
    }
}
