/* What the renderer hands its frame consumer and takes from its user: the settings a run is
 * rendered with, a published frame and the facts about it. Header only; the renderer (render.h)
 * fills frames, the triple buffer (frames.h) carries them, and the viewers read them without
 * knowing the renderer. */
#ifndef AO_FRAME_H
#define AO_FRAME_H

#include <stdbool.h>
#include <stdint.h>

#include "camera.h"
#include "modes.h"

/* What the user can change while rendering. */
struct ao_settings {
    int width, height;       /* image size in pixels (the window's, or --size) */
    enum ao_sampling sampling;
    bool aa;
    int spppp;               /* AO samples per pixel per pass; 0: auto (pass.c's schedule) */
    bool adaptive;           /* samples go where the estimated error is (pass.c, tile.c) */
    bool paused;
    bool previews;           /* coarse frames after each restart (preview.h), for a window's eye */
    bool navigating;         /* the camera is being moved (a drag): previews stop at cells of about
                                1/256 of the long side and the run waits there until a restart or
                                until this is cleared, which no restart needs */
    enum ao_output output;   /* AO or the normals view */
    enum ao_shading shading; /* Phong or flat mesh normals */
    struct ao_camera camera;
};

/* Facts about one published frame (one finished pass, or a preview: pass 0). A figure not known
 * yet is NAN, never 0: a preview's error, RMSE and converged share, and the error until both halves
 * have a pass. */
struct ao_frame_info {
    uint64_t restarts;       /* how many times accumulation restarted before this frame */
    uint32_t pass;           /* passes since the last restart, this one included; 0: a preview */
    uint32_t spp;            /* AO samples per pixel since the last restart (the most any pixel has) */
    uint32_t target_spp;
    double target_error;     /* the configuration's, 0 for none */
    double time_limit;       /* the configuration's, 0 for none */
    uint32_t spppp;          /* AO samples per pixel of this pass: the most a tile takes in it as the
                                schedule gives them, whatever a tile lacks of target_spp (the last
                                passes give each only that); 0 before the first */
    double mean_spp;         /* AO samples per pixel, averaged over the image (no pixel passes
                                target_spp) */
    uint64_t pixels;         /* of the image: its width times its height */
    double error;            /* estimated RMSE relative to the image mean, from the even and odd
                                passes without a reference; NAN until both halves have a pass */
    double converged;        /* share of the pixels that adaptive sampling leaves out of the next
                                pass; NAN before the first pass */
    double seconds;          /* render time since the last restart (previews' not counted) */
    uint64_t eye_rays, shadow_rays;
    double rmse;             /* against the reference; NAN without one, and before the first pass */
    enum ao_sampling sampling;
    bool aa;
    enum ao_output output;
    enum ao_shading shading;
    bool done;               /* spp reached target_spp, or the estimated error reached target_error,
                                or seconds reached time_limit, or adaptive sampling found nothing
                                left to sample */
};

/* A published frame: the running average, 3 linear floats per pixel, top row first, and the
 * estimated error of each tile of tile x tile pixels (the unit adaptive sampling decides on), as
 * an RMSE relative to the image mean, tiles_x per row, top row first; NAN until estimated. A preview
 * (block > 1, preview.h) holds width x height cells of block x block pixels of an image_width x
 * image_height image, its info that of the run it begins (pass 0), and no tile errors. */
struct ao_frame {
    struct ao_frame_info info;
    int width, height;
    float *rgb;
    int tile, tiles_x, tiles_y;
    float *tile_error;
    int block;
    int image_width, image_height;
};

#endif
