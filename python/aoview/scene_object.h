/* The Python object aoview._core.Scene, shared by the module's two extensions: _core (which makes
 * and renders scenes) and _window (view(), over the GL library), each of which links its own copy
 * of the core. */
#ifndef AO_PYTHON_SCENE_OBJECT_H
#define AO_PYTHON_SCENE_OBJECT_H

#include <Python.h>

#include <stdbool.h>

#include "scene.h"
#include "tracer.h"

/* A loaded scene and the tracer _core built for it at its first render (NULL until then). */
typedef struct {
    PyObject_HEAD
    struct ao_scene scene;
    struct ao_tracer *tracer;
    bool loaded;
} SceneObject;

#endif
