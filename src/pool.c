/* The thread team; see pool.h. */
#include "pool.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>

#include "text.h"

struct ao_pool {
    pthread_mutex_t lock;
    pthread_cond_t start, end;
    uint64_t serial;                 /* bumped to start a job */
    int busy;                        /* workers still in the job */
    bool quit;                       /* workers exit */
    ao_pool_job *job;
    void *user;
    const struct ao_text_sink *sink; /* ao_pool_run's caller's: the workers' route for its job */
    void (*thread_init)(void);
    atomic_int started;              /* numbers the workers */
    int workers;
    pthread_t *ids;
};

static void *worker_main(void *arg)
{
    struct ao_pool *p = arg;
    uint64_t seen = 0;
    int self = 1 + atomic_fetch_add(&p->started, 1);
    if (p->thread_init)
        p->thread_init();
    pthread_mutex_lock(&p->lock);
    for (;;) {
        while (p->serial == seen && !p->quit)
            pthread_cond_wait(&p->start, &p->lock);
        if (p->quit)
            break;
        seen = p->serial;
        ao_pool_job *job = p->job;
        void *user = p->user;
        ao_text_route(p->sink);
        pthread_mutex_unlock(&p->lock);
        job(user, self);
        pthread_mutex_lock(&p->lock);
        if (--p->busy == 0)
            pthread_cond_signal(&p->end);
    }
    pthread_mutex_unlock(&p->lock);
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
    p->quit = true;
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
    p->busy = p->workers;
    p->serial++;
    pthread_cond_broadcast(&p->start);
    pthread_mutex_unlock(&p->lock);
    job(user, 0);
    pthread_mutex_lock(&p->lock);
    while (p->busy > 0)
        pthread_cond_wait(&p->end, &p->lock);
    pthread_mutex_unlock(&p->lock);
}
