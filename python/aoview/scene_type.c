/* _core's Scene type and the module functions that fill it and read it whole: load a file, make a
 * scene of arrays, render its exact image; see scene_type.h. */
#define PY_SSIZE_T_CLEAN
#include "scene_type.h"

#include <math.h>
#include <stdio.h>
#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "arguments.h"
#include "exact_image.h"
#include "messages.h"
#include "options.h"
#include "scene_load.h"
#include "tracer.h"

static void scene_dealloc(SceneObject *self)
{
    ao_tracer_destroy(self->tracer);
    if (self->loaded)
        ao_scene_finish(&self->scene);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

/* True when every albedo and the background are grey: the image's three channels are equal. */
static PyObject *scene_is_grey(SceneObject *self, PyObject *unused)
{
    (void)unused;
    const struct ao_scene *s = &self->scene;
    bool grey = s->background.x == s->background.y && s->background.y == s->background.z;
    for (size_t i = 0; grey && i < s->albedo_count; i++)
        grey = s->albedos[i].x == s->albedos[i].y && s->albedos[i].y == s->albedos[i].z;
    for (size_t i = 0; grey && i < s->sphere_count; i++)
        grey = s->spheres[i].albedo.x == s->spheres[i].albedo.y && s->spheres[i].albedo.y == s->spheres[i].albedo.z;
    return PyBool_FromLong(grey);
}

/* (name, triangles, spheres, default width, default height) */
static PyObject *scene_facts(SceneObject *self, PyObject *unused)
{
    (void)unused;
    return Py_BuildValue("(snnii)", self->scene.name, (Py_ssize_t)self->scene.triangle_count,
                         (Py_ssize_t)self->scene.sphere_count, self->scene.width, self->scene.height);
}

static PyMethodDef scene_methods[] = {
    {"_is_grey", (PyCFunction)scene_is_grey, METH_NOARGS, "whether the image is grey"},
    {"_facts", (PyCFunction)scene_facts, METH_NOARGS, "(name, triangles, spheres, width, height)"},
    {NULL, NULL, 0, NULL},
};

PyTypeObject ao_scene_type = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "aoview._core.Scene",
    .tp_basicsize = sizeof(SceneObject),
    .tp_dealloc = (destructor)scene_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_BASETYPE,
    .tp_doc = "A loaded scene (the core's struct ao_scene) and its tracer.",
    .tp_methods = scene_methods,
    .tp_new = PyType_GenericNew,
};

struct ao_tracer *ao_scene_type_tracer(SceneObject *self)
{
    if (self->tracer)
        return self->tracer;
    struct ao_messages messages;
    struct ao_tracer *t;
    ao_messages_begin(&messages);
    Py_BEGIN_ALLOW_THREADS
    t = ao_tracer_create(&self->scene);
    Py_END_ALLOW_THREADS
    if (!ao_messages_close(&messages, t != NULL, PyExc_MemoryError, "aoview: the tracer could not be built")) {
        ao_tracer_destroy(t);
        return NULL;
    }
    if (self->tracer) /* another thread built one meanwhile (the GIL was released) */
        ao_tracer_destroy(t);
    else
        self->tracer = t;
    return self->tracer;
}

PyObject *ao_scene_type_load(PyObject *module, PyObject *args)
{
    (void)module;
    SceneObject *self;
    const char *path;
    PyObject *list, *keep;
    if (!PyArg_ParseTuple(args, "O!sO", &ao_scene_type, &self, &path, &list))
        return NULL;
    struct ao_options opts;
    if (!ao_arguments_parse_argv(list, &opts, &keep))
        return NULL;
    struct ao_scene_options load = ao_options_scene(&opts);
    struct ao_messages messages;
    bool ok;
    ao_messages_begin(&messages);
    Py_BEGIN_ALLOW_THREADS
    ok = ao_scene_load(&self->scene, path, &load);
    if (ok)
        ao_scene_say_notes(&self->scene);
    Py_END_ALLOW_THREADS
    self->loaded = ok;
    ok = ao_messages_close(&messages, ok, PyExc_ValueError, "aoview: the scene could not be loaded");
    Py_DECREF(keep);
    if (!ok)
        return NULL;
    Py_RETURN_NONE;
}

PyObject *ao_scene_type_from_arrays(PyObject *module, PyObject *args)
{
    (void)module;
    SceneObject *self;
    const char *name;
    PyObject *pos, *idx, *nrm, *sph, *cam, *list, *keep;
    Py_ssize_t n, m, k;
    float albedo[3];
    if (!PyArg_ParseTuple(args, "O!sOnOnO(fff)OnOO", &ao_scene_type, &self, &name, &pos, &n, &idx, &m, &nrm, &albedo[0],
                          &albedo[1], &albedo[2], &sph, &k, &cam, &list))
        return NULL;
    struct ao_options opts;
    if (!ao_arguments_parse_argv(list, &opts, &keep))
        return NULL;
    Py_buffer b[5] = {{0}};   /* positions, indices, normals, spheres, camera */
    bool ok = ao_arguments_get_buffer(pos, &b[0], 3 * sizeof(float), (size_t)n, false, "vertices") &&
              ao_arguments_get_buffer(idx, &b[1], 3 * sizeof(uint32_t), (size_t)m, false, "faces") &&
              (nrm == Py_None || ao_arguments_get_buffer(nrm, &b[2], 3 * sizeof(float), (size_t)n, false, "normals")) &&
              ao_arguments_get_buffer(sph, &b[3], 7 * sizeof(float), (size_t)k, false, "spheres") &&
              (cam == Py_None || ao_arguments_get_buffer(cam, &b[4], sizeof(float), 10, false, "camera"));
    struct ao_sphere *spheres = ok ? PyMem_Calloc((size_t)k + 1, sizeof *spheres) : NULL;
    if (ok && !spheres) {
        PyErr_NoMemory();
        ok = false;
    }
    if (ok) {
        const float *s = b[3].buf;
        for (Py_ssize_t i = 0; i < k; i++, s += 7)
            spheres[i] = (struct ao_sphere){{s[0], s[1], s[2]}, s[3], {s[4], s[5], s[6]}};
        struct ao_camera camera;
        if (cam != Py_None) {
            const float *f = b[4].buf;
            camera = (struct ao_camera){{f[0], f[1], f[2]}, {f[3], f[4], f[5]}, {f[6], f[7], f[8]}, f[9]};
        }
        struct ao_scene_arrays arrays = {.name = name, .positions = b[0].buf, .vertex_count = (size_t)n,
                                         .indices = b[1].buf, .triangle_count = (size_t)m,
                                         .normals = nrm == Py_None ? NULL : b[2].buf,
                                         .albedo = {albedo[0], albedo[1], albedo[2]}, .spheres = spheres,
                                         .sphere_count = (size_t)k, .camera = cam == Py_None ? NULL : &camera};
        struct ao_scene_options load = ao_options_scene(&opts);
        struct ao_messages messages;
        ao_messages_begin(&messages);
        Py_BEGIN_ALLOW_THREADS
        ok = ao_scene_from_arrays(&self->scene, &arrays, &load);
        if (ok)
            ao_scene_say_notes(&self->scene);
        Py_END_ALLOW_THREADS
        self->loaded = ok;
        ok = ao_messages_close(&messages, ok, PyExc_ValueError, "aoview: the scene could not be made");
    }
    PyMem_Free(spheres);
    for (int i = 0; i < 5; i++)
        if (b[i].obj)
            PyBuffer_Release(&b[i]);
    Py_DECREF(keep);
    if (!ok)
        return NULL;
    Py_RETURN_NONE;
}

PyObject *ao_scene_type_exact(PyObject *module, PyObject *args)
{
    (void)module;
    SceneObject *scene;
    PyObject *list, *out, *keep;
    if (!PyArg_ParseTuple(args, "O!OO", &ao_scene_type, &scene, &list, &out))
        return NULL;
    struct ao_options opts;
    if (!ao_arguments_parse_argv(list, &opts, &keep))
        return NULL;
    int w, h;
    ao_options_size(&opts, &scene->scene, &w, &h);
    Py_buffer view;
    struct ao_tracer *tracer = ao_scene_type_tracer(scene);
    if (!tracer || !ao_arguments_get_buffer(out, &view, 3 * sizeof(float), (size_t)w * (size_t)h, true, "image")) {
        Py_DECREF(keep);
        return NULL;
    }
    int grid = opts.aa ? (int)lround(sqrt((double)opts.spp)) : 0;
    float ao_distance = isnan(opts.ao_distance) ? scene->scene.ao_distance : opts.ao_distance;
    struct ao_exact_facts facts;
    char why[256];
    bool ok;
    struct ao_messages messages;
    ao_messages_begin(&messages);
    Py_BEGIN_ALLOW_THREADS
#if defined(__SSE__)
    unsigned modes = _mm_getcsr();   /* aoview-exact's modes while it traces, then the caller's */
#endif
    ao_tracer_thread_init();
    ok = ao_exact_render(&scene->scene, tracer, ao_distance, w, h, grid, view.buf, &facts, why, sizeof why);
#if defined(__SSE__)
    _mm_setcsr(modes);
#endif
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&view);
    Py_DECREF(keep);
    char reason[sizeof why + sizeof scene->scene.name + 2];
    snprintf(reason, sizeof reason, "%s: %s", scene->scene.name, why);
    if (!ao_messages_close(&messages, ok, PyExc_ValueError, reason))
        return NULL;
    return Py_BuildValue("s", facts.kind);
}
