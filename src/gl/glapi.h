/* The OpenGL 3.3 core functions aoview calls, loaded through whoever made the context
 * (glfwGetProcAddress in the window, OSMesaGetProcAddress headless), so that the drawing code
 * includes no window-system header; and the shader program builder they share. */
#ifndef AO_GLAPI_H
#define AO_GLAPI_H

#include <stdbool.h>

#include <GL/glcorearb.h>

/* Every GL function used, as X(type, name without the gl prefix). */
#define AO_GLAPI_FUNCTIONS(X) \
    X(PFNGLACTIVETEXTUREPROC, ActiveTexture) \
    X(PFNGLATTACHSHADERPROC, AttachShader) \
    X(PFNGLBINDBUFFERPROC, BindBuffer) \
    X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer) \
    X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer) \
    X(PFNGLBINDTEXTUREPROC, BindTexture) \
    X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray) \
    X(PFNGLBLENDFUNCPROC, BlendFunc) \
    X(PFNGLBLITFRAMEBUFFERPROC, BlitFramebuffer) \
    X(PFNGLBUFFERDATAPROC, BufferData) \
    X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus) \
    X(PFNGLCLEARPROC, Clear) \
    X(PFNGLCLEARCOLORPROC, ClearColor) \
    X(PFNGLCOMPILESHADERPROC, CompileShader) \
    X(PFNGLCREATEPROGRAMPROC, CreateProgram) \
    X(PFNGLCREATESHADERPROC, CreateShader) \
    X(PFNGLDELETEBUFFERSPROC, DeleteBuffers) \
    X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers) \
    X(PFNGLDELETEPROGRAMPROC, DeleteProgram) \
    X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers) \
    X(PFNGLDELETESHADERPROC, DeleteShader) \
    X(PFNGLDELETETEXTURESPROC, DeleteTextures) \
    X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays) \
    X(PFNGLDISABLEPROC, Disable) \
    X(PFNGLDRAWARRAYSPROC, DrawArrays) \
    X(PFNGLENABLEPROC, Enable) \
    X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray) \
    X(PFNGLFINISHPROC, Finish) \
    X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer) \
    X(PFNGLFRAMEBUFFERTEXTURE2DPROC, FramebufferTexture2D) \
    X(PFNGLGENBUFFERSPROC, GenBuffers) \
    X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers) \
    X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers) \
    X(PFNGLGENTEXTURESPROC, GenTextures) \
    X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays) \
    X(PFNGLGETERRORPROC, GetError) \
    X(PFNGLGETINTEGERVPROC, GetIntegerv) \
    X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog) \
    X(PFNGLGETPROGRAMIVPROC, GetProgramiv) \
    X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog) \
    X(PFNGLGETSHADERIVPROC, GetShaderiv) \
    X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation) \
    X(PFNGLLINKPROGRAMPROC, LinkProgram) \
    X(PFNGLPIXELSTOREIPROC, PixelStorei) \
    X(PFNGLREADPIXELSPROC, ReadPixels) \
    X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage) \
    X(PFNGLSCISSORPROC, Scissor) \
    X(PFNGLSHADERSOURCEPROC, ShaderSource) \
    X(PFNGLTEXIMAGE2DPROC, TexImage2D) \
    X(PFNGLTEXPARAMETERIPROC, TexParameteri) \
    X(PFNGLTEXSUBIMAGE2DPROC, TexSubImage2D) \
    X(PFNGLUNIFORM1IPROC, Uniform1i) \
    X(PFNGLUNIFORM2FPROC, Uniform2f) \
    X(PFNGLUNIFORM4FPROC, Uniform4f) \
    X(PFNGLUSEPROGRAMPROC, UseProgram) \
    X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer) \
    X(PFNGLVIEWPORTPROC, Viewport)

/* The loaded entry points of one context: call as gl->Clear(...). Owned by the context's thread. */
struct ao_glapi {
#define AO_GLAPI_MEMBER(type, name) type name;
    AO_GLAPI_FUNCTIONS(AO_GLAPI_MEMBER)
#undef AO_GLAPI_MEMBER
};

/* A GL entry point as the context's own lookup returns it (GLFWglproc, OSMESAproc). */
typedef void (*ao_glapi_proc)(void);

/* Fills *gl through get_proc with the context current; false with one message naming the first
 * missing function. GL thread. */
bool ao_glapi_load(struct ao_glapi *gl, ao_glapi_proc (*get_proc)(const char *name));

/* Compiles and links a program from two sources named name.vert and name.frag (the files in
 * shaders/); 0 after one line naming the failing shader with the first error of its log. GL
 * thread. */
GLuint ao_glapi_program(const struct ao_glapi *gl, const char *name, const char *vertex,
                        const char *fragment);

#endif
