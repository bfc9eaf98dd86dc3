/* Shared pieces of the libFuzzer targets: the entry point libFuzzer (or replay.c) calls, and a
 * private scratch directory for the files the loaders must read from disk. */
#ifndef AO_FUZZ_H
#define AO_FUZZ_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Runs one input through the target; aborts on a broken invariant, returns 0 otherwise. */
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* A directory of this process's own, made on first call and removed at exit; aborts on failure. */
const char *fuzz_temp_dir(void);

/* The path of name inside fuzz_temp_dir(), in a static buffer; remembered for removal at exit. */
const char *fuzz_temp_path(const char *name);

/* Replaces the file at path with size bytes of data; aborts on failure. */
void fuzz_write_file(const char *path, const void *data, size_t size);

#endif
