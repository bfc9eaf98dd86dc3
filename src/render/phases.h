/* Where a pass's time goes, phase by phase on every thread of the team: a measuring build's
 * (meson option phases=true, docs/performance.md#where-a-small-runs-time-goes), which says one
 * note a pass; in any other build every function here is an empty inline and costs nothing. One
 * renderer at a time: the figures are the process's. */
#ifndef AO_PHASES_H
#define AO_PHASES_H

#include <stdint.h>

/* The phases: between passes, planning the pass, surveying it (error estimate, RMSE, the next
 * pass's plan) and publishing it (the rest of the frame's resolve, the callbacks: a stats row);
 * in a pass, per thread, the time before its job (the render thread's start, a worker's wake-up),
 * tracing tiles, adding their sums (accumulation, error terms, resolve), and idling after its
 * last tile until the pass ends. */
enum ao_phase {
    AO_PHASE_PLAN,
    AO_PHASE_SURVEY,
    AO_PHASE_PUBLISH,
    AO_PHASE_BEFORE,
    AO_PHASE_TRACE,
    AO_PHASE_ADD,
    AO_PHASE_IDLE,
    AO_PHASE_COUNT
};

#ifdef AO_PHASES

/* ao_clock_seconds. Any thread. */
double ao_phases_clock(void);

/* Clears the figures of the pass before. Render thread. */
void ao_phases_begin(void);

/* Notes the start of the pass's job, from which each thread's time before it counts. Render
 * thread. */
void ao_phases_job(double start);

/* Adds seconds to this thread's phase (a thread outside a pass's job: the render thread's). Any
 * thread of the team, each its own. */
void ao_phases_add(enum ao_phase phase, double seconds);

/* Team thread `self` enters the pass's job (its wake-up or start measured from the pass's) or
 * leaves it. */
void ao_phases_enter(int self);
void ao_phases_leave(int self);

/* After the pass's job: every thread idled from its leaving until `end`. Render thread. */
void ao_phases_job_end(int threads, double end);

/* Says the pass's phases in one note (text.h): pass, rays, its seconds, and each phase in ms,
 * those in the pass the mean over the team's `threads`. Render thread. */
void ao_phases_say(int threads, uint32_t pass, uint64_t rays, double seconds);

#else

static inline double ao_phases_clock(void)
{
    return 0.0;
}

static inline void ao_phases_begin(void)
{
}

static inline void ao_phases_job(double start)
{
    (void)start;
}

static inline void ao_phases_add(enum ao_phase phase, double seconds)
{
    (void)phase;
    (void)seconds;
}

static inline void ao_phases_enter(int self)
{
    (void)self;
}

static inline void ao_phases_leave(int self)
{
    (void)self;
}

static inline void ao_phases_job_end(int threads, double end)
{
    (void)threads;
    (void)end;
}

static inline void ao_phases_say(int threads, uint32_t pass, uint64_t rays, double seconds)
{
    (void)threads;
    (void)pass;
    (void)rays;
    (void)seconds;
}

#endif

#endif
