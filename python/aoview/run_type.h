/* _core's Run type (aoview._core.Run): a render in progress, which the Python half steps pass by
 * pass (run.step), and the module function that starts one. The GIL held. */
#ifndef AO_PYTHON_RUN_TYPE_H
#define AO_PYTHON_RUN_TYPE_H

#include <Python.h>

/* aoview._core.Run: the core's renderer on a Scene it keeps alive (made ready by the module's init). */
extern PyTypeObject ao_run_type;

/* start(scene, argv, reference, every_pass) -> Run: the renderer started with argv's settings;
 * reference: None, a path (str), or a float32 buffer of the image's width x height x 3. NULL with
 * the exception set (ValueError with the core's message where the render could not start). */
PyObject *ao_run_type_start(PyObject *module, PyObject *args);

#endif
