/* aoview's Python module, its window (aoview._window): view() opens aoview's GLFW window on a scene
 * with the command line's settings and keys, through the GL library; built only with the front
 * ends, and imported only by view(), so that `import aoview` loads no GL. Its own copy of the core
 * sends the window's messages to the call's sink (messages.h): errors into the exception, notes to
 * Python's warnings. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "messages.h"
#include "options.h"
#include "render.h"
#include "scene_object.h"
#include "tracer.h"
#include "window.h"

/* The renderer's on_pass and on_preview: wake the window. */
static void wake(const struct ao_frame_info *info, void *user)
{
    (void)info, (void)user;
    ao_window_notify();
}

/* view(scene, argv): the window on the scene until the user closes it (Esc or Q); RuntimeError
 * where no window can be opened or OpenGL fails, ValueError for argv, as the command line. */
static PyObject *window_view(PyObject *module, PyObject *args)
{
    (void)module;
    PyObject *scene_obj, *list;
    if (!PyArg_ParseTuple(args, "OO!", &scene_obj, &PyList_Type, &list))
        return NULL;
    SceneObject *scene = (SceneObject *)scene_obj;   /* the caller (__init__.py) passes a _core.Scene */
    Py_ssize_t argc = PyList_Size(list);
    char **argv = PyMem_Calloc((size_t)argc + 1, sizeof *argv);
    if (!argv)
        return PyErr_NoMemory();
    for (Py_ssize_t i = 0; i < argc; i++)
        if (!(argv[i] = (char *)PyUnicode_AsUTF8(PyList_GetItem(list, i)))) {
            PyMem_Free(argv);
            return NULL;
        }
    struct ao_options opts;
    char message[512];
    bool ok = ao_cli_parse((int)argc, argv, &opts, message, sizeof message);
    if (!ok) {
        PyMem_Free(argv);
        PyErr_SetString(PyExc_ValueError, message);
        return NULL;
    }
    struct ao_render_config config;
    struct ao_settings settings;
    struct ao_tracer *tracer = NULL;
    struct ao_render *render = NULL;
    enum ao_window_result result = AO_WINDOW_FAILED;
    struct ao_messages messages;
    ao_messages_begin(&messages);
    Py_BEGIN_ALLOW_THREADS
    tracer = ao_tracer_create(&scene->scene);
    if (tracer && ao_options_render(&opts, &scene->scene, tracer, &config, &settings)) {
        config.on_pass = wake;
        config.on_preview = wake;
        settings.paused = true;   /* until the window is up: it opens on free cores (resume below) */
        render = ao_render_create(&config, &settings);
    }
    if (render) {
        struct ao_window_info info = {.scene_name = scene->scene.name, .quiet = opts.quiet, .seed = opts.seed,
                                      .pixel_size = opts.pixel_size, .config = &config, .resume = true,
                                      .sides = {opts.sides[0], opts.sides[1]}};
        result = ao_window_run(render, &info);
    }
    ao_render_destroy(render);
    ao_tracer_destroy(tracer);
    Py_END_ALLOW_THREADS
    PyMem_Free(argv);
    if (!ao_messages_close(&messages, result == AO_WINDOW_OK, PyExc_RuntimeError,
                           !render                         ? "aoview: the render could not start"
                           : result == AO_WINDOW_NO_DISPLAY ? "aoview: no display to open a window on"
                                                            : "aoview: OpenGL failed in the window"))
        return NULL;
    Py_RETURN_NONE;
}

static PyMethodDef window_methods[] = {
    {"view", window_view, METH_VARARGS, "view(scene, argv): the window until closed"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef window_module = {PyModuleDef_HEAD_INIT, "aoview._window",
                                           "aoview's window (see aoview.view).", -1, window_methods, NULL, NULL,
                                           NULL, NULL};

PyMODINIT_FUNC PyInit__window(void)
{
    return PyModule_Create(&window_module);
}
