/* Whole-file reading shared by the scene and mesh loaders. */
#ifndef AO_FILE_H
#define AO_FILE_H

#include <stdbool.h>
#include <stddef.h>

/* Reads the regular file at path into a malloc'd NUL-terminated buffer the caller frees, its
 * length (without the NUL) in *size. Refuses directories, FIFOs and devices without blocking; on
 * failure prints one "path: reason" line to stderr and returns false. Any thread. */
bool ao_file_read(const char *path, char **text, size_t *size);

#endif
