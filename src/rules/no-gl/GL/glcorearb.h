/* Poison: this header on a folder's include path stops <GL/glcorearb.h> there (src/meson.build). */
#error "GL in the core: the core links no GL or window system; GL code belongs in src/gl (docs/architecture.md#folders)"
