/* Benchmark: where a window's frame time goes on the GL at hand (Mesa's llvmpipe under Xvfb here),
 * phase by phase, at 1920x1080 and 3840x2160: the CPU's sRGB encoding of a new image, its upload and
 * copy into the window (display.c's path), a preview's cells expanded to the window, a redraw of an
 * image already there, the status overlay, the swap; and for comparison the ways not taken: the
 * display shader over every window pixel from the float image (the window's draw before), and a
 * blit from a sized GL_RGBA8 texture (a shader pass in Mesa). Medians of 9, glFinish after each
 * phase, the bunny at 1 spp as the image. One line per size; asserts nothing.
 * Run under a display with room for the window (it takes the size asked):
 *   xvfb-run -a -s "-screen 0 4320x2440x24" ./build/tests/bench_display [SCENE] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "ao_shaders.h"
#include "bench_util.h"
#include "config.h"
#include "display.h"
#include "glapi.h"
#include "hud.h"
#include "image.h"
#include "program.h"

enum { REPEATS = 9 };

struct bench {
    GLFWwindow *window;
    struct ao_glapi gl;
    struct ao_display *display;
    struct ao_hud *hud;
    int width, height;
    uint8_t *encoded;                    /* encode's output */
    GLuint program, texture, vao;        /* shader_draw's */
    GLuint sized, sized_fbo;             /* sized_blit's */
};

/* The median wall time of REPEATS runs of phase(b, rgb), each finished by glFinish, in ms. */
static double time_ms(struct bench *b, void (*phase)(struct bench *, const float *), const float *rgb)
{
    double t[REPEATS];
    for (int k = 0; k < REPEATS; k++) {
        double t0 = bench_now();
        phase(b, rgb);
        b->gl.Finish();
        t[k] = 1e3 * (bench_now() - t0);
    }
    return bench_median(t, REPEATS);
}

static void encode(struct bench *b, const float *rgb)
{
    ao_image_encode_srgb8_bgra(rgb, (size_t)b->width * (size_t)b->height, b->encoded);
}

static void new_image(struct bench *b, const float *rgb)
{
    ao_display_show(b->display, rgb, b->width, b->height, 1, b->width, b->height);
    ao_display_draw(b->display, b->width, b->height);
}

static void redraw(struct bench *b, const float *rgb)
{
    (void)rgb;
    ao_display_draw(b->display, b->width, b->height);
}

/* A preview of 16x16-pixel cells: the first rows of rgb as its cells. */
static void preview(struct bench *b, const float *rgb)
{
    ao_display_show(b->display, rgb, (b->width + 15) / 16, (b->height + 15) / 16, 16, b->width, b->height);
    ao_display_draw(b->display, b->width, b->height);
}

static void overlay(struct bench *b, const float *rgb)
{
    (void)rgb;
    static const char text[] = "bunny.scene  3840x2160  cosine\nAA on  spp 12 of 256  error 1.20 %  4.2s\n"
                               "~30 s left  25.0 Mrays/s  pass 12\nauto 1 spp/pass\nadaptive: 0 % converged\n"
                               "mean 12 spp";
    ao_hud_draw(b->hud, text, 16, 16, 2.0f, b->width, b->height);
}

static void swap(struct bench *b, const float *rgb)
{
    (void)rgb;
    glfwSwapBuffers(b->window);
}

/* The window's draw before: the float image uploaded, the display shader over every pixel. */
static void shader_draw(struct bench *b, const float *rgb)
{
    const struct ao_glapi *gl = &b->gl;
    gl->UseProgram(b->program);
    gl->Uniform1i(gl->GetUniformLocation(b->program, "image"), 0);
    gl->Uniform2f(gl->GetUniformLocation(b->program, "cover"), 1.0f, 1.0f);
    gl->ActiveTexture(GL_TEXTURE0);
    gl->BindTexture(GL_TEXTURE_2D, b->texture);
    gl->PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl->TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, b->width, b->height, GL_RGB, GL_FLOAT, rgb);
    gl->Viewport(0, 0, b->width, b->height);
    gl->BindVertexArray(b->vao);
    gl->DrawArrays(GL_TRIANGLES, 0, 3);
}

/* A blit to the window from a sized GL_RGBA8 texture, its source flipped as display.c's. */
static void sized_blit(struct bench *b, const float *rgb)
{
    (void)rgb;
    const struct ao_glapi *gl = &b->gl;
    gl->BindFramebuffer(GL_READ_FRAMEBUFFER, b->sized_fbo);
    gl->BindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    gl->BlitFramebuffer(0, b->height, b->width, 0, 0, 0, b->width, b->height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    gl->BindFramebuffer(GL_FRAMEBUFFER, 0);
}

static void measure(const struct ao_scene *scene, const struct ao_tracer *tracer, int width, int height)
{
    struct ao_render_config config = {.scene = scene, .tracer = tracer, .threads = 2, .seed = 1, .target_spp = 1,
                                      .ao_distance = scene->ao_distance};
    struct ao_settings settings = {.width = width, .height = height, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .camera = scene->camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    if (!r || !ao_render_wait(r))
        exit(1);
    const float *rgb = ao_render_take_frame(r)->rgb;

    struct bench b = {.width = width, .height = height};
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    b.window = glfwCreateWindow(width, height, "bench_display", NULL, NULL);
    if (!b.window)
        exit(1);
    glfwMakeContextCurrent(b.window);
    glfwSwapInterval(0);
    int fb_width, fb_height;
    glfwGetFramebufferSize(b.window, &fb_width, &fb_height);
    if (fb_width != width || fb_height != height) {
        fprintf(stderr, "bench_display: the window is %dx%d, not %dx%d\n", fb_width, fb_height, width, height);
        exit(1);
    }
    if (!ao_glapi_load(&b.gl, glfwGetProcAddress) || !(b.display = ao_display_create(&b.gl)) ||
        !(b.hud = ao_hud_create(&b.gl)) ||
        !(b.program = ao_glapi_program(&b.gl, "display", ao_shader_display_vert, ao_shader_display_frag)) ||
        !(b.encoded = malloc(4 * (size_t)width * (size_t)height)))
        exit(1);
    /* The ways not taken: a float texture for the shader, a sized RGBA8 one to blit from. */
    const struct ao_glapi *gl = &b.gl;
    gl->GenVertexArrays(1, &b.vao);
    gl->GenTextures(1, &b.texture);
    gl->BindTexture(GL_TEXTURE_2D, b.texture);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl->TexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, width, height, 0, GL_RGB, GL_FLOAT, NULL);
    gl->GenTextures(1, &b.sized);
    gl->GenFramebuffers(1, &b.sized_fbo);
    gl->BindTexture(GL_TEXTURE_2D, b.sized);
    gl->TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width, height, 0, GL_BGRA, GL_UNSIGNED_BYTE, NULL);
    gl->BindFramebuffer(GL_FRAMEBUFFER, b.sized_fbo);
    gl->FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, b.sized, 0);
    gl->BindFramebuffer(GL_FRAMEBUFFER, 0);
    double t_encode = time_ms(&b, encode, rgb), t_new = time_ms(&b, new_image, rgb);
    double t_redraw = time_ms(&b, redraw, rgb), t_preview = time_ms(&b, preview, rgb);
    double t_overlay = time_ms(&b, overlay, rgb), t_swap = time_ms(&b, swap, rgb);
    double t_shader = time_ms(&b, shader_draw, rgb), t_sized = time_ms(&b, sized_blit, rgb);
    printf("%dx%d: new image %.1f ms (its encoding %.1f), redraw %.1f, preview of 16 px cells %.1f, overlay %.1f, "
           "swap %.1f; not taken: the display shader over every pixel %.1f, a blit from a sized RGBA8 texture "
           "%.1f\n",
           width, height, t_new, t_encode, t_redraw, t_preview, t_overlay, t_swap, t_shader, t_sized);
    fflush(stdout);
    gl->DeleteFramebuffers(1, &b.sized_fbo);
    gl->DeleteTextures(1, &b.sized);
    gl->DeleteTextures(1, &b.texture);
    gl->DeleteVertexArrays(1, &b.vao);
    gl->DeleteProgram(b.program);
    free(b.encoded);
    ao_hud_destroy(b.hud);
    ao_display_destroy(b.display);
    glfwDestroyWindow(b.window);
    ao_render_destroy(r);
}

int main(int argc, char **argv)
{
    ao_program_init();
    if (!glfwInit()) {
        printf("SKIP: no display (run under xvfb-run -a -s \"-screen 0 4320x2440x24\")\n");
        return 77;
    }
    struct ao_scene scene;
    struct ao_tracer *tracer = bench_load(argc > 1 ? argv[1] : AO_DEFAULT_SCENE, &scene);
    measure(&scene, tracer, 1920, 1080);
    measure(&scene, tracer, 3840, 2160);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    glfwTerminate();
    return 0;
}
