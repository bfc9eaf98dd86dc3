/* Direction samplers for the AO estimator, each paired with its pdf per unit solid angle. */
#ifndef AO_SAMPLING_H
#define AO_SAMPLING_H

#include <stdbool.h>

#include "modes.h"
#include "vec3.h"

/* The mode's command-line name ("uniform", "hemisphere", "cosine"). */
const char *ao_sampling_name(enum ao_sampling mode);

/* Parses a command-line name into *mode; false when the name is unknown. */
bool ao_sampling_parse(const char *name, enum ao_sampling *mode);

/* Uniform direction on the unit sphere from (u1, u2) in [0,1)^2. */
struct ao_vec3 ao_sample_uniform_sphere(float u1, float u2);

/* Density of ao_sample_uniform_sphere: 1/4pi everywhere. */
float ao_uniform_sphere_pdf(void);

/* Density of hemisphere sampling (uniform about the normal n) at w: 1/2pi above the surface, 0
 * below. */
float ao_hemisphere_pdf(struct ao_vec3 n, struct ao_vec3 w);

/* Density of cosine-weighted sampling about the normal n (normalize(n + a uniform sphere sample),
 * evaluated in closed form so that it has no degenerate case) at w: max(0, n.w)/pi. */
float ao_cosine_pdf(struct ao_vec3 n, struct ao_vec3 w);

/* Draws n directions of the given mode, the k-th about the unit normal (nx, ny, nz)[k] from
 * (u1[k], u2[k]), into x/y/z[k], and their estimator weights max(0, n.w) / (pi p(w)) into
 * weight[k], simplified per mode (exactly 1 for cosine). One branch-free loop per mode, so that
 * the compiler vectorizes it across lanes, whether they share a surface or each has its own. */
void ao_sample_directions(enum ao_sampling mode, int n, const float *restrict nx, const float *restrict ny,
                          const float *restrict nz, const float *restrict u1, const float *restrict u2,
                          float *restrict x, float *restrict y, float *restrict z, float *restrict weight);

#endif
