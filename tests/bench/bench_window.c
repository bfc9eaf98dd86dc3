/* Benchmark: the real window as a user meets it, on the X display it is run under (Xvfb, Mesa's
 * software GL). For 1920x1080 and 3840x2160, one line:
 *   WxH: orbit F frames/s presented, idle window R Mrays/s against headless H (ratio)
 * F: the frames the window presents while a left drag moves the pointer every 16 ms, counted at
 * the X server (DAMAGE events on the window, one a swap) over the drag's seconds, and of those the
 * ones whose image differs from the one before (a row through the image's middle, read back from
 * the server). R: the window left alone for --seconds, per its --stats (the last run's last row);
 * H: the same run with --headless, started right after it. Medians of --rounds rounds (window and
 * headless interleaved, so that the machine's load drifts over both), and the ratio R / H of the
 * two medians printed. Then the CPU time of the idle window's GL thread (and llvmpipe's) and of
 * the X server against its render threads', which no other load on the machine changes.
 * Run under Xvfb with room for a 3840x2160 window (the window takes at most 90 % of the screen):
 *   xvfb-run -a -s "-screen 0 4320x2440x24" ./build/tests/bench_window [--aoview build/aoview] [SCENE]
 * or ninja -C build bench-window. Exits 77 without a display. Asserts nothing. */
#include <dirent.h>
#include <math.h>
#include <signal.h>
#include <spawn.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <X11/Xlib.h>
#include <X11/Xutil.h>
#include <X11/extensions/XTest.h>
#include <X11/extensions/Xdamage.h>

#include "bench_util.h"
#include "config.h"

extern char **environ;

/* The drag: a pointer move every STEP seconds of MOVE pixels, for ORBIT seconds. */
static const double STEP = 0.016, ORBIT = 4.0, SETTLE = 1.0;
enum { MOVE = 3 };

struct options {
    const char *aoview, *scene;
    double seconds;       /* of each idle and headless run */
    int rounds;
};

static void sleep_seconds(double s)
{
    if (s <= 0.0)
        return;
    struct timespec ts = {(time_t)s, (long)((s - floor(s)) * 1e9)};
    nanosleep(&ts, NULL);
}

/* Starts aoview with the arguments (NULL-terminated after the binary), stdout and stderr to
 * /dev/null unless AO_BENCH_VERBOSE is set; its pid. */
static pid_t launch(const char *const *argv)
{
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (!getenv("AO_BENCH_VERBOSE")) {
        posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", 1, 0);
        posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", 1, 0);
    }
    pid_t pid;
    if (posix_spawn(&pid, argv[0], &actions, NULL, (char *const *)argv, environ) != 0) {
        fprintf(stderr, "bench_window: cannot start %s\n", argv[0]);
        exit(1);
    }
    posix_spawn_file_actions_destroy(&actions);
    return pid;
}

static void end(pid_t pid)
{
    kill(pid, SIGTERM);
    waitpid(pid, NULL, 0);
}

/* Window w's title (_NET_WM_NAME, UTF-8) into out; "" when it has none. */
static void title_of(Display *dpy, Window w, char *out, size_t size)
{
    Atom type, name = XInternAtom(dpy, "_NET_WM_NAME", False);
    int format;
    unsigned long count, after;
    unsigned char *data = NULL;
    out[0] = '\0';
    if (XGetWindowProperty(dpy, w, name, 0, 1024, False, AnyPropertyType, &type, &format, &count, &after, &data) ==
            Success && data && format == 8)
        snprintf(out, size, "%.*s", (int)count, (const char *)data);
    if (data)
        XFree(data);
}

/* The first viewable top-level window whose title begins "aoview" and holds `want`, or None. */
static Window find_window(Display *dpy, const char *want)
{
    Window root = DefaultRootWindow(dpy), parent, *children = NULL, found = None;
    unsigned count = 0;
    if (!XQueryTree(dpy, root, &root, &parent, &children, &count))
        return None;
    for (unsigned k = 0; k < count && !found; k++) {
        XWindowAttributes a;
        char title[1024];
        if (!XGetWindowAttributes(dpy, children[k], &a) || a.map_state != IsViewable)
            continue;
        title_of(dpy, children[k], title, sizeof title);
        if (strncmp(title, "aoview", 6) == 0 && strstr(title, want))
            found = children[k];
    }
    if (children)
        XFree(children);
    return found;
}

/* Waits up to `seconds` for aoview's window whose title holds `want`; None on time out. */
static Window wait_window(Display *dpy, const char *want, double seconds)
{
    for (double t0 = bench_now(); bench_now() - t0 < seconds; sleep_seconds(0.05)) {
        Window w = find_window(dpy, want);
        if (w)
            return w;
    }
    return None;
}

/* A hash of the row through the middle of window w (its image's middle at any letterboxing). */
static uint64_t middle_row(Display *dpy, Window w, int width, int height)
{
    XImage *row = XGetImage(dpy, w, 0, height / 2, (unsigned)width, 1, AllPlanes, ZPixmap);
    if (!row)
        return 0;
    uint64_t h = 1469598103934665603ull;
    for (int x = 0; x < width; x++) {
        h ^= (uint64_t)XGetPixel(row, x, 0) & 0xffffff;
        h *= 1099511628211ull;
    }
    XDestroyImage(row);
    return h;
}

/* Counts what w presents while `seconds` pass: damage reports ending a request (presented), and
 * those after which the middle row differs (distinct); during a left drag when `drag`. */
static void count_frames(Display *dpy, Window w, int width, int height, int damage_event, bool drag, double seconds,
                         int *presented, int *distinct)
{
    Damage damage = XDamageCreate(dpy, w, XDamageReportRawRectangles);
    int x0, y0;
    Window child;
    XTranslateCoordinates(dpy, w, DefaultRootWindow(dpy), width / 2, height / 2, &x0, &y0, &child);
    int x = x0, direction = 1;
    if (drag) {
        XTestFakeMotionEvent(dpy, -1, x, y0, 0);
        XTestFakeButtonEvent(dpy, 1, True, 0);
    }
    XSync(dpy, False);
    /* the press itself restarts nothing; the first move does */
    uint64_t last = middle_row(dpy, w, width, height);
    *presented = *distinct = 0;
    double t0 = bench_now(), next = t0;
    while (bench_now() - t0 < seconds) {
        if (drag && bench_now() >= next) {
            /* back and forth across a quarter of the width, so the pointer stays in the window */
            if (abs(x + direction * MOVE - x0) > width / 8)
                direction = -direction;
            x += direction * MOVE;
            XTestFakeMotionEvent(dpy, -1, x, y0, 0);
            XFlush(dpy);
            next += STEP;
        }
        while (XPending(dpy)) {
            XEvent e;
            XNextEvent(dpy, &e);
            if (e.type != damage_event + XDamageNotify)
                continue;
            XDamageNotifyEvent *d = (XDamageNotifyEvent *)&e;
            if (d->more)
                continue;
            ++*presented;
            uint64_t now = middle_row(dpy, w, width, height);
            *distinct += now != last;
            last = now;
        }
        sleep_seconds(fmin(0.001, next - bench_now()));
    }
    if (drag)
        XTestFakeButtonEvent(dpy, 1, False, 0);
    XDamageDestroy(dpy, damage);
    XSync(dpy, False);
}

/* The mrays_per_s of the last row of the last run (pass numbers start again at 1) in a --stats
 * file; NAN when it has none. */
static double last_rate(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return NAN;
    char line[512];
    double rate = NAN;
    if (fgets(line, sizeof line, f))   /* the header: pass,spp,seconds,eye,shadow,mrays_per_s,... */
        while (fgets(line, sizeof line, f)) {
            double values[6];
            if (sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf", &values[0], &values[1], &values[2], &values[3], &values[4],
                       &values[5]) == 6)
                rate = values[5];
        }
    fclose(f);
    return rate;
}

/* The rate of the --stats row whose seconds first reach `seconds`, waiting for it; NAN on time out. */
static double rate_at(const char *path, double seconds, double patience)
{
    for (double t0 = bench_now(); bench_now() - t0 < patience; sleep_seconds(0.1)) {
        FILE *f = fopen(path, "r");
        if (!f)
            continue;
        char line[512];
        double rate = NAN;
        bool header = fgets(line, sizeof line, f) != NULL;
        while (header && fgets(line, sizeof line, f)) {
            double v[6];
            if (sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5]) == 6 &&
                v[2] >= seconds) {
                rate = v[5];
                break;
            }
        }
        fclose(f);
        if (!isnan(rate))
            return rate;
    }
    return NAN;
}

/* CPU seconds (user and system) of a /proc stat file's process or thread; 0 when unreadable. */
static double cpu_seconds(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return 0.0;
    char line[1024];
    double seconds = 0.0;
    if (fgets(line, sizeof line, f)) {
        const char *rest = strrchr(line, ')'); /* past the name, which may hold spaces */
        unsigned long utime, stime;
        if (rest && sscanf(rest + 2, "%*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %lu %lu", &utime, &stime) == 2)
            seconds = (double)(utime + stime) / (double)sysconf(_SC_CLK_TCK);
    }
    fclose(f);
    return seconds;
}

/* The pid of the X server of this display (an Xvfb whose arguments name it), or 0. */
static long x_server(void)
{
    const char *display = getenv("DISPLAY");
    long found = 0;
    DIR *proc = opendir("/proc");
    for (struct dirent *e; proc && display && !found && (e = readdir(proc));) {
        char path[64], args[4096];
        long pid = strtol(e->d_name, NULL, 10);
        snprintf(path, sizeof path, "/proc/%ld/cmdline", pid);
        FILE *f = pid > 0 ? fopen(path, "r") : NULL;
        size_t n = f ? fread(args, 1, sizeof args - 1, f) : 0;
        if (f)
            fclose(f);
        args[n] = '\0';
        if (!strstr(args, "Xvfb"))
            continue;
        for (size_t k = 0; k < n && !found; k += strlen(args + k) + 1)
            found = strcmp(args + k, display) == 0 ? pid : 0;
    }
    if (proc)
        closedir(proc);
    return found;
}

/* The CPU seconds aoview's process pid has spent drawing (its main thread, the GL thread, and
 * llvmpipe's) into gl, and rendering (every other thread) into render. */
static void cpu_split(pid_t pid, double *gl, double *render)
{
    char path[96];
    snprintf(path, sizeof path, "/proc/%d/task", (int)pid);
    *gl = *render = 0.0;
    DIR *tasks = opendir(path);
    for (struct dirent *e; tasks && (e = readdir(tasks));) {
        if (e->d_name[0] == '.')
            continue;
        char stat[512], comm[512], name[64] = "";
        snprintf(stat, sizeof stat, "%s/%s/stat", path, e->d_name);
        snprintf(comm, sizeof comm, "%s/%s/comm", path, e->d_name);
        FILE *f = fopen(comm, "r");
        if (f && !fgets(name, sizeof name, f))
            name[0] = '\0';
        if (f)
            fclose(f);
        double seconds = cpu_seconds(stat);
        if (atoi(e->d_name) == (int)pid || strncmp(name, "llvmpipe", 8) == 0)
            *gl += seconds;
        else
            *render += seconds;
    }
    if (tasks)
        closedir(tasks);
}

static void measure(Display *dpy, int damage_event, const struct options *o, int width, int height)
{
    char size[32], seconds[32], stats[2][64];
    snprintf(size, sizeof size, "%dx%d", width, height);
    snprintf(seconds, sizeof seconds, "%g", o->seconds);
    snprintf(stats[0], sizeof stats[0], "/tmp/bench_window_%d_w.csv", (int)getpid());
    snprintf(stats[1], sizeof stats[1], "/tmp/bench_window_%d_h.csv", (int)getpid());
    double orbit[16], distinct[16], idle[16], headless[16], share[16];
    char x_stat[64];
    snprintf(x_stat, sizeof x_stat, "/proc/%ld/stat", x_server());
    int rounds = o->rounds < 16 ? o->rounds : 16;
    for (int round = 0; round < rounds; round++) {
        /* The orbit: a run that never ends by itself. */
        const char *orbit_argv[] = {o->aoview, "--size", size, "--spp", "1000000", "--pixel-size", "1", o->scene, NULL};
        pid_t pid = launch(orbit_argv);
        Window w = wait_window(dpy, "spp", 30.0);
        if (!w) {
            fprintf(stderr, "bench_window: no window for %s\n", size);
            end(pid);
            exit(1);
        }
        sleep_seconds(SETTLE);
        XWindowAttributes a;
        XGetWindowAttributes(dpy, w, &a);
        if (a.width != width || a.height != height)
            fprintf(stderr, "bench_window: the window is %dx%d, not %s: the screen is too small\n", a.width,
                    a.height, size);
        int presented, changed;
        count_frames(dpy, w, a.width, a.height, damage_event, true, ORBIT, &presented, &changed);
        orbit[round] = presented / ORBIT;
        distinct[round] = changed / ORBIT;
        end(pid);

        /* The window left alone, then headless: both for the same seconds. */
        /* --spp high enough that neither run ends before its seconds (at 1920x1080 adaptive passes of 8
         * spp converge the bunny's 256 spp within 10 s, and the idle row at 10 s never came). */
        const char *idle_argv[] = {o->aoview, "--size",  size,     "--time",  seconds, "--spp",
                                   "1048576",  "--pixel-size", "1", "--stats", stats[0], o->scene, NULL};
        remove(stats[0]);
        double x_before = cpu_seconds(x_stat), gl, render;
        pid = launch(idle_argv);
        idle[round] = rate_at(stats[0], o->seconds, o->seconds + 60.0);
        cpu_split(pid, &gl, &render);
        share[round] = (gl + cpu_seconds(x_stat) - x_before) / render;
        end(pid);
        char out[80];
        snprintf(out, sizeof out, "/tmp/bench_window_%d.pfm", (int)getpid());
        const char *run_argv[] = {o->aoview, "--headless", "-q", "--size", size, "--time", seconds, "--spp", "1048576",
                                  "--stats", stats[1], "-o", out, o->scene, NULL};
        remove(stats[1]);
        pid = launch(run_argv);
        waitpid(pid, NULL, 0);
        headless[round] = last_rate(stats[1]);
        remove(out);
        if (getenv("AO_BENCH_VERBOSE"))
            printf("  round %d: orbit %.1f presented (%.1f distinct), idle %.2f, headless %.2f, drawing %.1f %%\n",
                   round + 1, orbit[round], distinct[round], idle[round], headless[round], 100.0 * share[round]);
    }
    remove(stats[0]);
    remove(stats[1]);
    double idle_median = bench_median(idle, rounds), headless_median = bench_median(headless, rounds);
    printf("%s: orbit %.0f frames/s presented, idle window %.1f Mrays/s against headless %.1f (%.2f)\n", size,
           bench_median(orbit, rounds), idle_median, headless_median, idle_median / headless_median);
    printf("%s: %.0f distinct frames/s of the orbit; the idle window's drawing and X server took %.1f %% of the CPU "
           "time of its render threads\n", size, bench_median(distinct, rounds), 100.0 * bench_median(share, rounds));
    fflush(stdout);
}

int main(int argc, char **argv)
{
    struct options o = {.aoview = "aoview", .scene = AO_DEFAULT_SCENE, .seconds = 10.0, .rounds = 3};
    for (int k = 1; k < argc; k++) {
        if (strcmp(argv[k], "--aoview") == 0 && k + 1 < argc)
            o.aoview = argv[++k];
        else if (strcmp(argv[k], "--seconds") == 0 && k + 1 < argc)
            o.seconds = atof(argv[++k]);
        else if (strcmp(argv[k], "--rounds") == 0 && k + 1 < argc)
            o.rounds = atoi(argv[++k]);
        else if (argv[k][0] != '-')
            o.scene = argv[k];
        else {
            fprintf(stderr, "usage: bench_window [--aoview PATH] [--seconds S] [--rounds N] [SCENE]\n");
            return 2;
        }
    }
    Display *dpy = XOpenDisplay(NULL);
    if (!dpy) {
        printf("SKIP: no X display (run under xvfb-run -a -s \"-screen 0 4320x2440x24\")\n");
        return 77;
    }
    int damage_event, damage_error, xtest[4];
    if (!XDamageQueryExtension(dpy, &damage_event, &damage_error) ||
        !XTestQueryExtension(dpy, &xtest[0], &xtest[1], &xtest[2], &xtest[3])) {
        printf("SKIP: the X server lacks DAMAGE or XTEST\n");
        return 77;
    }
    char cpu[128] = "unknown CPU";
    FILE *f = fopen("/proc/cpuinfo", "r");
    for (char line[256]; f && fgets(line, sizeof line, f);)
        if (strncmp(line, "model name", 10) == 0 && strchr(line, ':')) {
            snprintf(cpu, sizeof cpu, "%s", strchr(line, ':') + 2);
            cpu[strcspn(cpu, "\n")] = '\0';
            break;
        }
    if (f)
        fclose(f);
    printf("%s, %s, %ld cores, %g s idle runs, medians of %d rounds\n", o.scene, cpu, sysconf(_SC_NPROCESSORS_ONLN),
           o.seconds, o.rounds);
    fflush(stdout);
    measure(dpy, damage_event, &o, 1920, 1080);
    measure(dpy, damage_event, &o, 3840, 2160);
    XCloseDisplay(dpy);
    return 0;
}
