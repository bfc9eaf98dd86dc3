/* The standard descriptors, SIGPIPE and the signal watcher; see app_signals.h. */
#include "app_signals.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <unistd.h>

#include "image.h"
#include "render.h"
#include "text.h"

bool ao_app_begin(void)
{
    /* A write to a closed socket or pipe (an X server killed under the window, a --stats FIFO
     * whose reader left, stderr read by a program that quit) then fails and is reported, instead
     * of killing aoview silently. */
    signal(SIGPIPE, SIG_IGN);
    for (int fd = 0; fd <= 2; fd++) {
        if (fcntl(fd, F_GETFD) >= 0 || errno != EBADF)
            continue;
        int null = open("/dev/null", fd == 0 ? O_WRONLY : O_RDONLY); /* the lowest free: fd */
        if (null != fd) {
            fprintf(stderr, "aoview: cannot open /dev/null: %s\n", strerror(errno));
            return false;
        }
    }
    return true;
}

const char *ao_app_signal_name(int sig)
{
    return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "a signal";
}

/* What a signal that ends the process at once says. */
enum ending { ENDING_SILENT, ENDING_LOADING, ENDING_NOTHING_WRITTEN, ENDING_SECOND };

/* Ends the process at once with 128 + sig: removes the temporary files of writes in progress and
 * a --stats file this run created and got no row into; then says, in one line, what the ending
 * left (write(2): the main thread may hold stderr's lock): for a second signal whether -o was
 * written, which the count of finished writes tells, now that none can begin or end. */
static void end_at_once(const struct ao_interrupt *in, int sig, enum ending ending)
{
    ao_image_discard_temporaries();
    const struct ao_stats *st = in->stats;
    if (st && atomic_load(&st->created) && !atomic_load(&st->wrote))
        unlink(st->path);
    char line[AO_TEXT_SIZE + 128], name[AO_TEXT_SIZE];
    const char *what = ao_app_signal_name(sig);
    int n = 0;
    if (ending == ENDING_LOADING)
        n = snprintf(line, sizeof line, "aoview: interrupted by %s before rendering: nothing written\n", what);
    else if (ending == ENDING_NOTHING_WRITTEN)
        n = snprintf(line, sizeof line, "aoview: interrupted by %s: nothing written\n", what);
    else if (ending == ENDING_SECOND)
        n = snprintf(line, sizeof line, atomic_load(&in->writing) && ao_image_written() >
                                                                           atomic_load(&in->written_before)
                                            ? "aoview: a second %s ended the run once %s was written\n"
                                            : "aoview: a second %s ended the run: %s not written\n",
                     what, ao_text_escape(in->output ? in->output : "aoview.png", name, sizeof name));
    if (ending != ENDING_SILENT && !in->silent && write(STDERR_FILENO, line, (size_t)n) < 0) {
        /* nowhere left to say it */
    }
    _exit(128 + sig);
}

static void *watch_signals(void *arg)
{
    struct ao_interrupt *in = arg;
    int sig;
    if (sigwait(&in->signals, &sig) != 0 || atomic_load(&in->closing))
        return NULL;
    struct ao_render *render = atomic_load(&in->render);
    if (!atomic_load(&in->rendering))
        end_at_once(in, sig, ENDING_LOADING);
    if (!render)
        end_at_once(in, sig, ENDING_NOTHING_WRITTEN);
    if (!atomic_load(&in->graceful))
        end_at_once(in, sig, ENDING_SILENT);
    atomic_store(&in->caught, sig);
    ao_render_stop(render);
    if (sigwait(&in->signals, &sig) == 0 && !atomic_load(&in->closing))
        end_at_once(in, sig, ENDING_SECOND);
    return NULL;
}

/* Their disposition goes back to default first: a shell starts background jobs with SIGINT
 * ignored, and an ignored signal never reaches sigwait. SIGHUP ignored stays so: nohup asked for
 * the run to outlive the terminal. */
void ao_app_block_signals(struct ao_app *app)
{
    struct ao_interrupt *in = &app->interrupt;
    struct sigaction hup;
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    sigemptyset(&in->signals);
    sigaddset(&in->signals, SIGINT);
    sigaddset(&in->signals, SIGTERM);
    if (sigaction(SIGHUP, NULL, &hup) == 0 && hup.sa_handler != SIG_IGN)
        sigaddset(&in->signals, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &in->signals, NULL);
}

bool ao_app_start_watcher(struct ao_app *app, bool silent)
{
    app->interrupt.silent = silent;
    app->interrupt.stats = &app->stats;
    if (pthread_create(&app->interrupt.watcher, NULL, watch_signals, &app->interrupt) != 0) {
        fprintf(stderr, "aoview: could not start the signal watcher thread\n");
        return false;
    }
    app->interrupt.watching = true;
    return true;
}

void ao_app_watch(struct ao_app *app, struct ao_render *render)
{
    atomic_store(&app->interrupt.render, render);
    atomic_store(&app->interrupt.rendering, true);
}

bool ao_app_wait(struct ao_app *app, int *sig)
{
    bool finished = ao_render_wait(app->render);
    *sig = atomic_load(&app->interrupt.caught);
    return finished;
}

/* Wakes the watcher with a signal of its set sent to it alone, which it reads as the end. */
void ao_app_stop_watcher(struct ao_interrupt *in)
{
    if (!in->watching)
        return;
    atomic_store(&in->closing, true);
    pthread_kill(in->watcher, SIGTERM);
    pthread_join(in->watcher, NULL);
    in->watching = false;
}
