/* Big buffers; see pages.h. */
/* Linux's madvise and MADV_HUGEPAGE, and MAP_ANONYMOUS, which POSIX 2008 lacks. */
#define _DEFAULT_SOURCE
#include "pages.h"

#include <stdint.h>
#include <stdlib.h>
#include <sys/mman.h>

/* A transparent huge page (x86-64's). */
#define HUGE_PAGE ((size_t)2 << 20)

/* The bytes a buffer of AO_PAGES_HUGE_FROM or more maps: whole huge pages; 0 when that does not
 * fit a size_t. */
static size_t mapped(size_t size)
{
    return size > SIZE_MAX - 2 * HUGE_PAGE ? 0 : (size + HUGE_PAGE - 1) / HUGE_PAGE * HUGE_PAGE;
}

void *ao_pages_alloc(size_t size)
{
    /* Below a huge page, one would make the first touch fault in 2 MiB for less, where the heap
     * has pages touched already: at 160x120 the first pass took 5 ms with the sums and frame in
     * huge pages, 3 ms from the heap. */
    if (size < AO_PAGES_HUGE_FROM)
        return calloc(1, size);
    size_t whole = mapped(size);
    if (!whole)
        return NULL;
    /* Huge pages need 2 MiB alignment: one huge page more is mapped, and what lies outside the
     * aligned span given back. Fresh mappings are zero. */
    unsigned char *p = mmap(NULL, whole + HUGE_PAGE, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED)
        return NULL;
    size_t head = (HUGE_PAGE - (uintptr_t)p % HUGE_PAGE) % HUGE_PAGE;
    if (head)
        munmap(p, head);
    if (HUGE_PAGE - head)
        munmap(p + head + whole, HUGE_PAGE - head);
#ifdef MADV_HUGEPAGE
    madvise(p + head, whole, MADV_HUGEPAGE); /* advice: where the system cannot, 4 KiB pages */
#endif
    return p + head;
}

void ao_pages_free(void *pages, size_t size)
{
    if (size < AO_PAGES_HUGE_FROM)
        free(pages);
    else if (pages)
        munmap(pages, mapped(size));
}
