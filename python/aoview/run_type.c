/* _core's render in progress (aoview._core.Run): the core's renderer started on a scene, stepped
 * pass by pass by the Python half; see run_type.h. */
#define PY_SSIZE_T_CLEAN
#include "run_type.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "arguments.h"
#include "image.h"
#include "messages.h"
#include "options.h"
#include "progress.h"
#include "render.h"
#include "scene_object.h"
#include "scene_type.h"


/* Seconds between two checks for a pending signal while a render is waited for. */
static const double SIGNAL_POLL = 0.02;

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
    if (!ao_arguments_get_buffer(out, &view, sizeof(float), floats, true, "image"))
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

PyTypeObject ao_run_type = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "aoview._core.Run",
    .tp_basicsize = sizeof(RunObject),
    .tp_dealloc = (destructor)run_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "A render in progress (the core's renderer).",
    .tp_methods = run_methods,
};

PyObject *ao_run_type_start(PyObject *module, PyObject *args)
{
    (void)module;
    SceneObject *scene;
    PyObject *list, *reference;
    int every_pass;
    if (!PyArg_ParseTuple(args, "O!OOp", &ao_scene_type, &scene, &list, &reference, &every_pass))
        return NULL;
    if (!scene->loaded) {
        PyErr_SetString(PyExc_ValueError, "the scene was not loaded");
        return NULL;
    }
    RunObject *r = PyObject_New(RunObject, &ao_run_type);
    if (!r)
        return NULL;
    memset((char *)r + sizeof(PyObject), 0, sizeof *r - sizeof(PyObject));
    pthread_mutex_init(&r->lock, NULL);
    pthread_cond_init(&r->changed, NULL);
    Py_INCREF(scene);
    r->scene = scene;
    r->every_pass = every_pass;
    struct ao_tracer *tracer;
    if (!ao_arguments_parse_argv(list, &r->opts, &r->argv) || !(tracer = ao_scene_type_tracer(scene))) {
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
        if (!ao_arguments_get_buffer(reference, &view, 3 * sizeof(float), (size_t)w * (size_t)h, false, "reference")) {
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
