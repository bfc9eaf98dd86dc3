/* Big buffers (pages.c): zero and writable to their last byte; from AO_PAGES_HUGE_FROM mapped
 * 2 MiB-aligned and advised into huge pages (the mapping's VmFlags in /proc/self/smaps say "hg")
 * and given back whole, below it the heap's. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <fcntl.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "pages.h"
#include "unit_main.h"

enum { HUGE_PAGE = 2 << 20 };

/* Whether the mapping that holds `p` is advised into huge pages, by /proc/self/smaps; false when
 * the file is missing (not Linux). */
static bool advised_huge(const void *p)
{
    FILE *f = fopen("/proc/self/smaps", "r");
    if (!f)
        return false;
    char line[512];
    bool inside = false, huge = false;
    while (fgets(line, sizeof line, f)) {
        unsigned long long begin, end;
        if (sscanf(line, "%llx-%llx ", &begin, &end) == 2 && strchr(line, '-') < strchr(line, ' '))
            inside = (uintptr_t)p >= begin && (uintptr_t)p < end;
        else if (inside && strncmp(line, "VmFlags:", 8) == 0)
            huge = strstr(line, " hg") != NULL;
    }
    fclose(f);
    return huge;
}

/* Every byte zero, then written. */
static void check_zero_and_write(unsigned char *p, size_t size)
{
    for (size_t k = 0; k < size; k++)
        assert_int_equal(p[k], 0);
    memset(p, 0xa5, size);
    assert_int_equal(p[size - 1], 0xa5);
}

static void test_small_buffers(void **state)
{
    (void)state;
    static const size_t sizes[] = {1, 4095, 4097, 200000, AO_PAGES_HUGE_FROM - 1};
    for (size_t k = 0; k < sizeof sizes / sizeof *sizes; k++) {
        unsigned char *p = ao_pages_alloc(sizes[k]);
        assert_non_null(p);
        assert_int_equal((uintptr_t)p % _Alignof(double), 0);
        check_zero_and_write(p, sizes[k]);
        assert_false(advised_huge(p));
        ao_pages_free(p, sizes[k]);
    }
    ao_pages_free(NULL, 100);
}

static void test_big_buffers(void **state)
{
    (void)state;
    static const size_t sizes[] = {AO_PAGES_HUGE_FROM, AO_PAGES_HUGE_FROM + 1, 5 * (size_t)HUGE_PAGE - 12345};
    for (size_t k = 0; k < sizeof sizes / sizeof *sizes; k++) {
        unsigned char *p = ao_pages_alloc(sizes[k]);
        assert_non_null(p);
        assert_int_equal((uintptr_t)p % HUGE_PAGE, 0);
        check_zero_and_write(p, sizes[k]);
        FILE *smaps = fopen("/proc/self/smaps", "r");
        if (smaps) { /* Linux: the advice is in the mapping's flags */
            fclose(smaps);
            assert_true(advised_huge(p));
        }
        ao_pages_free(p, sizes[k]);
    }
}

/* The process's mapped address space in KiB (/proc/self/status's VmSize), -1 where there is none.
 * Read without allocating (stdio's buffer could be mapped in between, under a sanitizer's
 * allocator). */
static long mapped_kib(void)
{
    int fd = open("/proc/self/status", O_RDONLY);
    if (fd < 0)
        return -1;
    char text[8192];
    ssize_t n = read(fd, text, sizeof text - 1);
    close(fd);
    text[n > 0 ? n : 0] = '\0';
    const char *line = strstr(text, "VmSize:");
    long kib = -1;
    return line && sscanf(line, "VmSize: %ld kB", &kib) == 1 ? kib : -1;
}

/* A buffer maps its size rounded up to whole huge pages (nothing is left of the room taken to
 * align it) and gives back all of it. */
static void test_given_back(void **state)
{
    (void)state;
    long before = mapped_kib();
    if (before < 0)
        skip();
    static const size_t sizes[] = {AO_PAGES_HUGE_FROM, 3 * (size_t)HUGE_PAGE + 1};
    for (size_t k = 0; k < sizeof sizes / sizeof *sizes; k++) {
        void *p = ao_pages_alloc(sizes[k]);
        assert_non_null(p);
        long whole = (long)((sizes[k] + HUGE_PAGE - 1) / HUGE_PAGE * HUGE_PAGE / 1024);
        assert_int_equal(mapped_kib() - before, whole);
        ao_pages_free(p, sizes[k]);
        assert_int_equal(mapped_kib(), before);
    }
}

UNIT_TEST_MAIN(cmocka_unit_test(test_small_buffers), cmocka_unit_test(test_big_buffers),
               cmocka_unit_test(test_given_back))
