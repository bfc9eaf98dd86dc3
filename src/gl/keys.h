/* The window's keys: what each typed character does (a change of the render's settings, or one of
 * the viewer's own actions) and the help text that lists every key and mouse gesture. No GL and no
 * window: window.c asks and acts. */
#ifndef AO_KEYS_H
#define AO_KEYS_H

#include <stdint.h>

#include "frame.h"

/* What a key asks of the viewer. */
enum ao_key_action {
    AO_KEY_NONE,             /* not a key of the viewer's */
    AO_KEY_SETTINGS,         /* the settings were changed: apply them */
    AO_KEY_ERROR_VIEW,       /* E: the estimated error's heat map on/off */
    AO_KEY_DIFFERENCE_VIEW,  /* D: the difference from --reference on/off */
    AO_KEY_RESTART,          /* R */
    AO_KEY_COMPARE,          /* V: the equal-time comparison on/off */
    AO_KEY_LAYOUT,           /* B: split or side by side */
    AO_KEY_SAVE,             /* S: a screenshot */
    AO_KEY_FINER,            /* [: halve the pixel size */
    AO_KEY_COARSER,          /* ]: double the pixel size */
    AO_KEY_HELP,             /* ?: the help on/off */
    AO_KEY_QUIT,             /* Q */
};

/* What typing the character codepoint does, by character so that it follows the keyboard layout
 * ('+' from the main keyboard or the keypad, '=' as the unshifted '+', either case): a change of
 * *s (sampling, AA, pause, samples per pass, adaptive sampling, normals view, shading) returned as
 * AO_KEY_SETTINGS, where + and - leave auto from the samples per pass on screen (shown_spppp, 0
 * before a pass: 1); else the viewer's action, *s untouched. Pure. */
enum ao_key_action ao_keys_typed(unsigned int codepoint, struct ao_settings *s, uint32_t shown_spppp);

/* The help overlay's text: a line per key or gesture, '\n' between them. */
const char *ao_keys_help(void);

#endif
