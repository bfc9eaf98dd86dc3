/* The thread team; see pool.h. */
#include "pool.h"

#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>

#include "clock.h"
#include "text.h"

/* Between jobs a thread spins this long, yielding, before it sleeps: a sleeping thread takes some
 * 0.05-0.1 ms to wake in a virtual machine, a fifth of a small pass, and the next job comes sooner
 * (the render thread's work between two passes of 640x480, or a worker's last tile at the end of
 * a pass, take less); a team left without jobs is asleep that much later (docs/performance.md). */
static const double SPIN_SECONDS = 0.5e-3;

struct ao_pool {
    pthread_mutex_t lock;
    pthread_cond_t start, end;
    atomic_uint_fast64_t serial;     /* bumped under `lock` to start a job */
    atomic_int busy;                 /* workers still in the job */
    atomic_bool quit;                /* workers exit; set under `lock` */
    ao_pool_job *job;                /* the job's, under `lock` */
    void *user;
    const struct ao_text_sink *sink; /* ao_pool_run's caller's: the workers' route for its job */
    void (*thread_init)(void);
    atomic_int started;              /* numbers the workers */
    int workers;
    pthread_t *ids;
};

/* One step of a bounded spin begun with *until = 0: yields the core (to any thread with work, when
 * the cores have more threads than they run), and false once the spin has lasted SPIN_SECONDS (the
 * clock read every 8 steps). */
static bool spinning(double *until, unsigned *steps)
{
    sched_yield();
    if (++*steps % 8)
        return true;
    double now = ao_clock_seconds();
    if (*until == 0.0)
        *until = now + SPIN_SECONDS;
    return now < *until;
}

/* Whether worker's next job (after job `seen`) is posted, or the team quits. */
static bool posted(const struct ao_pool *p, uint64_t seen)
{
    return atomic_load_explicit(&p->serial, memory_order_acquire) != seen ||
           atomic_load_explicit(&p->quit, memory_order_acquire);
}

static void *worker_main(void *arg)
{
    struct ao_pool *p = arg;
    uint64_t seen = 0;
    int self = 1 + atomic_fetch_add(&p->started, 1);
    if (p->thread_init)
        p->thread_init();
    for (;;) {
        double until = 0.0;
        unsigned steps = 0;
        while (!posted(p, seen) && spinning(&until, &steps))
            continue;
        pthread_mutex_lock(&p->lock);
        while (!posted(p, seen))
            pthread_cond_wait(&p->start, &p->lock);
        if (atomic_load(&p->quit)) {
            pthread_mutex_unlock(&p->lock);
            break;
        }
        seen = atomic_load(&p->serial);
        ao_pool_job *job = p->job;
        void *user = p->user;
        ao_text_route(p->sink);
        pthread_mutex_unlock(&p->lock);
        job(user, self);
        if (atomic_fetch_sub(&p->busy, 1) == 1) { /* the last: wakes ao_pool_run if it sleeps */
            pthread_mutex_lock(&p->lock);
            pthread_cond_signal(&p->end);
            pthread_mutex_unlock(&p->lock);
        }
    }
    return NULL;
}

struct ao_pool *ao_pool_create(int threads, void (*thread_init)(void))
{
    struct ao_pool *p = calloc(1, sizeof *p);
    if (!p || !(p->ids = calloc((size_t)threads, sizeof *p->ids))) {
        ao_text_report("aoview: out of memory starting the renderer");
        free(p);
        return NULL;
    }
    p->thread_init = thread_init;
    atomic_init(&p->serial, 0);
    atomic_init(&p->busy, 0);
    atomic_init(&p->quit, false);
    atomic_init(&p->started, 0);
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->start, NULL);
    pthread_cond_init(&p->end, NULL);
    while (p->workers + 1 < threads && pthread_create(&p->ids[p->workers], NULL, worker_main, p) == 0)
        p->workers++;
    if (p->workers + 1 < threads) {
        ao_text_report("aoview: could not start %d render threads", threads);
        ao_pool_destroy(p);
        return NULL;
    }
    return p;
}

void ao_pool_destroy(struct ao_pool *p)
{
    if (!p)
        return;
    pthread_mutex_lock(&p->lock);
    atomic_store(&p->quit, true);
    pthread_cond_broadcast(&p->start);
    pthread_mutex_unlock(&p->lock);
    for (int k = 0; k < p->workers; k++)
        pthread_join(p->ids[k], NULL);
    pthread_cond_destroy(&p->end);
    pthread_cond_destroy(&p->start);
    pthread_mutex_destroy(&p->lock);
    free(p->ids);
    free(p);
}

void ao_pool_run(struct ao_pool *p, ao_pool_job *job, void *user)
{
    pthread_mutex_lock(&p->lock);
    p->job = job;
    p->user = user;
    p->sink = ao_text_current();
    atomic_store(&p->busy, p->workers);
    atomic_fetch_add_explicit(&p->serial, 1, memory_order_release);
    pthread_cond_broadcast(&p->start);
    pthread_mutex_unlock(&p->lock);
    job(user, 0);
    double until = 0.0;
    unsigned steps = 0;
    while (atomic_load(&p->busy) > 0 && spinning(&until, &steps))
        continue;
    if (atomic_load(&p->busy) > 0) {
        pthread_mutex_lock(&p->lock);
        while (atomic_load(&p->busy) > 0)
            pthread_cond_wait(&p->end, &p->lock);
        pthread_mutex_unlock(&p->lock);
    }
}
