/* _core's Mesh type (aoview._core.Mesh): a triangle mesh's Embree BVH (the core's tracer_arrays.h),
 * built once and traced against by batches of rays, with the GIL released while it builds or traces;
 * the Python half's ray_mesh_intersect and RayMeshIntersector stand on it. */
#ifndef AO_PYTHON_RAYS_H
#define AO_PYTHON_RAYS_H

#include <Python.h>

/* aoview._core.Mesh(positions, n, indices, m), with intersect(...) (made ready by the module's init). */
extern PyTypeObject ao_rays_mesh_type;

#endif
