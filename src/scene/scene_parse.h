/* The statements of a scene file: its text read line by line into the scene as it is read
 * (scene_place.h), each line's words checked and reported at its line. Private to scene_load.c. */
#ifndef AO_SCENE_PARSE_H
#define AO_SCENE_PARSE_H

#include <stdbool.h>

#include "scene.h"
#include "scene_place.h"

/* Reads every line of text into w (and the scene's spheres, image size, background and AO
 * distance into s), counting lines in c; false after reporting the first bad line. */
bool ao_scene_parse_lines(struct ao_cursor *c, struct ao_scene *s, struct ao_world *w, const char *text);

#endif
