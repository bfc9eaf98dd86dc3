/* The image on screen and in PNG files (see display.h): the screen's image encoded to sRGB on the
 * CPU and blitted letterboxed, each shown frame's cost measured; the files' drawn at 1:1 through
 * the display shader into an offscreen framebuffer and read back. */
#include "display.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ao_shaders.h"
#include "clock.h"
#include "image.h"

/* Letterbox bars: dark grey, so that they stay apart from fully occluded (black) pixels. */
#define BAR_GREY 0.12f

struct ao_display {
    const struct ao_glapi *gl;
    GLuint program, vao, texture;
    GLint cover;                    /* the shader's share of the texture the image covers */
    float cover_x, cover_y;         /* its value for the image uploaded */
    int width, height;              /* of the texture; 0 before the first upload */
    int image_width, image_height;  /* of the image it shows */
    GLuint fbo, colour;             /* offscreen 1:1 target for PNG files, made on first use */
    int fbo_width, fbo_height;
    /* The screen's image: the CPU's 8-bit BGRA encoding of what ao_display_show was given (texels
     * of block x block pixels of an image_width x image_height image, top row first), and that
     * image resampled (nearest) to the rectangle it fills on screen, in the texture read through
     * screen_fbo (sized screen_width x screen_height; stale: older than the encoding). */
    uint8_t *encoded, *expanded;
    size_t encoded_room, expanded_room;
    int texels_width, texels_height, block, shown_width, shown_height;
    GLuint screen, screen_fbo;
    int screen_width, screen_height;
    bool stale;
    double frame_start;             /* monotonic seconds of the open frame's first GL call; 0: none */
    bool frame_uploads;             /* the open frame showed a new image */
    double costs[2][AO_DISPLAY_COSTS];  /* the last frames' costs, redraws' then new images' */
    int cost_count[2];              /* how many were measured of each */
    bool seen[2];                   /* a frame of the kind was presented: the first is not measured */
};

/* Starts the frame's clock, unless it runs. */
static void open_frame(struct ao_display *d)
{
    if (d->frame_start == 0.0)
        d->frame_start = ao_clock_seconds();
}

struct ao_display *ao_display_create(const struct ao_glapi *gl)
{
    return ao_display_create_from_source(gl, ao_shader_display_vert, ao_shader_display_frag);
}

struct ao_display *ao_display_create_from_source(const struct ao_glapi *gl, const char *vertex,
                                                 const char *fragment)
{
    struct ao_display *d = calloc(1, sizeof *d);
    if (!d) {
        fprintf(stderr, "aoview: out of memory for the display\n");
        return NULL;
    }
    d->gl = gl;
    d->program = ao_glapi_program(gl, "display", vertex, fragment);
    if (!d->program) {
        free(d);
        return NULL;
    }
    gl->UseProgram(d->program);
    gl->Uniform1i(gl->GetUniformLocation(d->program, "image"), 0);
    d->cover = gl->GetUniformLocation(d->program, "cover");
    gl->Uniform2f(d->cover, 1.0f, 1.0f);

    /* The triangle comes from gl_VertexID, but core profile still wants a vertex array bound. */
    gl->GenVertexArrays(1, &d->vao);

    /* Magnified, each pixel stays a block, so the noise under study is shown as it is rather than
     * smoothed; shrunk, linear (draw_image picks the minifying filter). */
    gl->GenTextures(1, &d->texture);
    gl->BindTexture(GL_TEXTURE_2D, d->texture);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return d;
}

void ao_display_destroy(struct ao_display *d)
{
    if (!d)
        return;
    const struct ao_glapi *gl = d->gl;
    gl->DeleteFramebuffers(1, &d->fbo);
    gl->DeleteRenderbuffers(1, &d->colour);
    gl->DeleteFramebuffers(1, &d->screen_fbo);
    gl->DeleteTextures(1, &d->screen);
    free(d->encoded);
    free(d->expanded);
    gl->DeleteTextures(1, &d->texture);
    gl->DeleteVertexArrays(1, &d->vao);
    gl->DeleteProgram(d->program);
    free(d);
}

bool ao_display_upload(struct ao_display *d, const float *rgb, int width, int height)
{
    return ao_display_upload_cells(d, rgb, width, height, 1, width, height);
}

bool ao_display_upload_cells(struct ao_display *d, const float *rgb, int width, int height, int block,
                             int image_width, int image_height)
{
    const struct ao_glapi *gl = d->gl;
    gl->ActiveTexture(GL_TEXTURE0);
    gl->BindTexture(GL_TEXTURE_2D, d->texture);
    gl->PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    /* The cells cover the image from its top left, the last row and column cut by its edges. */
    d->cover_x = (float)image_width / (float)(width * block);
    d->cover_y = (float)image_height / (float)(height * block);
    d->image_width = image_width;
    d->image_height = image_height;
    /* Row 0 of the texture is the image's top row; the vertex shader's uv accounts for it. */
    if (width == d->width && height == d->height) {
        gl->TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGB, GL_FLOAT, rgb);
        return true;
    }
    GLint max = 0;
    gl->GetIntegerv(GL_MAX_TEXTURE_SIZE, &max);
    if (width > max || height > max) {
        fprintf(stderr, "aoview: image %dx%d exceeds the OpenGL texture limit of %d pixels\n",
                width, height, (int)max);
        d->width = d->height = d->image_width = d->image_height = 0;
        return false;
    }
    gl->TexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, width, height, 0, GL_RGB, GL_FLOAT, rgb);
    d->width = width;
    d->height = height;
    return true;
}

struct ao_display_rect ao_display_fit(int image_width, int image_height, int fb_width, int fb_height)
{
    /* A whole magnification k that fills the framebuffer to within k pixels each way (an image
     * rendered at 1/k of it, or at its size) keeps every pixel a k x k block. */
    int k = image_width > 0 && image_height > 0 ? fb_width / image_width : 0;
    k = k > 0 && fb_height / image_height < k ? fb_height / image_height : k;
    if (k >= 1 && fb_width - k * image_width < k && fb_height - k * image_height < k)
        return (struct ao_display_rect){(fb_width - k * image_width) / 2, (fb_height - k * image_height) / 2,
                                        k * image_width, k * image_height};
    /* Else compare fb_width / fb_height with the image's ratio in integers: the wider side gets bars. */
    struct ao_display_rect r = {0, 0, fb_width, fb_height};
    long long lhs = (long long)fb_width * image_height, rhs = (long long)fb_height * image_width;
    if (lhs > rhs)
        r.width = (int)(rhs / image_height);
    else
        r.height = (int)(lhs / image_width);
    r.x = (fb_width - r.width) / 2;
    r.y = (fb_height - r.height) / 2;
    return r;
}

/* Draws the texture through the display shader into the given viewport of the bound framebuffer. */
static void draw_image(struct ao_display *d, struct ao_display_rect r)
{
    const struct ao_glapi *gl = d->gl;
    gl->Viewport(r.x, r.y, r.width, r.height);
    gl->Disable(GL_BLEND);
    gl->UseProgram(d->program);
    gl->Uniform2f(d->cover, d->cover_x, d->cover_y);
    gl->ActiveTexture(GL_TEXTURE0);
    gl->BindTexture(GL_TEXTURE_2D, d->texture);
    /* At 1:1 the level of detail is 0 only up to rounding: a linear minifying filter would then
     * blend in about 1e-5 of a neighbour, enough to move a pixel near a rounding boundary by one
     * 8-bit step between two files of one image. Nearest reads each texel as it is. */
    bool shrunk = r.width < d->image_width || r.height < d->image_height;
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, shrunk ? GL_LINEAR : GL_NEAREST);
    gl->BindVertexArray(d->vao);
    gl->DrawArrays(GL_TRIANGLES, 0, 3);
}

/* Makes *buffer hold `bytes` bytes (*room counting them); false after one line when memory is short. */
static bool reserve(uint8_t **buffer, size_t *room, size_t bytes)
{
    if (bytes <= *room)
        return true;
    uint8_t *more = realloc(*buffer, bytes);
    if (!more) {
        fprintf(stderr, "aoview: out of memory for the image on the screen\n");
        return false;
    }
    *buffer = more;
    *room = bytes;
    return true;
}

bool ao_display_show(struct ao_display *d, const float *rgb, int width, int height, int block, int image_width,
                     int image_height)
{
    open_frame(d);
    d->frame_uploads = true;
    if (!reserve(&d->encoded, &d->encoded_room, 4 * (size_t)width * (size_t)height))
        return false;
    ao_image_encode_srgb8_bgra(rgb, (size_t)width * (size_t)height, d->encoded);
    d->texels_width = width;
    d->texels_height = height;
    d->block = block;
    d->shown_width = image_width;
    d->shown_height = image_height;
    d->stale = true;
    return true;
}

/* The screen's pixels for rectangle r: the encoding itself at 1:1, else the texels resampled to r
 * (nearest: pixel x of r shows image pixel x * image_width / r.width, which its texel holds); NULL
 * when memory is short. */
static const uint8_t *screen_pixels(struct ao_display *d, struct ao_display_rect r)
{
    if (d->block == 1 && r.width == d->shown_width && r.height == d->shown_height)
        return d->encoded;
    size_t row = 4 * (size_t)r.width;
    if (!reserve(&d->expanded, &d->expanded_room, row * (size_t)r.height))
        return NULL;
    uint32_t *out = (uint32_t *)(void *)d->expanded;
    const uint32_t *texels = (const uint32_t *)(const void *)d->encoded;
    int previous = -1;
    for (int y = 0; y < r.height; y++, out += r.width) {
        int texel_row = (int)((int64_t)y * d->shown_height / r.height) / d->block;
        if (texel_row == previous) { /* a block's rows are alike */
            memcpy(out, out - r.width, row);
            continue;
        }
        previous = texel_row;
        const uint32_t *in = texels + (size_t)texel_row * (size_t)d->texels_width;
        for (int x = 0; x < r.width; x++)
            out[x] = in[(int)((int64_t)x * d->shown_width / r.width) / d->block];
    }
    return d->expanded;
}

/* Uploads the screen's pixels for r into the screen texture (made or remade at r's size): unsized
 * GL_RGBA from BGRA bytes, which Mesa keeps as the window's own B8G8R8A8, so that the blit to the
 * window is a copy; false when memory or GL's size limit is short. */
static bool upload_screen(struct ao_display *d, struct ao_display_rect r)
{
    const struct ao_glapi *gl = d->gl;
    const uint8_t *pixels = screen_pixels(d, r);
    if (!pixels)
        return false;
    if (!d->screen) {
        gl->GenTextures(1, &d->screen);
        gl->GenFramebuffers(1, &d->screen_fbo);
    }
    gl->ActiveTexture(GL_TEXTURE0);
    gl->BindTexture(GL_TEXTURE_2D, d->screen);
    gl->PixelStorei(GL_UNPACK_ALIGNMENT, 4);
    if (r.width == d->screen_width && r.height == d->screen_height) {
        gl->TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, r.width, r.height, GL_BGRA, GL_UNSIGNED_BYTE, pixels);
    } else {
        GLint max = 0;
        gl->GetIntegerv(GL_MAX_TEXTURE_SIZE, &max);
        if (r.width > max || r.height > max) {
            fprintf(stderr, "aoview: a %dx%d window exceeds the OpenGL texture limit of %d pixels\n", r.width,
                    r.height, (int)max);
            return false;
        }
        gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        gl->TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, r.width, r.height, 0, GL_BGRA, GL_UNSIGNED_BYTE, pixels);
        gl->BindFramebuffer(GL_FRAMEBUFFER, d->screen_fbo);
        gl->FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, d->screen, 0);
        gl->BindFramebuffer(GL_FRAMEBUFFER, 0);
        d->screen_width = r.width;
        d->screen_height = r.height;
    }
    d->stale = false;
    return true;
}

/* Clears the parts of the framebuffer outside r to the letterbox colour. */
static void clear_bars(const struct ao_glapi *gl, struct ao_display_rect r, int fb_width, int fb_height)
{
    const struct ao_display_rect bars[4] = {
        {0, 0, r.x, fb_height}, {r.x + r.width, 0, fb_width - r.x - r.width, fb_height},
        {r.x, 0, r.width, r.y}, {r.x, r.y + r.height, r.width, fb_height - r.y - r.height}};
    gl->ClearColor(BAR_GREY, BAR_GREY, BAR_GREY, 1.0f);
    gl->Enable(GL_SCISSOR_TEST);
    for (int k = 0; k < 4; k++)
        if (bars[k].width > 0 && bars[k].height > 0) {
            gl->Scissor(bars[k].x, bars[k].y, bars[k].width, bars[k].height);
            gl->Clear(GL_COLOR_BUFFER_BIT);
        }
    gl->Disable(GL_SCISSOR_TEST);
}

void ao_display_draw(struct ao_display *d, int fb_width, int fb_height)
{
    const struct ao_glapi *gl = d->gl;
    open_frame(d);
    gl->Viewport(0, 0, fb_width, fb_height);
    struct ao_display_rect r = {0, 0, 0, 0};
    if (d->texels_width > 0 && fb_width > 0 && fb_height > 0)
        r = ao_display_fit(d->shown_width, d->shown_height, fb_width, fb_height);
    bool shown = r.width > 0 && r.height > 0 &&
                 ((!d->stale && r.width == d->screen_width && r.height == d->screen_height) || upload_screen(d, r));
    clear_bars(gl, shown ? r : (struct ao_display_rect){0, 0, 0, 0}, fb_width, fb_height);
    if (!shown)
        return;
    /* Top row first in memory as the window's pixels are, which GL counts from the bottom: the
     * source flipped, so that the blit is a plain copy. */
    gl->BindFramebuffer(GL_READ_FRAMEBUFFER, d->screen_fbo);
    gl->BindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    gl->BlitFramebuffer(0, r.height, r.width, 0, r.x, r.y, r.x + r.width, r.y + r.height, GL_COLOR_BUFFER_BIT,
                        GL_NEAREST);
    gl->BindFramebuffer(GL_FRAMEBUFFER, 0);
}

void ao_display_presented(struct ao_display *d)
{
    d->gl->Finish();
    int kind = d->frame_uploads;
    if (d->seen[kind]) /* the first pays once for the shaders' compilation and the textures */
        d->costs[kind][d->cost_count[kind]++ % AO_DISPLAY_COSTS] = ao_clock_seconds() - d->frame_start;
    d->seen[kind] = true;
    d->frame_start = 0.0;
    d->frame_uploads = false;
}

/* The median of the last costs of a kind (of all while fewer were measured); 0 before one. */
static double median_cost(const struct ao_display *d, int kind)
{
    int n = d->cost_count[kind] < AO_DISPLAY_COSTS ? d->cost_count[kind] : AO_DISPLAY_COSTS;
    double v[AO_DISPLAY_COSTS];
    for (int k = 0; k < n; k++) { /* insertion sort */
        int j = k;
        for (; j > 0 && v[j - 1] > d->costs[kind][k]; j--)
            v[j] = v[j - 1];
        v[j] = d->costs[kind][k];
    }
    return n ? v[n / 2] : 0.0;
}

struct ao_display_cost ao_display_cost(const struct ao_display *d)
{
    return (struct ao_display_cost){.new_image = median_cost(d, 1), .redraw = median_cost(d, 0)};
}

/* Makes the offscreen framebuffer match the image size and binds it; false if GL refuses it. */
static bool bind_offscreen(struct ao_display *d)
{
    const struct ao_glapi *gl = d->gl;
    if (!d->fbo) {
        gl->GenFramebuffers(1, &d->fbo);
        gl->GenRenderbuffers(1, &d->colour);
    }
    gl->BindFramebuffer(GL_FRAMEBUFFER, d->fbo);
    if (d->fbo_width != d->image_width || d->fbo_height != d->image_height) {
        gl->BindRenderbuffer(GL_RENDERBUFFER, d->colour);
        gl->RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, d->image_width, d->image_height);
        gl->FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, d->colour);
        d->fbo_width = d->image_width;
        d->fbo_height = d->image_height;
    }
    if (gl->CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        fprintf(stderr, "aoview: OpenGL cannot render a %dx%d offscreen image\n", d->image_width, d->image_height);
        gl->BindFramebuffer(GL_FRAMEBUFFER, 0);
        return false;
    }
    return true;
}

/* GL reads the bottom row first; PNG rows go top first. Swaps rows in place. */
static void flip_rows(uint8_t *pixels, size_t row, int height)
{
    for (int y = 0; y < height / 2; y++) {
        uint8_t *a = pixels + row * (size_t)y, *b = pixels + row * (size_t)(height - 1 - y);
        for (size_t i = 0; i < row; i++) {
            uint8_t t = a[i];
            a[i] = b[i];
            b[i] = t;
        }
    }
}

bool ao_display_write_png(struct ao_display *d, const char *path)
{
    return ao_display_write_png_with(d, path, NULL, NULL);
}

bool ao_display_write_png_with(struct ao_display *d, const char *path, ao_display_overlay *overlay, void *user)
{
    const struct ao_glapi *gl = d->gl;
    if (d->image_width == 0) {
        fprintf(stderr, "aoview: %s: no image to save yet\n", path);
        return false;
    }
    size_t row = (size_t)d->image_width * 3;
    uint8_t *pixels = malloc(row * (size_t)d->image_height);
    if (!pixels) {
        fprintf(stderr, "aoview: %s: out of memory\n", path);
        return false;
    }
    if (!bind_offscreen(d)) {
        free(pixels);
        return false;
    }

    /* Draw at 1:1 and read back tightly packed (rows of 3 * width bytes). */
    draw_image(d, (struct ao_display_rect){0, 0, d->image_width, d->image_height});
    if (overlay)
        overlay(user, d->image_width, d->image_height);
    gl->PixelStorei(GL_PACK_ALIGNMENT, 1);
    gl->ReadPixels(0, 0, d->image_width, d->image_height, GL_RGB, GL_UNSIGNED_BYTE, pixels);
    gl->BindFramebuffer(GL_FRAMEBUFFER, 0);
    flip_rows(pixels, row, d->image_height);

    GLenum error = gl->GetError();
    bool ok = error == GL_NO_ERROR;
    if (!ok)
        fprintf(stderr, "aoview: %s: OpenGL error 0x%x while reading the image back\n", path, error);
    else
        ok = ao_image_write_png(path, pixels, d->image_width, d->image_height);
    free(pixels);
    return ok;
}
