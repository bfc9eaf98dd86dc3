/* Whole-file reading shared by the scene and mesh loaders (charged to the scene budget, the files
 * read remembered as inputs, big ones mapped), opening a stream output (--stats), and the programs'
 * check that no output is an input or another output. Failures are reported as one line each
 * (ao_text_report). */
#ifndef AO_FILE_H
#define AO_FILE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "budget.h"

/* Reads the regular file at path into a malloc'd NUL-terminated buffer the caller frees, its
 * length (without the NUL) in *size. Refuses directories, FIFOs and devices without blocking; on
 * failure reports one "path: reason" line and returns false. Any thread. */
bool ao_file_read(const char *path, char **text, size_t *size);

/* Opens path to write a stream into (--stats) without truncating it, so that an existing file is
 * left as it was until the caller writes (it truncates then), and without blocking: a FIFO that
 * no process reads yet is waited for, a little at a time, up to 2 s (a reader started beside
 * aoview), then refused; the descriptor then blocks again, so that a slow reader loses nothing.
 * Written through: a symbolic link (its target), a FIFO, a character device (a terminal,
 * /dev/null); refused: a block device, and a regular file no one may write (read-only even for
 * root). *created: this call created the file. NULL after one line "what: cannot write path:
 * reason" (reported). Main thread (signals end the wait). */
FILE *ao_file_open_output(const char *path, const char *what, bool *created);

/* ao_file_read charging the file's size plus one (the NUL) to budget before anything is allocated:
 * a file that does not fit is refused, unread, with "path: N bytes need about ...". The caller
 * gives the bytes back (ao_budget_give(budget, *size + 1)) once it frees the text. Any thread. */
bool ao_file_read_budget(const char *path, struct ao_budget *budget, char **text, size_t *size);

/* ao_file_read_budget without a copy, for big files read once: the file is mapped read-only
 * (*mapped; its pages are the page cache's, so nothing is zeroed or copied), a NUL after it; a
 * file whose length is a whole number of pages (no room for the NUL), that cannot be mapped, or
 * any file while the host has turned mapping off (ao_file_set_mapping), is read. Release it with
 * ao_file_unmap, then give back the charge. Reading a mapped file that another process shrank
 * raises SIGBUS; the core installs no handler: a program's looks the address up with
 * ao_file_mapped_line. Any thread, several at once. */
bool ao_file_map_budget(const char *path, struct ao_budget *budget, const char **text, size_t *size, bool *mapped);

/* Whether ao_file_map_budget maps files (true, as before any call) or reads them all. A host that
 * cannot end the process on a SIGBUS (the Python module) turns mapping off, so that a file shrunk
 * under a load is that load's error ("read error"). Any thread; from the next load on. */
void ao_file_set_mapping(bool on);

/* The line "path: the file shrank while it was being read\n" of the live mapping (ao_file_map_budget,
 * not yet released) that holds address, its length in *length; NULL when none does. Lock-free and
 * async-signal-safe: for a program's SIGBUS handler (si_addr), which the core never installs. */
const char *ao_file_mapped_line(const void *address, size_t *length);

/* Releases what ao_file_map_budget gave (text, size and mapped as it gave them). */
void ao_file_unmap(const char *text, size_t size, bool mapped);

/* Reads the first `length` bytes of the open file fd into a malloc'd buffer (a NUL after them)
 * the caller frees. Refuses, before allocating, what is not a regular file or holds fewer bytes;
 * then returns false with the reason in *why (static text) and prints nothing. Any thread. */
bool ao_file_read_prefix(int fd, size_t length, char **data, const char **why);

/* From now on, every file read through this module (and noted by ao_file_note_input) is remembered
 * as an input of this process, so that no output overwrites it (ao_file_input_name); off until
 * then, so that a library user loading file after file (tests, fuzzers) holds no growing list.
 * Main thread, before loading. */
void ao_file_remember_inputs(void);

/* Records the open file fd as an input this process read (its name for messages: path), when
 * inputs are remembered. Any thread. */
void ao_file_note_input(int fd, const char *path);

/* A file that a program's command line names, for ao_file_check_roles: its role in messages ("-o",
 * "--stats", "the scene", "--reference"), its path, and whether the run writes it. */
struct ao_file_role {
    const char *role, *path;
    bool written;
};

/* Before loading: true when no file of files[0, count) that the run writes is also a later one,
 * compared as files (an existing one by its identity, through links; one to be made by its
 * folder's identity and its name there); else false after one line naming both ("-o: x.pfm is also
 * --stats (x.pfm): each output needs a file of its own", or "... aoview does not overwrite its
 * inputs" where the later one is read). The outputs come first. What every program checks. Main
 * thread. */
bool ao_file_check_roles(const struct ao_file_role *files, size_t count);

/* After loading: true when the output of this role at path (fd >= 0: the open file fd, as it is
 * now) does not exist or is none of the inputs read since ao_file_remember_inputs (meshes, glTF
 * buffers); else false after one line "role: path is a file the scene reads (input): aoview does
 * not overwrite its inputs". Main thread. */
bool ao_file_check_not_read(const char *role, const char *path, int fd);

#endif
