/* A pass's phases on every thread (see phases.h): built with meson's phases=true only. */
#include "phases.h"

#include "clock.h"
#include "text.h"

/* Threads the figures keep apart (--threads allows 256; more share the last slot). */
enum { MOST = 256 };

/* Each thread's seconds per phase and the time it left the job, written by that thread during a
 * job (the render thread's between jobs) and read by the render thread after it: ao_pool_run's
 * lock orders them. */
static double seconds_of[MOST][AO_PHASE_COUNT], left[MOST], started;
static _Thread_local int slot = -1; /* -1: a thread outside the team's jobs */

double ao_phases_clock(void)
{
    return ao_clock_seconds();
}

void ao_phases_begin(void)
{
    for (int k = 0; k < MOST; k++)
        for (int p = 0; p < AO_PHASE_COUNT; p++)
            seconds_of[k][p] = 0.0;
    slot = 0;
}

void ao_phases_job(double start)
{
    started = start;
}

void ao_phases_add(enum ao_phase phase, double seconds)
{
    if (slot >= 0)
        seconds_of[slot][phase] += seconds;
}

void ao_phases_enter(int self)
{
    slot = self < MOST ? self : MOST - 1;
    seconds_of[slot][AO_PHASE_BEFORE] += ao_clock_seconds() - started;
}

void ao_phases_leave(int self)
{
    left[self < MOST ? self : MOST - 1] = ao_clock_seconds();
    slot = self ? -1 : 0;
}

void ao_phases_job_end(int threads, double end)
{
    for (int k = 0; k < threads && k < MOST; k++)
        seconds_of[k][AO_PHASE_IDLE] += end - left[k];
}

void ao_phases_say(int threads, uint32_t pass, uint64_t rays, double seconds)
{
    int team = threads < MOST ? threads : MOST;
    double mean[AO_PHASE_COUNT] = {0}, wake = 0.0;
    for (int p = AO_PHASE_BEFORE; p < AO_PHASE_COUNT; p++)
        for (int k = 0; k < team; k++)
            mean[p] += seconds_of[k][p] / team;
    for (int k = 1; k < team; k++)
        wake += (seconds_of[k][AO_PHASE_BEFORE] - seconds_of[0][AO_PHASE_BEFORE]) / (team - 1);
    double other = seconds - mean[AO_PHASE_BEFORE] - mean[AO_PHASE_TRACE] - mean[AO_PHASE_ADD] - mean[AO_PHASE_IDLE];
    const double *own = seconds_of[0];
    ao_text_note("phases: pass %u rays %llu ms %.4f plan %.4f start %.4f wake %.4f trace %.4f add %.4f idle %.4f "
                 "other %.4f survey %.4f publish %.4f",
                 pass, (unsigned long long)rays, 1e3 * seconds, 1e3 * own[AO_PHASE_PLAN],
                 1e3 * own[AO_PHASE_BEFORE], 1e3 * wake, 1e3 * mean[AO_PHASE_TRACE], 1e3 * mean[AO_PHASE_ADD],
                 1e3 * mean[AO_PHASE_IDLE], 1e3 * other, 1e3 * own[AO_PHASE_SURVEY], 1e3 * own[AO_PHASE_PUBLISH]);
}
