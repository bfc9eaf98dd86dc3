/* What a real aoview window shows, seen from the X server, for the window suite (test_window.sh's
 * frames and start cases) and by hand. It starts aoview with its --stats rows written into a FIFO
 * that it reads as they come, and logs on one clock when each pass finished (its row), when the
 * window was mapped, and when it presented a frame: a DAMAGE report on the window (one a swap)
 * after its title changed (window.c sets the title, which holds the pass number, before it swaps),
 * so that a redraw of nothing new (an expose) does not count.
 *   window_frames frames [OPTIONS] AOVIEW ARGS...   every finished pass on screen (check_frames)
 *   window_frames start [OPTIONS] KEY AOVIEW ARGS... a window at once, keys during a pass, and the
 *                                                    end within 0.2 s of KEY (q, Escape, or close:
 *                                                    the window manager's WM_DELETE_WINDOW)
 * Options: --log prints the events; --patience N multiplies every time bound (a sanitizer's
 * build, several times slower). Exits 77 without a display, DAMAGE or XTEST; 1 after a FAIL line. */
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <X11/Xlib.h>
#include <X11/extensions/XTest.h>
#include <X11/extensions/Xdamage.h>

extern char **environ;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* How much longer than on a quiet machine a thread of ours takes to get its CPU time now: 1 / (1 -
 * s), s the share of the last 10 s in which some runnable thread waited for a core (the kernel's
 * pressure stall information, /proc/pressure/cpu's "some avg10"), at least 1; where the kernel
 * gives none, the wall time over the CPU time of 200 ms of spinning. On a quiet machine 1; with
 * other builds on both cores 2 to 4. */
static double slowdown(void)
{
    FILE *f = fopen("/proc/pressure/cpu", "r");
    double share = -1.0;
    if (f) {
        if (fscanf(f, "some avg10=%lf", &share) != 1)
            share = -1.0;
        fclose(f);
    }
    if (share >= 0.0)
        return 1.0 / (1.0 - fmin(share, 90.0) / 100.0);
    struct timespec ts;
    double wall = now(), cpu;
    do {
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
        cpu = (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
    } while (cpu < 0.2 && now() - wall < 5.0);
    return fmax(1.0, (now() - wall) / cpu);
}

enum kind { PASS, MAPPED, PRESENTED, KEY, EXITED };
static const char *const kind_name[] = {"pass", "mapped", "presented", "key", "exited"};

struct event {
    double t;                /* seconds since aoview was started */
    enum kind kind;
    int pass;                /* a pass's number */
};

/* The run being watched. */
struct watch {
    Display *dpy;
    int damage_event;
    Atom title;              /* _NET_WM_NAME */
    Window window;           /* aoview's, once mapped */
    bool retitled;           /* the title changed since the last DAMAGE report */
    pid_t pid;
    bool exited;
    double t0;
    int rows;                /* the FIFO's read end */
    char fifo[64];
    char line[4096];
    size_t used;
    struct event events[1 << 15];
    int count;
};

static void note(struct watch *w, enum kind kind, int pass)
{
    if (w->count < (int)(sizeof w->events / sizeof w->events[0]))
        w->events[w->count++] = (struct event){now() - w->t0, kind, pass};
}

/* Takes in what happened: rows, X events, the process's end; waits at most 1 ms for it. */
static void poll_once(struct watch *w)
{
    struct pollfd fds[2] = {{ConnectionNumber(w->dpy), POLLIN, 0}, {w->rows, POLLIN, 0}};
    poll(fds, 2, 1);
    ssize_t got;
    while ((got = read(w->rows, w->line + w->used, sizeof w->line - 1 - w->used)) > 0) {
        w->used += (size_t)got;
        w->line[w->used] = '\0';
        for (char *end; (end = strchr(w->line, '\n'));) {
            int pass;
            if (sscanf(w->line, "%d,", &pass) == 1)
                note(w, PASS, pass);
            size_t rest = w->used - (size_t)(end + 1 - w->line);
            memmove(w->line, end + 1, rest + 1);
            w->used = rest;
        }
    }
    while (XPending(w->dpy)) {
        XEvent e;
        XNextEvent(w->dpy, &e);
        if (e.type == MapNotify && !w->window && e.xmap.event == DefaultRootWindow(w->dpy)) {
            w->window = e.xmap.window;
            note(w, MAPPED, 0);
            XSelectInput(w->dpy, w->window, PropertyChangeMask);
            XDamageCreate(w->dpy, w->window, XDamageReportRawRectangles);
        } else if (e.type == PropertyNotify && e.xproperty.window == w->window && e.xproperty.atom == w->title) {
            w->retitled = true;
        } else if (e.type == w->damage_event + XDamageNotify && !((XDamageNotifyEvent *)&e)->more && w->retitled) {
            w->retitled = false;
            note(w, PRESENTED, 0);
        }
    }
    if (!w->exited && waitpid(w->pid, NULL, WNOHANG) == w->pid) {
        w->exited = true;
        note(w, EXITED, 0);
    }
}

/* Starts aoview (argv, NULL-terminated) with --stats into a FIFO, watching for its window. */
static bool start(struct watch *w, char **argv, int argc)
{
    char fifo[64];
    snprintf(fifo, sizeof fifo, "/tmp/window_frames_%d.csv", (int)getpid());
    unlink(fifo);
    if (mkfifo(fifo, 0600) != 0 || (w->rows = open(fifo, O_RDONLY | O_NONBLOCK)) < 0) {
        perror("window_frames: the FIFO");
        return false;
    }
    XSelectInput(w->dpy, DefaultRootWindow(w->dpy), SubstructureNotifyMask);
    w->title = XInternAtom(w->dpy, "_NET_WM_NAME", False);
    XSync(w->dpy, False);
    char **args = calloc((size_t)argc + 3, sizeof *args);
    for (int k = 0; k < argc; k++)
        args[k] = argv[k];
    args[argc] = "--stats";
    args[argc + 1] = fifo;
    w->t0 = now();
    bool ok = posix_spawn(&w->pid, args[0], NULL, NULL, args, environ) == 0;
    if (!ok)
        fprintf(stderr, "window_frames: cannot start %s\n", args[0]);
    free(args);
    snprintf(w->fifo, sizeof w->fifo, "%s", fifo);
    return ok;
}

/* The time of the first event of a kind at or after `from`; NAN when none came. */
static double first_after(const struct watch *w, enum kind kind, double from)
{
    for (int k = 0; k < w->count; k++)
        if (w->events[k].kind == kind && w->events[k].t >= from)
            return w->events[k].t;
    return NAN;
}

/* Watches until `until` seconds since the start, the process's end, or (unless `from` is NAN) an
 * event of the kind at or after `from`. */
static void watch_until(struct watch *w, double until, enum kind kind, double from)
{
    while (!w->exited && now() - w->t0 < until && (isnan(from) || isnan(first_after(w, kind, from))))
        poll_once(w);
}

/* Ends aoview (SIGTERM) unless it has ended, and waits for it. */
static void finish(struct watch *w)
{
    if (!w->exited) {
        kill(w->pid, SIGTERM);
        waitpid(w->pid, NULL, 0);
        w->exited = true;
    }
    close(w->rows);
    unlink(w->fifo);
}

static void print_log(const struct watch *w)
{
    for (int k = 0; k < w->count; k++)
        printf("%8.4f %s %d\n", w->events[k].t, kind_name[w->events[k].kind], w->events[k].pass);
}

/* Every finished pass on screen (docs/views.md, "Frames"), from the passes that end once the
 * window shows its first image: (1) each has a presented frame within LATENCY x f of its end, f
 * the machine's slowdown (see below); (2) the frames presented from the first such pass to 0.1 s
 * after the last, each the first after a pass ended, are at least 0.9 of the passes, counted at
 * most 60 a second (a pass that ends less than 1/60 s after the last counted one shares its
 * display frame; in a sanitizer's build, `sanitized`, less than LATENCY x f).
 *
 * The bounds: the window presents each new frame as it comes, a display frame (1/60 s) after the
 * last at the soonest, later only while a presentation costs more than half of that (PRESENT_SHARE),
 * and never more than 0.1 s after the last one (PRESENT_LATEST); at 640x480 a presentation costs
 * 2-4 ms of the GL thread (docs/performance.md) against passes 30-100 ms apart, so that on a quiet
 * machine every counted pass is presented, within a few ms. The GL thread shares two cores with
 * two render threads and llvmpipe's; with other jobs on the machine it waits for a core as any
 * thread does, which `slowdown` measures before the run and after it (the larger counts; the
 * latter counts the run's own threads too, three on two cores, which loosens it by a third at
 * most on a quiet machine): a wait of LATENCY x f leaves the window its 0.1 s at the machine's
 * speed of the moment, and a window that lets passes wait for seconds fails at any load. The 0.9 is
 * the target: with the window's rule only passes less than a display frame apart (the
 * adaptive tail's, which the counting at 60 a second merges) share a presentation. A sanitizer's
 * build encodes and copies a frame in a fifth of a second (the window's code instrumented), so
 * that its presentations come up to the window's 0.1 s apart, and passes closer than the bound
 * on their wait share one. */
static const double LATENCY = 0.1;

static int check_frames(struct watch *w, double f, bool sanitized)
{
    double display_frame = sanitized ? LATENCY * f : 1.0 / 60.0;
    double image = first_after(w, PRESENTED, 0.0);
    if (isnan(image)) {
        printf("FAIL: no frame presented\n");
        return 1;
    }
    int passes = 0, counted = 0, late = 0, last_pass = -1;
    double counted_at = -1.0, first = NAN, last = NAN, worst = 0.0;
    for (int k = 0; k < w->count; k++) {
        const struct event *e = &w->events[k];
        if (e->kind != PASS || e->t < image)
            continue;
        passes++;
        first = isnan(first) ? e->t : first;
        last = e->t;
        last_pass = e->pass;
        if (counted_at < 0.0 || e->t - counted_at >= display_frame) {
            counted++;
            counted_at = e->t;
        }
        double shown = first_after(w, PRESENTED, e->t) - e->t;
        worst = isnan(shown) || shown > worst ? shown : worst;
        late += !(shown <= LATENCY * f);
    }
    /* Frames presented after a pass ended since the frame before (a clock tick's does not count). */
    int presented = 0;
    bool fresh = false;
    for (int k = 0; k < w->count; k++) {
        const struct event *e = &w->events[k];
        fresh = fresh || (e->kind == PASS && e->t >= image);
        if (e->kind == PRESENTED && e->t >= first && e->t <= last + 0.1 && fresh) {
            presented++;
            fresh = false;
        }
    }
    printf("frames: %d passes from %.3f s (up to pass %d), %d at most one a %.3f s display frame, %d frames "
           "presented by %.3f s; slowest pass to screen %.3f s (slowdown %.2f)\n", passes, first, last_pass, counted,
           display_frame, presented, last + 0.1, worst, f);
    int failed = 0;
    if (passes < 10) {
        printf("FAIL: only %d passes ended after the first image: nothing to judge\n", passes);
        failed = 1;
    }
    if (presented < 0.9 * counted) {
        printf("FAIL: %d frames presented for %d passes (at most one a display frame): below 0.9\n", presented,
               counted);
        failed = 1;
    }
    if (late) {
        printf("FAIL: %d passes reached the screen later than %.3f s (slowest %.3f s)\n", late, LATENCY * f, worst);
        failed = 1;
    }
    return failed;
}

/* Sends the key named by keysym to the window (focused first), or, for "close", the window
 * manager's WM_DELETE_WINDOW, as a close button does. */
static void press(struct watch *w, const char *key)
{
    Display *dpy = w->dpy;
    if (strcmp(key, "close") == 0) {
        XEvent e = {.xclient = {.type = ClientMessage, .window = w->window, .format = 32,
                                .message_type = XInternAtom(dpy, "WM_PROTOCOLS", False)}};
        e.xclient.data.l[0] = (long)XInternAtom(dpy, "WM_DELETE_WINDOW", False);
        e.xclient.data.l[1] = CurrentTime;
        XSendEvent(dpy, w->window, False, NoEventMask, &e);
    } else {
        XSetInputFocus(dpy, w->window, RevertToParent, CurrentTime);
        KeyCode code = XKeysymToKeycode(dpy, XStringToKeysym(key));
        XTestFakeKeyEvent(dpy, code, True, 0);
        XTestFakeKeyEvent(dpy, code, False, 0);
    }
    XFlush(dpy);
    note(w, KEY, 0);
}

/* A window at once and keys during any pass, with passes that last minutes (--spppp 4096):
 * (1) a frame presented within OPEN x f of the start; (2) A (antialiasing off: a restart, whose
 * preview comes at once) presents a frame within KEYS x f while the first pass runs; (3) `key`
 * ends the process within END x f, cutting the pass in flight at a tile boundary.
 *
 * The bounds: the targets (0.5 s to an image, 0.2 s to the end) at the machine's speed of
 * the moment, f as for check_frames: the window opens on free cores (the renderer waits for it),
 * and what it waits for then is its own GL's start (about 0.15 s of CPU under Xvfb) and the
 * first preview; the end waits for the tiles in flight (16x16 pixels of 4096 samples: about
 * 0.05 s of a thread at 640x480), then frees the GL, tracer and scene. The key's bound is the
 * end's: its restart aborts the pass at a tile boundary as the end does, and the first preview
 * of 640x480 takes a few ms. */
static const double OPEN = 0.5, KEYS = 0.2, END = 0.2;

/* What check_start measured: seconds from the start to the first image, from A to its frame,
 * from `key` to the end (NAN: never). */
struct start_times {
    double image, answer, ended;
};

static void measure_start(struct watch *w, const char *key, double f, struct start_times *t)
{
    watch_until(w, 5.0 * f, PRESENTED, 0.0);
    printf("start: window mapped at %.3f s\n", first_after(w, MAPPED, 0.0));
    t->image = first_after(w, PRESENTED, 0.0);
    t->answer = t->ended = NAN;
    if (isnan(t->image))
        return;
    /* Each key once the threads are well into the bunny's tiles (the top rows are sky, quick). */
    watch_until(w, t->image + 1.0, PRESENTED, NAN);
    double pressed = now() - w->t0;
    press(w, "a");
    watch_until(w, pressed + 5.0 * f, PRESENTED, pressed);
    t->answer = first_after(w, PRESENTED, pressed) - pressed;
    watch_until(w, pressed + 1.5, PRESENTED, NAN);
    pressed = now() - w->t0;
    press(w, key);
    watch_until(w, pressed + 5.0 * f, EXITED, pressed);
    t->ended = first_after(w, EXITED, pressed) - pressed;
}

static int check_start(const struct start_times *t, const char *key, double f)
{
    printf("start: first image at %.3f s, A on screen in %.3f s, %s ended the run in %.3f s (slowdown %.2f)\n",
           t->image, t->answer, key, t->ended, f);
    int failed = 0;
    if (!(t->image <= OPEN * f)) {
        printf("FAIL: no image within %.3f s of the start\n", OPEN * f);
        failed = 1;
    }
    if (!(t->answer <= KEYS * f)) {
        printf("FAIL: A was not on screen within %.3f s\n", KEYS * f);
        failed = 1;
    }
    if (!(t->ended <= END * f)) {
        printf("FAIL: %s did not end the run within %.3f s\n", key, END * f);
        failed = 1;
    }
    return failed;
}

int main(int argc, char **argv)
{
    int first = 2;
    bool log = false;
    double patience = 1.0;
    for (;;) {
        if (first < argc && strcmp(argv[first], "--log") == 0)
            log = true, first++;
        else if (first + 1 < argc && strcmp(argv[first], "--patience") == 0)
            patience = atof(argv[first + 1]), first += 2;
        else
            break;
    }
    bool frames = argc > 1 && strcmp(argv[1], "frames") == 0, starts = argc > 1 && strcmp(argv[1], "start") == 0;
    const char *key = starts && first < argc ? argv[first++] : NULL;
    if ((!frames && !starts) || first >= argc) {
        fprintf(stderr, "usage: window_frames frames [--log] [--patience N] AOVIEW ARGS...\n"
                        "       window_frames start [--log] [--patience N] q|Escape|close AOVIEW ARGS...\n");
        return 2;
    }
    static struct watch w;
    if (!(w.dpy = XOpenDisplay(NULL))) {
        printf("SKIP: no X display\n");
        return 77;
    }
    int error, xtest[4];
    if (!XDamageQueryExtension(w.dpy, &w.damage_event, &error) ||
        !XTestQueryExtension(w.dpy, &xtest[0], &xtest[1], &xtest[2], &xtest[3])) {
        printf("SKIP: the X server lacks DAMAGE or XTEST\n");
        return 77;
    }
    double f = slowdown() * (patience > 1.0 ? patience : 1.0);
    if (!start(&w, argv + first, argc - first))
        return 1;
    int failed;
    if (frames) {
        /* Until no pass has ended for 2 s (the run is over) or 60 s have passed. */
        for (;;) {
            double t = now() - w.t0, last = 0.0;
            for (int k = 0; k < w.count; k++)
                last = w.events[k].kind == PASS ? w.events[k].t : last;
            if (w.exited || t > 60.0 * patience || (last > 0.0 && t - last > 2.0 * patience))
                break;
            poll_once(&w);
        }
        finish(&w);
        failed = check_frames(&w, fmax(f, slowdown() * patience), patience > 1.0);
    } else {
        struct start_times t;
        measure_start(&w, key, f, &t);
        finish(&w);
        failed = check_start(&t, key, fmax(f, slowdown() * patience));
    }
    if (log)
        print_log(&w);
    XCloseDisplay(w.dpy);
    return failed;
}
