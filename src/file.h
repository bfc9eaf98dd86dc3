/* Whole-file reading shared by the scene and mesh loaders; opening a stream output (--stats). */
#ifndef AO_FILE_H
#define AO_FILE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

/* Reads the regular file at path into a malloc'd NUL-terminated buffer the caller frees, its
 * length (without the NUL) in *size. Refuses directories, FIFOs and devices without blocking; on
 * failure prints one "path: reason" line to stderr and returns false. Any thread. */
bool ao_file_read(const char *path, char **text, size_t *size);

/* Opens path to write a stream into (--stats) without truncating it, so that an existing file is
 * left as it was until the caller writes (it truncates then), and without blocking: a FIFO that
 * no process reads yet is waited for, a little at a time, up to 2 s (a reader started beside
 * aoview), then refused; the descriptor then blocks again, so that a slow reader loses nothing.
 * *created: this call created the file. NULL after one line "what: cannot write path: reason".
 * Main thread (signals end the wait). */
FILE *ao_file_open_output(const char *path, const char *what, bool *created);

#endif
