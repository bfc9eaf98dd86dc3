/* The checks every function of _core makes of its arguments; see arguments.h. */
#define PY_SSIZE_T_CLEAN
#include "arguments.h"

#include "cli.h"

bool ao_arguments_parse_argv(PyObject *list, struct ao_options *opts, PyObject **keep)
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

bool ao_arguments_get_buffer(PyObject *obj, Py_buffer *view, size_t size, size_t count, bool writable,
                             const char *what)
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
