/* Direction samplers for the AO estimator, each paired with its pdf per unit solid angle. */
#ifndef AO_SAMPLING_H
#define AO_SAMPLING_H

#include <stdbool.h>

#include "vec3.h"

/* Which distribution occlusion directions are drawn from. */
enum ao_sampling {
    AO_SAMPLING_UNIFORM,     /* uniform over the whole sphere, p = 1/4pi */
    AO_SAMPLING_HEMISPHERE,  /* uniform over the hemisphere about n, p = 1/2pi */
    AO_SAMPLING_COSINE,      /* cosine-weighted about n, p = cos(theta)/pi */
};

/* The mode's command-line name ("uniform", "hemisphere", "cosine"). */
const char *ao_sampling_name(enum ao_sampling mode);

/* Parses a command-line name into *mode; false when the name is unknown. */
bool ao_sampling_parse(const char *name, enum ao_sampling *mode);

/* Uniform direction on the unit sphere from (u1, u2) in [0,1)^2. */
struct ao_vec3 ao_sample_uniform_sphere(float u1, float u2);

/* Density of ao_sample_uniform_sphere: 1/4pi everywhere. */
float ao_uniform_sphere_pdf(void);

/* Uniform direction on the hemisphere about f->n. */
struct ao_vec3 ao_sample_hemisphere(const struct ao_basis *f, float u1, float u2);

/* Density of ao_sample_hemisphere at w: 1/2pi above the surface, 0 below. */
float ao_hemisphere_pdf(struct ao_vec3 n, struct ao_vec3 w);

/* Cosine-weighted direction about f->n: normalize(n + uniform sphere sample), evaluated in closed
 * form so that it has no degenerate case. */
struct ao_vec3 ao_sample_cosine(const struct ao_basis *f, float u1, float u2);

/* Density of ao_sample_cosine at w: max(0, n.w)/pi. */
float ao_cosine_pdf(struct ao_vec3 n, struct ao_vec3 w);

/* Draws a direction of the given mode into *w and returns its estimator weight
 * max(0, n.w) / (pi p(w)), simplified per mode (exactly 1 for cosine). */
float ao_sample_direction(enum ao_sampling mode, const struct ao_basis *f, float u1, float u2,
                          struct ao_vec3 *w);

#endif
