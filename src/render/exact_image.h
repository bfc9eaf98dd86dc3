/* The exact ambient-occlusion image of a scene that has a closed form (a plane with at most one
 * sphere over it, or a closed box around the eye; exact_image.c derives each), traced through the
 * project's camera and tracer so that each pixel sees what aoview sees: what aoview-exact writes and
 * the Python module's exact() returns. */
#ifndef AO_EXACT_IMAGE_H
#define AO_EXACT_IMAGE_H

#include <stdbool.h>
#include <stddef.h>

#include "scene.h"
#include "tracer.h"

/* What ao_exact_render found: the closed form's kind ("sphere over a plane", "sphere alone", "open
 * plane", "closed box"), and the bound on the finite ground's residual (NAN where there is none). */
struct ao_exact_facts {
    const char *kind;
    double ground_error;
};

/* Fills rgb (width x height x 3 floats, top row first) with the scene's exact AO at AO distance
 * ao_distance (which must be infinite): each pixel the mean of the closed form over grid x grid
 * sub-pixel cell centres (0: the pixel centre alone, as without AA), the facts in *facts; false
 * with one line in why ("no closed form: REASON", or that the camera cannot form the image).
 * Calls the tracer from the calling thread, whose floating-point modes ao_tracer_thread_init
 * should have set (as for any thread that traces). */
bool ao_exact_render(const struct ao_scene *scene, const struct ao_tracer *tracer, float ao_distance, int width,
                     int height, int grid, float *rgb, struct ao_exact_facts *facts, char *why, size_t why_size);

#endif
