/* aoview's Python module, its C half (aoview._core): the core library's scene loading, renderer,
 * exact images and ray batches behind a few functions that take contiguous buffers, which the
 * Python half (__init__.py) checks and converts. Options come as the command line's argv and go
 * through its own parser (cli.h), so that every default, range and message is aoview's. The GIL is
 * released while anything traces; a render waits in slices of SIGNAL_POLL seconds, checking for
 * Ctrl-C between them. The core's messages come to each call's own sink (messages.h): its errors
 * become its exception, its notes Python warnings. This file is the module itself (its table, its
 * init, and parse() and cores()); the Scene type and the functions that fill it are scene_type.c's,
 * a render in progress run_type.c's, the ray batches rays.c's, the argument checks arguments.c's. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <unistd.h>

#include "arguments.h"
#include "config.h"
#include "file.h"
#include "options.h"
#include "rays.h"
#include "run_type.h"
#include "scene.h"
#include "scene_type.h"
#include "tracer_arrays.h"

/* parse(argv): checks argv as aoview's command line; ValueError with its message. */
static PyObject *core_parse(PyObject *module, PyObject *list)
{
    (void)module;
    struct ao_options opts;
    PyObject *keep;
    if (!ao_arguments_parse_argv(list, &opts, &keep))
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
    {"load", ao_scene_type_load, METH_VARARGS, "load(scene, path, argv)"},
    {"from_arrays", ao_scene_type_from_arrays, METH_VARARGS, "from_arrays(scene, name, ...)"},
    {"start", ao_run_type_start, METH_VARARGS, "start(scene, argv, reference, every_pass) -> Run"},
    {"exact", ao_scene_type_exact, METH_VARARGS, "exact(scene, argv, out) -> kind"},
    {"parse", core_parse, METH_O, "parse(argv) -> --threads (0: the default)"},
    {"cores", core_cores, METH_NOARGS, "the number of cores"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef core_module = {PyModuleDef_HEAD_INIT, "aoview._core",
                                         "aoview's core library (see the aoview package).", -1, core_methods,
                                         NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__core(void)
{
    if (PyType_Ready(&ao_scene_type) < 0 || PyType_Ready(&ao_run_type) < 0 || PyType_Ready(&ao_rays_mesh_type) < 0)
        return NULL;
    /* The interpreter cannot end on a SIGBUS: the core reads files rather than map them, so that a
     * file shrunk under a load is that load's error. */
    ao_file_set_mapping(false);
    PyObject *m = PyModule_Create(&core_module);
    if (!m)
        return NULL;
    Py_INCREF(&ao_scene_type);
    Py_INCREF(&ao_rays_mesh_type);
    if (PyModule_AddObject(m, "Scene", (PyObject *)&ao_scene_type) < 0 ||
        PyModule_AddObject(m, "Mesh", (PyObject *)&ao_rays_mesh_type) < 0 ||
        PyModule_AddObject(m, "ARRAYS_LIMIT", PyFloat_FromDouble(AO_TRACER_ARRAYS_LIMIT)) < 0 ||
        PyModule_AddObject(m, "MIN_EXTENT", PyFloat_FromDouble(AO_SCENE_MIN_EXTENT)) < 0 ||
        PyModule_AddObject(m, "MAX_EXTENT", PyFloat_FromDouble(AO_SCENE_MAX_EXTENT)) < 0 ||
        PyModule_AddStringConstant(m, "__version__", AO_VERSION) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
