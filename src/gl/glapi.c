/* The OpenGL 3.3 core entry points aoview calls (see glapi.h), looked up through the context's
 * loader, each checked present, so that a context without one fails in one line. */
#include "glapi.h"

#include <stdio.h>
#include <string.h>

bool ao_glapi_load(struct ao_glapi *gl, ao_glapi_proc (*get_proc)(const char *name))
{
    /* Each entry point is looked up under its "gl" name and cast to its own pointer type. */
#define AO_GLAPI_LOAD(type, name) \
    gl->name = (type)get_proc("gl" #name); \
    if (!gl->name) { \
        fprintf(stderr, "aoview: OpenGL function gl" #name " is missing (OpenGL 3.3 needed)\n"); \
        return false; \
    }
    AO_GLAPI_FUNCTIONS(AO_GLAPI_LOAD)
#undef AO_GLAPI_LOAD
    return true;
}

/* Reports a shader or program that failed on one line: its file name and the first line of its
 * info log (the first error; the driver's log runs on for each further one). */
static void print_log(const char *file, const char *what, const char *log)
{
    if (!log[0])
        log = "the driver gives no reason";
    fprintf(stderr, "aoview: %s %s: %.*s\n", file, what, (int)strcspn(log, "\n"), log);
}

/* One compiled shader stage, or 0 after printing its log. */
static GLuint compile(const struct ao_glapi *gl, GLenum stage, const char *file, const char *source)
{
    GLuint shader = gl->CreateShader(stage);
    gl->ShaderSource(shader, 1, &source, NULL);
    gl->CompileShader(shader);
    GLint ok = GL_FALSE;
    gl->GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096] = "";
        gl->GetShaderInfoLog(shader, sizeof log, NULL, log);
        print_log(file, "does not compile", log);
        gl->DeleteShader(shader);
        return 0;
    }
    return shader;
}

GLuint ao_glapi_program(const struct ao_glapi *gl, const char *name, const char *vertex,
                        const char *fragment)
{
    char vert_file[128], frag_file[128], both[160];
    snprintf(vert_file, sizeof vert_file, "shaders/%s.vert", name);
    snprintf(frag_file, sizeof frag_file, "shaders/%s.frag", name);
    snprintf(both, sizeof both, "%s and .frag", vert_file);

    GLuint vs = compile(gl, GL_VERTEX_SHADER, vert_file, vertex);
    GLuint fs = vs ? compile(gl, GL_FRAGMENT_SHADER, frag_file, fragment) : 0;
    if (!fs) {
        gl->DeleteShader(vs);
        return 0;
    }
    GLuint program = gl->CreateProgram();
    gl->AttachShader(program, vs);
    gl->AttachShader(program, fs);
    gl->LinkProgram(program);
    gl->DeleteShader(vs);
    gl->DeleteShader(fs);
    GLint ok = GL_FALSE;
    gl->GetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[4096] = "";
        gl->GetProgramInfoLog(program, sizeof log, NULL, log);
        print_log(both, "do not link", log);
        gl->DeleteProgram(program);
        return 0;
    }
    return program;
}
