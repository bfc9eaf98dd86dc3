/* What the window needs of Xlib beside GLFW: the handler for a lost connection to the X server
 * (GLFW 3.3 leaves Xlib's, which exits from under the running threads), and the display's name
 * for messages. The only file that includes Xlib is x11.c. */
#ifndef AO_X11_H
#define AO_X11_H

/* Installs aoview's handler for a lost connection in place of Xlib's, which it keeps: on whichever
 * thread's Xlib call notices the loss, one line naming the display and exit status 1 at once.
 * Main thread, before glfwInit. */
void ao_x11_catch_lost_display(void);

/* Puts back the handler ao_x11_catch_lost_display replaced. Main thread, after glfwTerminate. */
void ao_x11_restore(void);

/* The name of the X display a window opens on ($DISPLAY, as Xlib reads it), for messages. */
const char *ao_x11_display_name(void);

#endif
