/* The checks every function of _core makes of its arguments: the command line it is given as a list
 * (argv) and the contiguous buffers it reads or writes. Each fails with a Python exception set. The
 * GIL held. */
#ifndef AO_PYTHON_ARGUMENTS_H
#define AO_PYTHON_ARGUMENTS_H

#include <Python.h>

#include <stdbool.h>
#include <stddef.h>

#include "options.h"

/* Parses argv (a list of str, argv[0] first) as aoview's command line; false with ValueError set to
 * the CLI's message. The strings must live as long as opts is used: *keep holds them (the caller's
 * reference, to drop). */
bool ao_arguments_parse_argv(PyObject *list, struct ao_options *opts, PyObject **keep);

/* Gets obj's contiguous buffer of `count` items of `size` bytes (writable when asked) into *view, to
 * release; false with ValueError naming `what` where its length differs. */
bool ao_arguments_get_buffer(PyObject *obj, Py_buffer *view, size_t size, size_t count, bool writable,
                             const char *what);

#endif
