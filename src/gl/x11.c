/* What the window needs of Xlib; see x11.h. */
#include "x11.h"

#include <stdatomic.h>
#include <stdio.h>
#include <unistd.h>

#include <X11/Xlib.h>

/* Xlib's handler for a broken connection (the X server died or went away), on whichever thread's
 * Xlib call noticed it (the GL thread's, or the render thread's glfwPostEmptyEvent): one line, and
 * exit status 1 at once, because no way back is sound: after the handler returns Xlib calls
 * exit(1) itself, from under the running threads, after printing its own message; and an exit
 * handler (XSetIOErrorExitHandler) that returns resumes the Xlib call with the display's lock
 * released twice (libX11 1.8 _XIOError; ThreadSanitizer reports it), while GLFW 3.3's
 * glfwWaitEvents spins for ever on the dead connection. Nothing is lost: stats rows are flushed
 * per pass, screenshots are renamed into place whole. */
static int on_io_error(Display *display)
{
    static atomic_flag reported = ATOMIC_FLAG_INIT;
    if (atomic_flag_test_and_set(&reported))
        for (;;)
            pause();   /* another thread is exiting */
    fprintf(stderr, "aoview: lost the connection to the X display %s\n", DisplayString(display));
    _exit(1);
}

/* The handler ao_x11_catch_lost_display replaced. */
static XIOErrorHandler replaced;

void ao_x11_catch_lost_display(void)
{
    replaced = XSetIOErrorHandler(on_io_error);
}

void ao_x11_restore(void)
{
    XSetIOErrorHandler(replaced);
}

const char *ao_x11_display_name(void)
{
    return XDisplayName(NULL);
}
