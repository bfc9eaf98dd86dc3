/* What a program (aoview, aoview-mpi, aoview-exact, the benchmarks) installs around the core, which,
 * being a library as well, installs nothing process-wide itself: the core's messages on stderr, and
 * the end of the process when a file the core mapped shrinks under it. */
#ifndef AO_PROGRAM_H
#define AO_PROGRAM_H

/* Makes stderr the process's sink for the core's messages (ao_text_set_sink), one line each, notes
 * and errors alike, and installs the SIGBUS handler: a SIGBUS in a file the core mapped
 * (ao_file_mapped_line), which another process shrank while it was read, ends the process with
 * that file's one line ("path: the file shrank while it was being read") and status 1; any other
 * SIGBUS does what it does by default. Main thread, first thing in main. */
void ao_program_init(void);

#endif
