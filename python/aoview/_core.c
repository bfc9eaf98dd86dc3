/* aoview's Python module, its C half (aoview._core): the core library's scene loading, renderer,
 * exact images and ray batches behind a few functions that take contiguous buffers, which the
 * Python half (__init__.py) checks and converts. Options come as the command line's argv and go
 * through its own parser (cli.h), so that every default, range and message is aoview's. The GIL is
 * released while anything traces; a render waits in slices of SIGNAL_POLL seconds, checking for
 * Ctrl-C between them. The core's messages come to each call's own sink (messages.h): its errors
 * become its exception, its notes Python warnings. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "cli.h"
#include "config.h"
#include "exact_image.h"
#include "file.h"
#include "image.h"
#include "messages.h"
#include "options.h"
#include "progress.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "scene_object.h"
#include "tracer.h"
#include "tracer_arrays.h"

/* Seconds between two checks for a pending signal while a render is waited for. */
static const double SIGNAL_POLL = 0.02;

/* ------------------------------------------------------------------ options and buffers */

/* Parses argv (a list of str, argv[0] first) as aoview's command line; false with ValueError set to
 * the CLI's message. The strings must live as long as opts is used: *keep holds them. */
static bool parse_options(PyObject *list, struct ao_options *opts, PyObject **keep)
{
    if (!PyList_Check(list)) {
        PyErr_SetString(PyExc_TypeError, "argv must be a list");
        return false;
    }
    Py_ssize_t argc = PyList_Size(list);
    char **argv = PyMem_Calloc((size_t)argc + 1, sizeof *argv);
    if (!argv) {
        PyErr_NoMemory();
        return false;
    }
    for (Py_ssize_t i = 0; i < argc; i++) {
        const char *s = PyUnicode_AsUTF8(PyList_GetItem(list, i));
        if (!s) {
            PyMem_Free(argv);
            return false;
        }
        argv[i] = (char *)s;
    }
    char message[512];
    bool ok = ao_cli_parse((int)argc, argv, opts, message, sizeof message);
    PyMem_Free(argv);
    if (!ok) {
        PyErr_SetString(PyExc_ValueError, message);
        return false;
    }
    Py_INCREF(list);
    *keep = list;
    return true;
}

/* A contiguous buffer of `count` items of `size` bytes (writable when asked); false with ValueError. */
static bool get_buffer(PyObject *obj, Py_buffer *view, size_t size, size_t count, bool writable, const char *what)
{
    if (PyObject_GetBuffer(obj, view, PyBUF_C_CONTIGUOUS | (writable ? PyBUF_WRITABLE : 0)) < 0)
        return false;
    if ((size_t)view->len != size * count) {
        PyBuffer_Release(view);
        PyErr_Format(PyExc_ValueError, "%s: %zu bytes expected, got %zd", what, size * count, view->len);
        return false;
    }
    return true;
}

/* ------------------------------------------------------------------ Scene */


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

static PyTypeObject SceneType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "aoview._core.Scene",
    .tp_basicsize = sizeof(SceneObject),
    .tp_dealloc = (destructor)scene_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_BASETYPE,
    .tp_doc = "A loaded scene (the core's struct ao_scene) and its tracer.",
    .tp_methods = scene_methods,
    .tp_new = PyType_GenericNew,
};

/* The scene's tracer, built on first use (GIL released meanwhile); NULL with MemoryError (the core's
 * message) when it cannot be built. */
static struct ao_tracer *scene_tracer(SceneObject *self)
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

/* load(scene: Scene, path: str, argv: list): ao_scene_load with argv's scene options. */
static PyObject *core_load(PyObject *module, PyObject *args)
{
    (void)module;
    SceneObject *self;
    const char *path;
    PyObject *list, *keep;
    if (!PyArg_ParseTuple(args, "O!sO", &SceneType, &self, &path, &list))
        return NULL;
    struct ao_options opts;
    if (!parse_options(list, &opts, &keep))
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

/* from_arrays(scene, name, positions float32 (n,3), indices uint32 (m,3), normals or None,
 * albedo (r, g, b), spheres float32 (k,7) [cx cy cz r ar ag ab], camera float32 (10,) or None, argv). */
static PyObject *core_from_arrays(PyObject *module, PyObject *args)
{
    (void)module;
    SceneObject *self;
    const char *name;
    PyObject *pos, *idx, *nrm, *sph, *cam, *list, *keep;
    Py_ssize_t n, m, k;
    float albedo[3];
    if (!PyArg_ParseTuple(args, "O!sOnOnO(fff)OnOO", &SceneType, &self, &name, &pos, &n, &idx, &m, &nrm, &albedo[0],
                          &albedo[1], &albedo[2], &sph, &k, &cam, &list))
        return NULL;
    struct ao_options opts;
    if (!parse_options(list, &opts, &keep))
        return NULL;
    Py_buffer b[5] = {{0}};   /* positions, indices, normals, spheres, camera */
    bool ok = get_buffer(pos, &b[0], 3 * sizeof(float), (size_t)n, false, "vertices") &&
              get_buffer(idx, &b[1], 3 * sizeof(uint32_t), (size_t)m, false, "faces") &&
              (nrm == Py_None || get_buffer(nrm, &b[2], 3 * sizeof(float), (size_t)n, false, "normals")) &&
              get_buffer(sph, &b[3], 7 * sizeof(float), (size_t)k, false, "spheres") &&
              (cam == Py_None || get_buffer(cam, &b[4], sizeof(float), 10, false, "camera"));
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

/* ------------------------------------------------------------------ Run: a render in progress */

typedef struct {
    PyObject_HEAD
    SceneObject *scene;         /* kept alive while the renderer reads it */
    PyObject *argv;             /* the strings opts points into */
    struct ao_options opts;
    struct ao_render_config config;
    struct ao_settings settings;
    float *reference;
    struct ao_render *render;
    pthread_mutex_t lock;
    pthread_cond_t changed;
    struct ao_frame_info info; /* the newest pass's */
    uint64_t published, seen;  /* passes published by the render thread, and taken by step */
    bool every_pass;           /* the render thread waits in on_pass until step has taken the pass */
    bool closing;              /* no waiting in on_pass any more */
    bool finished;             /* the last pass was taken */
    struct ao_messages messages;   /* the render thread's route, kept while it runs */
    bool messages_live;            /* begun and not finished */
    struct ao_progress progress;   /* how far the run is, from the passes step returned (progress.h) */
} RunObject;

/* The renderer's on_pass (render thread): records the pass, wakes step and, when every pass is
 * wanted, waits until step has taken it (the frame stays the newest meanwhile). */
static void run_on_pass(const struct ao_frame_info *info, void *user)
{
    RunObject *r = user;
    pthread_mutex_lock(&r->lock);
    r->info = *info;
    r->published++;
    pthread_cond_broadcast(&r->changed);
    while (r->every_pass && r->seen < r->published && !r->closing)
        pthread_cond_wait(&r->changed, &r->lock);
    pthread_mutex_unlock(&r->lock);
}

/* Stops and frees the renderer (GIL released: joining waits for the tile in flight). */
static void run_close(RunObject *r)
{
    if (!r->render)
        return;
    pthread_mutex_lock(&r->lock);
    r->closing = true;
    pthread_cond_broadcast(&r->changed);
    pthread_mutex_unlock(&r->lock);
    struct ao_render *render = r->render;
    r->render = NULL;
    Py_BEGIN_ALLOW_THREADS
    ao_render_stop(render);
    ao_render_destroy(render);
    Py_END_ALLOW_THREADS
}

static void run_dealloc(RunObject *self)
{
    run_close(self);
    if (self->messages_live)
        ao_messages_finish(&self->messages);
    pthread_cond_destroy(&self->changed);
    pthread_mutex_destroy(&self->lock);
    free(self->reference);
    Py_XDECREF(self->scene);
    Py_XDECREF(self->argv);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *run_close_method(RunObject *self, PyObject *unused)
{
    (void)unused;
    run_close(self);
    Py_RETURN_NONE;
}

/* The facts of a pass as a dict. */
static PyObject *info_dict(const struct ao_frame_info *i, struct ao_progress *progress)
{
    /* How far the run is, as the window's title and the headless line say it (progress.h). */
    ao_progress_add(progress, i);
    char samples[64];
    ao_progress_format_spp(i, samples, sizeof samples);
    return Py_BuildValue("{s:I,s:I,s:I,s:I,s:d,s:d,s:d,s:K,s:K,s:d,s:d,s:d,s:O,s:s,s:d,s:d}", "pass", i->pass, "spp",
                         i->spp, "target_spp", i->target_spp, "spppp", i->spppp, "mean_spp", i->mean_spp, "seconds",
                         i->seconds, "error", i->error, "eye_rays", (unsigned long long)i->eye_rays, "shadow_rays",
                         (unsigned long long)i->shadow_rays, "rmse", i->rmse, "converged", i->converged,
                         "mrays_per_s", i->seconds > 0 ? (double)(i->eye_rays + i->shadow_rays) / i->seconds * 1e-6 : NAN,
                         "done", i->done ? Py_True : Py_False, "samples", samples, "progress",
                         ao_progress_share(progress, i), "seconds_left", ao_progress_left(progress, i));
}

/* step(out, always): waits for the next pass (checking for signals every SIGNAL_POLL seconds, the
 * GIL released), copies its image (width x height x 3 floats, top row first) into out when always
 * or when it is the last, and returns its facts; None after the last. KeyboardInterrupt (or what a
 * signal handler raised) stops the render. */
static PyObject *run_step(RunObject *self, PyObject *args)
{
    PyObject *out;
    int always;
    if (!PyArg_ParseTuple(args, "Op", &out, &always))
        return NULL;
    if (self->finished || !self->render)
        Py_RETURN_NONE;
    size_t floats = 3 * (size_t)self->settings.width * (size_t)self->settings.height;
    Py_buffer view;
    if (!get_buffer(out, &view, sizeof(float), floats, true, "image"))
        return NULL;
    struct ao_frame_info info;
    for (;;) {
        bool got;
        Py_BEGIN_ALLOW_THREADS
        pthread_mutex_lock(&self->lock);
        if (self->seen == self->published) {
            struct timespec until;
            clock_gettime(CLOCK_REALTIME, &until);
            long ns = until.tv_nsec + (long)(SIGNAL_POLL * 1e9);
            until.tv_sec += ns / 1000000000L;
            until.tv_nsec = ns % 1000000000L;
            pthread_cond_timedwait(&self->changed, &self->lock, &until);
        }
        got = self->seen < self->published;
        info = self->info;
        pthread_mutex_unlock(&self->lock);
        Py_END_ALLOW_THREADS
        if (got)
            break;
        if (PyErr_CheckSignals() < 0) {
            PyBuffer_Release(&view);
            run_close(self);
            return NULL;
        }
    }
    if (always || info.done) {
        const struct ao_frame *frame = ao_render_take_frame(self->render);
        if (frame) /* this pass's: the render thread waits (every pass) or has finished (the last) */
            memcpy(view.buf, frame->rgb, floats * sizeof(float));
    }
    PyBuffer_Release(&view);
    pthread_mutex_lock(&self->lock);
    self->seen = self->published;
    self->finished = info.done;
    pthread_cond_broadcast(&self->changed);
    pthread_mutex_unlock(&self->lock);
    if (info.done)
        run_close(self);
    if (!ao_messages_warn(&self->messages, true)) {
        run_close(self);
        return NULL;
    }
    return info_dict(&info, &self->progress);
}

/* (width, height) of the images step writes. */
static PyObject *run_size(RunObject *self, PyObject *unused)
{
    (void)unused;
    return Py_BuildValue("(ii)", self->settings.width, self->settings.height);
}

static PyMethodDef run_methods[] = {
    {"step", (PyCFunction)run_step, METH_VARARGS, "the next pass's facts (image into out), None after the last"},
    {"close", (PyCFunction)run_close_method, METH_NOARGS, "stops the render"},
    {"size", (PyCFunction)run_size, METH_NOARGS, "(width, height)"},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject RunType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "aoview._core.Run",
    .tp_basicsize = sizeof(RunObject),
    .tp_dealloc = (destructor)run_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "A render in progress (the core's renderer).",
    .tp_methods = run_methods,
};

/* start(scene, argv, reference, every_pass) -> Run: the renderer started with argv's settings;
 * reference: None, a path (str), or a float32 buffer of the image's width x height x 3. */
static PyObject *core_start(PyObject *module, PyObject *args)
{
    (void)module;
    SceneObject *scene;
    PyObject *list, *reference;
    int every_pass;
    if (!PyArg_ParseTuple(args, "O!OOp", &SceneType, &scene, &list, &reference, &every_pass))
        return NULL;
    if (!scene->loaded) {
        PyErr_SetString(PyExc_ValueError, "the scene was not loaded");
        return NULL;
    }
    RunObject *r = PyObject_New(RunObject, &RunType);
    if (!r)
        return NULL;
    memset((char *)r + sizeof(PyObject), 0, sizeof *r - sizeof(PyObject));
    pthread_mutex_init(&r->lock, NULL);
    pthread_cond_init(&r->changed, NULL);
    Py_INCREF(scene);
    r->scene = scene;
    r->every_pass = every_pass;
    struct ao_tracer *tracer;
    if (!parse_options(list, &r->opts, &r->argv) || !(tracer = scene_tracer(scene))) {
        Py_DECREF(r);
        return NULL;
    }
    ao_messages_begin(&r->messages);   /* the render thread keeps this route */
    r->messages_live = true;
    bool ok = ao_options_render(&r->opts, &scene->scene, tracer, &r->config, &r->settings);
    int w = r->settings.width, h = r->settings.height;
    if (ok && PyUnicode_Check(reference)) {
        const char *path = PyUnicode_AsUTF8(reference);
        ok = path && ao_image_read_linear_sized(path, w, h, &r->reference);
    } else if (ok && reference != Py_None) {
        Py_buffer view;
        if (!get_buffer(reference, &view, 3 * sizeof(float), (size_t)w * (size_t)h, false, "reference")) {
            ao_messages_end(&r->messages);
            Py_DECREF(r);
            return NULL;
        }
        r->reference = malloc((size_t)view.len);
        if (r->reference)
            memcpy(r->reference, view.buf, (size_t)view.len);
        PyBuffer_Release(&view);
        if (!r->reference) {
            ao_messages_end(&r->messages);
            Py_DECREF(r);
            return PyErr_NoMemory();
        }
    }
    if (ok) {
        r->config.reference = r->reference;
        r->config.reference_width = w;
        r->config.reference_height = h;
        r->config.on_pass = run_on_pass;
        r->config.user = r;
        ok = (r->render = ao_render_create(&r->config, &r->settings)) != NULL;
    }
    if (!ok) {
        r->messages_live = false;
        ao_messages_close(&r->messages, false, PyExc_ValueError, "aoview: the render could not start");
        Py_DECREF(r);
        return NULL;
    }
    ao_messages_end(&r->messages);
    if (!ao_messages_warn(&r->messages, false)) {
        Py_DECREF(r);
        return NULL;
    }
    return (PyObject *)r;
}

/* ------------------------------------------------------------------ exact images, ray batches */

/* exact(scene, argv, out): the exact image (width x height x 3 floats) as aoview-exact makes it. */
static PyObject *core_exact(PyObject *module, PyObject *args)
{
    (void)module;
    SceneObject *scene;
    PyObject *list, *out, *keep;
    if (!PyArg_ParseTuple(args, "O!OO", &SceneType, &scene, &list, &out))
        return NULL;
    struct ao_options opts;
    if (!parse_options(list, &opts, &keep))
        return NULL;
    int w, h;
    ao_options_size(&opts, &scene->scene, &w, &h);
    Py_buffer view;
    struct ao_tracer *tracer = scene_tracer(scene);
    if (!tracer || !get_buffer(out, &view, 3 * sizeof(float), (size_t)w * (size_t)h, true, "image")) {
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

/* ------------------------------------------------------------------ Mesh: a BVH for ray batches */

typedef struct {
    PyObject_HEAD
    struct ao_tracer_arrays *mesh;
} MeshObject;

static void mesh_dealloc(MeshObject *self)
{
    ao_tracer_arrays_destroy(self->mesh);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

/* intersect(origins float32 (k,3), directions float32 (k,3), k, tnear, threads, t float64 (k,),
 * ids int32 (k,), barys float64 (k,3)): the closest hits, written into the last three. */
static PyObject *mesh_intersect(MeshObject *self, PyObject *args)
{
    PyObject *o[5];
    Py_ssize_t k;
    float tnear;
    int threads;
    if (!PyArg_ParseTuple(args, "OOnfiOOO", &o[0], &o[1], &k, &tnear, &threads, &o[2], &o[3], &o[4]))
        return NULL;
    static const char *const names[5] = {"origins", "directions", "hit_distances", "triangle_hit_ids", "barys"};
    const size_t sizes[5] = {12, 12, 8, 4, 24};
    Py_buffer b[5];
    int got = 0;
    for (; got < 5; got++)
        if (!get_buffer(o[got], &b[got], sizes[got], (size_t)k, got >= 2, names[got]))
            break;
    bool ok = got == 5;
    if (ok) {
        struct ao_messages messages;
        ao_messages_begin(&messages);
        Py_BEGIN_ALLOW_THREADS
        ok = ao_tracer_intersect_arrays(self->mesh, b[0].buf, b[1].buf, (size_t)k, tnear, threads, b[2].buf,
                                        b[3].buf, b[4].buf);
        Py_END_ALLOW_THREADS
        ok = ao_messages_close(&messages, ok, PyExc_MemoryError, "aoview: the rays could not be traced");
    }
    for (int i = 0; i < got; i++)
        PyBuffer_Release(&b[i]);
    if (!ok)
        return NULL;
    Py_RETURN_NONE;
}

static PyMethodDef mesh_methods[] = {
    {"intersect", (PyCFunction)mesh_intersect, METH_VARARGS, "the closest hits of a batch of rays"},
    {NULL, NULL, 0, NULL},
};

/* Mesh(positions float32 (n,3), n, indices uint32 (m,3), m): the mesh's BVH, built with the GIL
 * released (the arrays are copied). */
static PyObject *mesh_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    PyObject *o[2];
    Py_ssize_t n, m;
    if (kwds && PyDict_Size(kwds) > 0) {
        PyErr_SetString(PyExc_TypeError, "Mesh() takes no keyword arguments");
        return NULL;
    }
    if (!PyArg_ParseTuple(args, "OnOn", &o[0], &n, &o[1], &m))
        return NULL;
    Py_buffer b[2];
    if (!get_buffer(o[0], &b[0], 12, (size_t)n, false, "vertices"))
        return NULL;
    if (!get_buffer(o[1], &b[1], 12, (size_t)m, false, "faces")) {
        PyBuffer_Release(&b[0]);
        return NULL;
    }
    MeshObject *self = (MeshObject *)type->tp_alloc(type, 0);
    bool ok = false;
    if (self) {
        struct ao_messages messages;
        ao_messages_begin(&messages);
        Py_BEGIN_ALLOW_THREADS
        self->mesh = ao_tracer_arrays_create(b[0].buf, (size_t)n, b[1].buf, (size_t)m);
        Py_END_ALLOW_THREADS
        ok = ao_messages_close(&messages, self->mesh != NULL, PyExc_MemoryError, "aoview: the mesh could not be built");
    }
    PyBuffer_Release(&b[0]);
    PyBuffer_Release(&b[1]);
    if (!ok) {
        Py_XDECREF(self);
        return NULL;
    }
    return (PyObject *)self;
}

static PyTypeObject MeshType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "aoview._core.Mesh",
    .tp_basicsize = sizeof(MeshObject),
    .tp_dealloc = (destructor)mesh_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "A triangle mesh's Embree BVH, for batches of rays.",
    .tp_methods = mesh_methods,
    .tp_new = mesh_new,
};

/* parse(argv): checks argv as aoview's command line; ValueError with its message. */
static PyObject *core_parse(PyObject *module, PyObject *list)
{
    (void)module;
    struct ao_options opts;
    PyObject *keep;
    if (!parse_options(list, &opts, &keep))
        return NULL;
    Py_DECREF(keep);
    return PyLong_FromLong(opts.threads);
}

/* cores(): what --threads defaults to. */
static PyObject *core_cores(PyObject *module, PyObject *unused)
{
    (void)module, (void)unused;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    return PyLong_FromLong(cores > 0 ? cores : 1);
}

static PyMethodDef core_methods[] = {
    {"load", core_load, METH_VARARGS, "load(scene, path, argv)"},
    {"from_arrays", core_from_arrays, METH_VARARGS, "from_arrays(scene, name, ...)"},
    {"start", core_start, METH_VARARGS, "start(scene, argv, reference, every_pass) -> Run"},
    {"exact", core_exact, METH_VARARGS, "exact(scene, argv, out) -> kind"},
    {"parse", core_parse, METH_O, "parse(argv) -> --threads (0: the default)"},
    {"cores", core_cores, METH_NOARGS, "the number of cores"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef core_module = {PyModuleDef_HEAD_INIT, "aoview._core",
                                         "aoview's core library (see the aoview package).", -1, core_methods,
                                         NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__core(void)
{
    if (PyType_Ready(&SceneType) < 0 || PyType_Ready(&RunType) < 0 || PyType_Ready(&MeshType) < 0)
        return NULL;
    /* The interpreter cannot end on a SIGBUS: the core reads files rather than map them, so that a
     * file shrunk under a load is that load's error. */
    ao_file_set_mapping(false);
    PyObject *m = PyModule_Create(&core_module);
    if (!m)
        return NULL;
    Py_INCREF(&SceneType);
    Py_INCREF(&MeshType);
    if (PyModule_AddObject(m, "Scene", (PyObject *)&SceneType) < 0 ||
        PyModule_AddObject(m, "Mesh", (PyObject *)&MeshType) < 0 ||
        PyModule_AddObject(m, "ARRAYS_LIMIT", PyFloat_FromDouble(AO_TRACER_ARRAYS_LIMIT)) < 0 ||
        PyModule_AddObject(m, "MIN_EXTENT", PyFloat_FromDouble(AO_SCENE_MIN_EXTENT)) < 0 ||
        PyModule_AddObject(m, "MAX_EXTENT", PyFloat_FromDouble(AO_SCENE_MAX_EXTENT)) < 0 ||
        PyModule_AddStringConstant(m, "__version__", AO_VERSION) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
