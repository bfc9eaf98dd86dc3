/* A team of threads that runs one job at a time on every thread together: the render thread's
 * passes and previews. The thread that runs a job takes part in it as thread 0. Between jobs, and
 * while thread 0 waits for the others, a thread spins briefly (yielding its core) before it sleeps,
 * so that the many short passes of a small image do not wait for threads to wake. */
#ifndef AO_POOL_H
#define AO_POOL_H

#include <stdbool.h>

/* The team; opaque. */
struct ao_pool;

/* What every thread of a job runs: self in [0, threads), 0 being the caller of ao_pool_run. */
typedef void ao_pool_job(void *user, int self);

/* Starts threads - 1 workers, each calling thread_init (if not NULL) once before its first job;
 * NULL after one message (text.h) when memory or threads are short. */
struct ao_pool *ao_pool_create(int threads, void (*thread_init)(void));

/* Joins the workers and frees; accepts NULL. Not while a job runs. */
void ao_pool_destroy(struct ao_pool *pool);

/* Runs job(user, self) on every thread of the team and returns when all of them have returned;
 * the workers' messages go to the calling thread's sink (text.h) meanwhile. One thread at a time
 * (the render thread). */
void ao_pool_run(struct ao_pool *pool, ao_pool_job *job, void *user);

#endif
