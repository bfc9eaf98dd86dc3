/* Buffers mapped from the system; see pages.h. */
/* Linux's madvise and MADV_HUGEPAGE, and MAP_ANONYMOUS, which POSIX 2008 lacks. */
#define _DEFAULT_SOURCE
#include "pages.h"

#include <stdint.h>
#include <sys/mman.h>
#include <unistd.h>

/* A transparent huge page (x86-64's). */
#define HUGE_PAGE ((size_t)2 << 20)

/* The bytes a buffer of `size` maps: whole huge pages from AO_PAGES_HUGE_FROM, else whole pages;
 * 0 when that does not fit a size_t. */
static size_t mapped(size_t size)
{
    size_t unit = size >= AO_PAGES_HUGE_FROM ? HUGE_PAGE : (size_t)sysconf(_SC_PAGESIZE);
    return size > SIZE_MAX - 2 * HUGE_PAGE ? 0 : (size + unit - 1) / unit * unit;
}

void *ao_pages_map(size_t size)
{
    size_t whole = mapped(size);
    if (!whole)
        return NULL;
    if (whole % HUGE_PAGE) {
        void *p = mmap(NULL, whole, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        return p == MAP_FAILED ? NULL : p;
    }
    /* Huge pages need 2 MiB alignment: one huge page more is mapped, and what lies outside the
     * aligned span given back. */
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

void ao_pages_unmap(void *pages, size_t size)
{
    if (pages)
        munmap(pages, mapped(size));
}
