/* What the image readers and writers share with their users: the largest image accepted anywhere,
 * and a string attribute of a saved image's header. Header only: image.h (PNG, PFM and the choice
 * by extension) and exr.h (OpenEXR) both include it, neither the other's header. */
#ifndef AO_IMAGE_TYPES_H
#define AO_IMAGE_TYPES_H

/* Largest image side and pixel count accepted anywhere (so buffers stay far from size_t limits). */
enum { AO_IMAGE_MAX_SIDE = 16384, AO_IMAGE_MAX_PIXELS = 16384 * 16384 / 4 };

/* A string attribute of a linear image's header (EXR keeps them; PFM has no place for them). */
struct ao_image_note {
    const char *key, *value;
};

#endif
