/* Big buffers that a run fills as it goes (an image's sums, its frames): zeroed, and from 2 MiB
 * mapped from the system directly in transparent huge pages where the system has them. In a
 * virtual machine the first touch of a fresh 4 KiB page costs about 11 µs (the sums and frames of a
 * 640x480 image: 25 ms of a first pass's 36), of a 2 MiB page a few ms at most; smaller buffers
 * come from the heap, whose pages the process has mostly touched already (docs/performance.md). */
#ifndef AO_PAGES_H
#define AO_PAGES_H

#include <stddef.h>

/* Buffers of at least this many bytes are mapped whole in 2 MiB pages (rounded up to them: at most
 * half their size more); smaller ones are the heap's. */
#define AO_PAGES_HUGE_FROM ((size_t)2 << 20)

/* A zeroed buffer of `size` bytes (more than 0), aligned as malloc's; NULL when memory is short.
 * Give it back with ao_pages_free and the same size. Any thread. */
void *ao_pages_alloc(size_t size);

/* Gives back a buffer of `size` bytes from ao_pages_alloc; accepts NULL. Any thread. */
void ao_pages_free(void *pages, size_t size);

#endif
