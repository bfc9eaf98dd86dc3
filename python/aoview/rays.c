/* _core's Mesh type: a triangle mesh's Embree BVH (the core's tracer_arrays.h) and the batches of
 * rays traced against it, for ray_mesh_intersect and RayMeshIntersector; see rays.h. */
#define PY_SSIZE_T_CLEAN
#include "rays.h"

#include "arguments.h"
#include "messages.h"
#include "tracer_arrays.h"

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
        if (!ao_arguments_get_buffer(o[got], &b[got], sizes[got], (size_t)k, got >= 2, names[got]))
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
    if (!ao_arguments_get_buffer(o[0], &b[0], 12, (size_t)n, false, "vertices"))
        return NULL;
    if (!ao_arguments_get_buffer(o[1], &b[1], 12, (size_t)m, false, "faces")) {
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

PyTypeObject ao_rays_mesh_type = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "aoview._core.Mesh",
    .tp_basicsize = sizeof(MeshObject),
    .tp_dealloc = (destructor)mesh_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "A triangle mesh's Embree BVH, for batches of rays.",
    .tp_methods = mesh_methods,
    .tp_new = mesh_new,
};
