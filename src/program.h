/* What a program (aoview, aoview-mpi, aoview-exact, the benchmarks) installs around the core, which,
 * being a library as well, installs nothing process-wide itself: the core's messages on stderr. */
#ifndef AO_PROGRAM_H
#define AO_PROGRAM_H

/* Makes stderr the process's sink for the core's messages (ao_text_set_sink), one line each, notes
 * and errors alike. Main thread, first thing in main. */
void ao_program_init(void);

#endif
