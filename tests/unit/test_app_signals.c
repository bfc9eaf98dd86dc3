/* The front ends' signals (app_signals.c): the names; the standard descriptors and SIGPIPE at the
 * start; what blocking leaves; each way a signal ends the process at once (while loading, with no
 * renderer, in the window, a second one), in child processes; then in this process, a watcher
 * started and finished without a signal, and a SIGTERM that stops a real renderer. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "app_fixture.h"
#include "app_load.h"
#include "app_output.h"
#include "app_report.h"
#include "app_signals.h"
#include "render.h"

static void test_signal_names(void **state)
{
    (void)state;
    assert_string_equal(ao_app_signal_name(SIGINT), "SIGINT");
    assert_string_equal(ao_app_signal_name(SIGTERM), "SIGTERM");
    assert_string_equal(ao_app_signal_name(SIGHUP), "SIGHUP");
    assert_string_equal(ao_app_signal_name(SIGUSR1), "a signal");
}

/* Runs child in a child process with its stderr in the scratch file `name`, which must end it
 * (an alarm does after 20 s: a watcher that misses its signal); returns its wait status. Called
 * while this process has no thread but its own, so that the child can start threads. */
static int run_child(void (*child)(void), const char *name)
{
    fflush(NULL);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        int fd = open(scratch_path(name), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(fd, STDERR_FILENO);
        alarm(20);
        child();
        _exit(99);
    }
    int status;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    return status;
}

/* The child exited with code (not killed by a signal, nor by the alarm). */
static void assert_exited(int status, int code)
{
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), code);
}

/* The child said exactly `expected` on stderr, kept in the scratch file `name`. */
static void assert_said(const char *name, const char *expected)
{
    char *said = read_file(scratch_path(name), NULL);
    assert_non_null(said);
    assert_string_equal(said, expected);
    free(said);
}

/* Sends sig to this process and waits for the watcher to end it. */
static _Noreturn void signal_self(int sig)
{
    kill(getpid(), sig);
    for (;;)
        pause();
}

/* Descriptors 0 and 1 closed: /dev/null takes them, for writing on 0 and reading on 1, so that a
 * file opened later is neither; SIGPIPE ignored. Exits 0 when all of that holds. */
static void begin_closed(void)
{
    close(STDIN_FILENO);
    close(STDOUT_FILENO);
    bool begun = ao_app_begin();
    struct sigaction pipe;
    sigaction(SIGPIPE, NULL, &pipe);
    int in = fcntl(STDIN_FILENO, F_GETFL), out = fcntl(STDOUT_FILENO, F_GETFL);
    int next = open("/dev/null", O_RDONLY);
    _exit(begun && pipe.sa_handler == SIG_IGN && in >= 0 && (in & O_ACCMODE) == O_WRONLY && out >= 0 &&
                  (out & O_ACCMODE) == O_RDONLY && next > STDERR_FILENO
              ? 0
              : 1);
}

static void test_begin(void **state)
{
    (void)state;
    assert_exited(run_child(begin_closed, "begin.txt"), 0);
    assert_said("begin.txt", "");
}

/* SIGINT ignored (a shell's background job) and SIGHUP ignored (nohup): SIGINT and SIGTERM are
 * blocked with their default disposition back, SIGHUP stays ignored and unblocked. Exits 0 when
 * so. */
static void block_ignored(void)
{
    signal(SIGINT, SIG_IGN);
    signal(SIGHUP, SIG_IGN);
    struct ao_app app = {0};
    ao_app_block_signals(&app);
    sigset_t mask;
    pthread_sigmask(SIG_BLOCK, NULL, &mask);
    struct sigaction in, hup;
    sigaction(SIGINT, NULL, &in);
    sigaction(SIGHUP, NULL, &hup);
    _exit(sigismember(&mask, SIGINT) && sigismember(&mask, SIGTERM) && !sigismember(&mask, SIGHUP) &&
                  in.sa_handler == SIG_DFL && hup.sa_handler == SIG_IGN &&
                  sigismember(&app.interrupt.signals, SIGTERM) && !sigismember(&app.interrupt.signals, SIGHUP)
              ? 0
              : 1);
}

static void test_block(void **state)
{
    (void)state;
    assert_exited(run_child(block_ignored, "block.txt"), 0);
}

/* Loading: a --stats file this run created is open, with no row. */
static void interrupt_loading(bool silent, int sig)
{
    struct ao_app app = {0};
    ao_app_block_signals(&app);
    const char *stats = scratch_path("loading.csv");
    if (!ao_app_start_watcher(&app, silent) || !ao_app_open_stats(&app.stats, stats, false, false))
        _exit(1);
    signal_self(sig);
}

static void interrupt_loading_said(void)
{
    interrupt_loading(false, SIGINT);
}

static void interrupt_loading_silent(void)
{
    interrupt_loading(true, SIGTERM);
}

/* While loading: 128 + the signal, one line (none from aoview-mpi's other ranks), and the --stats
 * file this run created removed. */
static void test_loading(void **state)
{
    (void)state;
    assert_exited(run_child(interrupt_loading_said, "loading.txt"), 128 + SIGINT);
    assert_said("loading.txt", "aoview: interrupted by SIGINT before rendering: nothing written\n");
    assert_int_not_equal(access(scratch_path("loading.csv"), F_OK), 0);
    assert_exited(run_child(interrupt_loading_silent, "silent.txt"), 128 + SIGTERM);
    assert_said("silent.txt", "");
}

/* Rendering with no renderer to stop (--compare's sides), graceful. */
static void interrupt_no_renderer(void)
{
    struct ao_app app = {0};
    ao_app_block_signals(&app);
    if (!ao_app_start_watcher(&app, false))
        _exit(1);
    atomic_store(&app.interrupt.graceful, true);
    ao_app_watch(&app, NULL);
    signal_self(SIGTERM);
}

static void test_no_renderer(void **state)
{
    (void)state;
    assert_exited(run_child(interrupt_no_renderer, "none.txt"), 128 + SIGTERM);
    assert_said("none.txt", "aoview: interrupted by SIGTERM: nothing written\n");
}

/* Loads the small scene, -o output, into l (zero-initialised) with its renderer watched, paused or
 * running until stopped; graceful: a signal stops it. False when it cannot. */
static bool start_rendering(struct loaded *l, const char *output, bool paused, bool graceful)
{
    struct ao_app *app = &l->app;
    ao_app_block_signals(app);
    if (!ao_app_start_watcher(app, false) ||
        load_line(l, "aoview --headless --size 32x24 --spp 1000000 --threads 1 --quiet -o %s %s", output,
                  source_path("assets/scenes/sphere-on-plane.scene")) != 0)
        return false;
    l->settings.paused = paused;
    if (!(app->render = ao_render_create(&l->config, &l->settings)))
        return false;
    atomic_store(&app->interrupt.graceful, graceful);
    ao_app_watch(app, app->render);
    return true;
}

/* The window's run (not graceful): a signal ends it as by default, silently. */
static void interrupt_window(void)
{
    struct loaded l = {0};
    if (!start_rendering(&l, scratch_path("window.pfm"), true, false))
        _exit(1);
    signal_self(SIGINT);
}

static void test_window(void **state)
{
    (void)state;
    assert_exited(run_child(interrupt_window, "window.txt"), 128 + SIGINT);
    assert_said("window.txt", "");
}

/* What the run does between the two signals. */
enum between { BEFORE_WRITING, AFTER_WRITING, AFTER_FAILED_WRITE };

/* Headless: the first SIGTERM stops the renderer (exit 3 if not), then, before -o is written, once
 * it is, or once its write failed (exit 4 if the write did otherwise), a second SIGINT ends the
 * process. */
static void interrupt_twice(enum between between)
{
    struct loaded l = {0};
    const char *output = scratch_path(between == AFTER_FAILED_WRITE ? "no-such-folder/second.pfm" : "second.pfm");
    if (!start_rendering(&l, output, false, true))
        _exit(1);
    kill(getpid(), SIGTERM);
    int sig;
    if (ao_app_wait(&l.app, &sig) || sig != SIGTERM)
        _exit(3);
    if (between != BEFORE_WRITING &&
        ao_app_write(&l.app, &l.opts, ao_render_resolve_stopped(l.app.render), NULL, false, 0) !=
            (between == AFTER_WRITING ? 0 : AO_EXIT_RUNTIME))
        _exit(4);
    signal_self(SIGINT);
}

static void interrupt_twice_unwritten(void)
{
    interrupt_twice(BEFORE_WRITING);
}

static void interrupt_twice_written(void)
{
    interrupt_twice(AFTER_WRITING);
}

static void interrupt_twice_failed(void)
{
    interrupt_twice(AFTER_FAILED_WRITE);
}

static void test_second_signal(void **state)
{
    (void)state;
    char expected[8192];
    assert_exited(run_child(interrupt_twice_unwritten, "unwritten.txt"), 128 + SIGINT);
    snprintf(expected, sizeof expected, "aoview: a second SIGINT ended the run: %s not written\n",
             scratch_path("second.pfm"));
    assert_said("unwritten.txt", expected);
    assert_exited(run_child(interrupt_twice_written, "written.txt"), 128 + SIGINT);
    snprintf(expected, sizeof expected, "aoview: a second SIGINT ended the run once %s was written\n",
             scratch_path("second.pfm"));
    assert_said("written.txt", expected);
    /* The write began and failed (its one line first): not written. */
    assert_exited(run_child(interrupt_twice_failed, "failed.txt"), 128 + SIGINT);
    char *said = read_file(scratch_path("failed.txt"), NULL);
    snprintf(expected, sizeof expected, "aoview: a second SIGINT ended the run: %s not written\n",
             scratch_path("no-such-folder/second.pfm"));
    assert_non_null(said);
    assert_int_equal(strlen(said), strchr(said, '\n') + 1 - said + strlen(expected));   /* two lines */
    assert_string_equal(strchr(said, '\n') + 1, expected);
    free(said);
}

/* From here on in this process (the children are done): a watcher started and ended without a
 * signal is joined, and the process goes on. */
static void test_watcher_joins(void **state)
{
    (void)state;
    struct ao_app app = {0};
    ao_app_block_signals(&app);
    assert_true(ao_app_start_watcher(&app, false));
    assert_true(app.interrupt.watching);
    ao_app_stop_watcher(&app.interrupt);
    assert_false(app.interrupt.watching);
    assert_int_equal(atomic_load(&app.interrupt.caught), 0);
    ao_app_stop_watcher(&app.interrupt);   /* ended already: nothing to do */
    assert_int_equal(ao_app_finish(&app, 7), 7);
}

/* SIGTERM to this process during a graceful run: the watcher stops the renderer, the wait says so,
 * and ao_app_finish ends the watcher before it frees the renderer. */
static void test_graceful_sigterm(void **state)
{
    (void)state;
    struct loaded l = {0};
    struct ao_app *app = &l.app;
    assert_true(start_rendering(&l, scratch_path("graceful.pfm"), false, true));
    assert_int_equal(kill(getpid(), SIGTERM), 0);
    int sig = 0;
    assert_false(ao_app_wait(app, &sig));
    assert_int_equal(sig, SIGTERM);
    const struct ao_frame *frame = ao_render_resolve_stopped(app->render);
    assert_non_null(frame);
    assert_true(frame->info.spp < 1000000);
    assert_int_equal(ao_app_finish(app, 128 + SIGTERM), 128 + SIGTERM);
    assert_false(app->interrupt.watching);
    assert_null(app->render);
}

int main(void)
{
    /* The tests that fork come first, while this process has no other thread. */
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_signal_names),
        cmocka_unit_test(test_begin),
        cmocka_unit_test(test_block),
        cmocka_unit_test(test_loading),
        cmocka_unit_test(test_no_renderer),
        cmocka_unit_test(test_window),
        cmocka_unit_test(test_second_signal),
        cmocka_unit_test(test_watcher_joins),
        cmocka_unit_test(test_graceful_sigterm),
    };
    return cmocka_run_group_tests(tests, app_fixture_setup, app_fixture_teardown);
}
