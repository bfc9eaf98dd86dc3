/* _core's Scene type (aoview._core.Scene, whose object is scene_object.h's) and the module functions
 * that fill a Scene or read it whole. The functions take the module's arguments as a tuple, as
 * METH_VARARGS does, and return a new reference or NULL with the exception set; the GIL held, which
 * they release while the core works. */
#ifndef AO_PYTHON_SCENE_TYPE_H
#define AO_PYTHON_SCENE_TYPE_H

#include <Python.h>

#include "scene_object.h"
#include "tracer.h"

/* aoview._core.Scene: a loaded scene and its tracer (made ready by the module's init). */
extern PyTypeObject ao_scene_type;

/* The scene's tracer, built on first use (GIL released meanwhile) and owned by the scene; NULL with
 * MemoryError (the core's message) when it cannot be built. */
struct ao_tracer *ao_scene_type_tracer(SceneObject *self);

/* load(scene: Scene, path: str, argv: list): ao_scene_load with argv's scene options. */
PyObject *ao_scene_type_load(PyObject *module, PyObject *args);

/* from_arrays(scene, name, positions float32 (n,3), n, indices uint32 (m,3), m, normals or None,
 * albedo (r, g, b), spheres float32 (k,7) [cx cy cz r ar ag ab], k, camera float32 (10,) or None,
 * argv): ao_scene_from_arrays. */
PyObject *ao_scene_type_from_arrays(PyObject *module, PyObject *args);

/* exact(scene, argv, out) -> kind: the exact image (width x height x 3 floats) as aoview-exact makes it. */
PyObject *ao_scene_type_exact(PyObject *module, PyObject *args);

#endif
