/* libFuzzer target for the OpenEXR reader: the input is written to a scratch .exr file and read
 * as a --reference would be. An image that loads must be of a size image.h allows, with finite
 * pixels. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "exr.h"
#include "fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_temp_path("input.exr");
    fuzz_write_file(path, data, size);
    float *rgb = NULL;
    int width = 0, height = 0;
    if (ao_exr_read(path, 0, 0, &rgb, &width, &height)) {
        const char *broken = NULL;
        if (width < 1 || height < 1 || width > AO_IMAGE_MAX_SIDE || height > AO_IMAGE_MAX_SIDE ||
            (long long)width * height > AO_IMAGE_MAX_PIXELS)
            broken = "size out of bounds";
        for (size_t i = 0; !broken && i < (size_t)width * (size_t)height * 3; i++)
            if (!isfinite(rgb[i]))
                broken = "non-finite pixel";
        if (broken) {
            fprintf(stderr, "fuzz_exr: %s\n", broken);
            abort();
        }
    }
    free(rgb);
    return 0;
}
