/* Poison: this header on a folder's include path stops <embree3/rtcore_ray.h> there (src/meson.build). */
#error "Embree outside src/trace: only the tracer sees Embree; others use tracer.h (docs/architecture.md#folders)"
