#include "glapi.h"

#include <stdio.h>

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

/* Prints a shader's or program's info log under the file name it came from. */
static void print_log(const char *what, const char *file, const char *log)
{
    fprintf(stderr, "aoview: %s %s failed:\n%s\n", what, file, log[0] ? log : "(no log)");
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
        print_log("compiling", file, log);
        gl->DeleteShader(shader);
        return 0;
    }
    return shader;
}

GLuint ao_glapi_program(const struct ao_glapi *gl, const char *name, const char *vertex,
                        const char *fragment)
{
    char vert_file[128], frag_file[128];
    snprintf(vert_file, sizeof vert_file, "shaders/%s.vert", name);
    snprintf(frag_file, sizeof frag_file, "shaders/%s.frag", name);

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
        print_log("linking", name, log);
        gl->DeleteProgram(program);
        return 0;
    }
    return program;
}
