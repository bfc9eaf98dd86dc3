/* The window's keys; see keys.h. */
#include "keys.h"

#include <ctype.h>

static const char HELP[] =
    "U  uniform sphere sampling\n"
    "H  uniform hemisphere sampling\n"
    "C  cosine sampling\n"
    "A  anti-aliasing on/off\n"
    "Space  pause/resume\n"
    "R  restart accumulation\n"
    "+ -  double/halve samples per pass (leaves auto)\n"
    "G  adaptive sampling on/off\n"
    "E  estimated error map on/off\n"
    "D  difference from --reference on/off\n"
    "N  normals view on/off (restarts)\n"
    "F  flat/Phong mesh normals (restarts)\n"
    "V  compare with a second configuration at equal time\n"
    "B  split / side-by-side comparison\n"
    "S  save aoview-N.png and aoview-N.pfm (or .exr)\n"
    "[ ]  halve/double the pixel size (restarts)\n"
    "left drag  orbit (on the divider: move it)\n"
    "right drag  pan\n"
    "wheel  zoom\n"
    "F1 or ?  this help\n"
    "F2  hide/show the overlay and error chart\n"
    "Esc or Q  quit";

const char *ao_keys_help(void)
{
    return HELP;
}

/* Doubles (factor 2) or halves (factor 0) the samples per pass within 1..65536; from auto (0),
 * those of the pass on screen, so that the keys switch to manual where auto stood. */
static int scale_spppp(int spppp, uint32_t shown, int factor)
{
    if (spppp == 0)
        spppp = shown ? (int)shown : 1;
    long next = factor ? 2L * spppp : spppp / 2;
    return next < 1 ? 1 : next > 65536 ? 65536 : (int)next;
}

enum ao_key_action ao_keys_typed(unsigned int codepoint, struct ao_settings *s, uint32_t shown_spppp)
{
    if (codepoint > 127)
        return AO_KEY_NONE;
    switch (tolower((int)codepoint)) {
    case 'u': s->sampling = AO_SAMPLING_UNIFORM; break;
    case 'h': s->sampling = AO_SAMPLING_HEMISPHERE; break;
    case 'c': s->sampling = AO_SAMPLING_COSINE; break;
    case 'a': s->aa = !s->aa; break;
    case ' ': s->paused = !s->paused; break;
    case '+': case '=': s->spppp = scale_spppp(s->spppp, shown_spppp, 2); break;
    case '-': s->spppp = scale_spppp(s->spppp, shown_spppp, 0); break;
    case 'g': s->adaptive = !s->adaptive; break;
    case 'n': s->output = s->output == AO_OUTPUT_NORMALS ? AO_OUTPUT_AO : AO_OUTPUT_NORMALS; break;
    case 'f': s->shading = s->shading == AO_SHADING_FLAT ? AO_SHADING_PHONG : AO_SHADING_FLAT; break;
    case 'e': return AO_KEY_ERROR_VIEW;
    case 'd': return AO_KEY_DIFFERENCE_VIEW;
    case 'r': return AO_KEY_RESTART;
    case 'v': return AO_KEY_COMPARE;
    case 'b': return AO_KEY_LAYOUT;
    case 's': return AO_KEY_SAVE;
    case '[': return AO_KEY_FINER;
    case ']': return AO_KEY_COARSER;
    case '?': return AO_KEY_HELP;
    case 'q': return AO_KEY_QUIT;
    default: return AO_KEY_NONE;
    }
    return AO_KEY_SETTINGS;
}
