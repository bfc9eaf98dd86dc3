/* The thread team (pool.c): a job runs once on every thread, the caller as thread 0, and the run
 * returns only when all have returned; each worker calls thread_init once, before its first job;
 * a team of one is the caller alone; many runs in a row (the threads suite runs this under
 * ThreadSanitizer too); a team without jobs stops spinning and sleeps. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <pthread.h>
#include <stdatomic.h>
#include <time.h>

#include "pool.h"
#include "unit_main.h"

enum { THREADS = 4, RUNS = 2000 };

/* What a job records: each thread's runs, selves out of range, and the thread that ran as 0. */
struct record {
    atomic_int runs[THREADS];
    atomic_int inside;               /* threads inside the job now */
    atomic_int strays;
    pthread_t zero;
};

/* The workers' thread_init calls. */
static atomic_int inits;

static void count_init(void)
{
    atomic_fetch_add(&inits, 1);
}

static void job(void *user, int self)
{
    struct record *r = user;
    if (self < 0 || self >= THREADS) {   /* counted: cmocka asserts on the test's thread only */
        atomic_fetch_add(&r->strays, 1);
        return;
    }
    if (self == 0)
        r->zero = pthread_self();
    atomic_fetch_add(&r->inside, 1);
    atomic_fetch_add(&r->runs[self], 1);
    atomic_fetch_sub(&r->inside, 1);
}

/* Every thread runs every job once, thread 0 being the caller; nobody is inside when a run
 * returns; thread_init ran once per worker. */
static void test_every_thread_once(void **state)
{
    (void)state;
    atomic_store(&inits, 0);
    struct ao_pool *pool = ao_pool_create(THREADS, count_init);
    assert_non_null(pool);
    struct record r = {0};
    for (int run = 1; run <= RUNS; run++) {
        ao_pool_run(pool, job, &r);
        assert_int_equal(atomic_load(&r.inside), 0);
        assert_int_equal(atomic_load(&r.strays), 0);
        for (int k = 0; k < THREADS; k++)
            assert_int_equal(atomic_load(&r.runs[k]), run);
        assert_true(pthread_equal(r.zero, pthread_self()));
    }
    assert_int_equal(atomic_load(&inits), THREADS - 1);
    ao_pool_destroy(pool);
}

/* A slow thread holds the run: ao_pool_run waits for it. */
static void slow_job(void *user, int self)
{
    atomic_int *done = user;
    if (self == THREADS - 1)
        nanosleep(&(struct timespec){.tv_nsec = 20 * 1000 * 1000}, NULL);
    atomic_fetch_add(done, 1);
}

static void test_run_waits_for_all(void **state)
{
    (void)state;
    struct ao_pool *pool = ao_pool_create(THREADS, NULL);
    assert_non_null(pool);
    for (int run = 0; run < 5; run++) {
        atomic_int done = 0;
        ao_pool_run(pool, slow_job, &done);
        assert_int_equal(atomic_load(&done), THREADS);
    }
    ao_pool_destroy(pool);
}

/* A team of one: the caller alone, no worker, no thread_init. */
static void test_team_of_one(void **state)
{
    (void)state;
    atomic_store(&inits, 0);
    struct ao_pool *pool = ao_pool_create(1, count_init);
    assert_non_null(pool);
    struct record r = {0};
    ao_pool_run(pool, job, &r);
    assert_int_equal(atomic_load(&r.runs[0]), 1);
    for (int k = 1; k < THREADS; k++)
        assert_int_equal(atomic_load(&r.runs[k]), 0);
    assert_int_equal(atomic_load(&inits), 0);
    ao_pool_destroy(pool);
    ao_pool_destroy(NULL);
}

/* The process's CPU seconds so far. */
static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* After a job the workers spin (pool.c's SPIN_SECONDS, 0.5 ms) and then sleep: over 0.3 s that
 * the caller sleeps 30 ms after a job, the process takes at most 30 ms of CPU (the spins, and the
 * scheduler's and clock's noise; three workers that kept spinning would take about 0.3 s each,
 * on however many cores they share). */
static void test_idle_team_sleeps(void **state)
{
    (void)state;
    struct ao_pool *pool = ao_pool_create(THREADS, NULL);
    assert_non_null(pool);
    struct record r = {0};
    ao_pool_run(pool, job, &r);
    nanosleep(&(struct timespec){.tv_nsec = 30 * 1000 * 1000}, NULL);
    double before = cpu_seconds();
    nanosleep(&(struct timespec){.tv_nsec = 300 * 1000 * 1000}, NULL);
    assert_true(cpu_seconds() - before < 0.03);
    ao_pool_destroy(pool);
}

UNIT_TEST_MAIN(cmocka_unit_test(test_every_thread_once), cmocka_unit_test(test_run_waits_for_all),
               cmocka_unit_test(test_team_of_one), cmocka_unit_test(test_idle_team_sleeps))
