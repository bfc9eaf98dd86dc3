/* Big buffers that a run fills as it goes (an image's sums, its frames), mapped from the system
 * directly: zero until written, and backed by transparent huge pages where the system has them.
 * In a virtual machine the first touch of a fresh 4 KiB page costs about 11 µs (the sums and
 * frames of a 640x480 image: 30 ms of a first pass's 40), of a 2 MiB page about 0.1 ms
 * (docs/performance.md). */
#ifndef AO_PAGES_H
#define AO_PAGES_H

#include <stddef.h>

/* Buffers of at least this many bytes are mapped whole in 2 MiB pages (rounded up to them, at
 * most 2 MiB more than asked); smaller ones in the system's pages. */
#define AO_PAGES_HUGE_FROM ((size_t)128 << 10)

/* A zeroed buffer of `size` bytes (more than 0), aligned to 64 bytes at least; NULL when memory
 * is short. Give it back with ao_pages_unmap and the same size. Any thread. */
void *ao_pages_map(size_t size);

/* Gives back a buffer of `size` bytes from ao_pages_map; accepts NULL. Any thread. */
void ao_pages_unmap(void *pages, size_t size);

#endif
