#!/usr/bin/env python3
"""Where a run's time goes, pass by pass: runs the measuring build of aoview (meson option
phases=true, whose every pass says its phases as a note) to 1 % estimated error per size and seed,
and prints per size a markdown table of each pass's phases in ms, the median over the seeds, and
the run's totals (docs/performance.md#where-a-small-runs-time-goes).

  pass_phases.py [--aoview BIN] [--sizes WxH,...] [--seeds N] [--threads N] [--args 'AOVIEW ARGS']
                 [SCENE]

--aoview: the measuring build's aoview (default build-phases/aoview); --sizes default
160x120,320x240,640x480; --seeds default 5 (seeds 1 to N, the sizes taken in turn for each seed, so
that a change in the machine's load falls on all of them); --threads default 2; SCENE default the
bunny.
"""
import argparse
import os
import shlex
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The note's fields after "phases:": pass, rays, then the phases (ms).
PHASES = ('ms', 'plan', 'start', 'wake', 'trace', 'add', 'idle', 'other', 'survey', 'publish')
# The columns printed: the pass's own time, the mean over the team of each thread's time before its
# job (the render thread's start and the workers' wake-up), tracing, adding, idling at the end, the
# rest; then the render thread's work between passes.
COLUMNS = ('ms', 'before', 'wake', 'trace', 'add', 'idle', 'other', 'survey', 'publish', 'plan')


def run(aoview, size, seed, threads, args, scene, work):
    """One run to 1 % estimated error; its passes as dicts of the note's fields."""
    command = [aoview, '--headless', '-q', '--threads', str(threads), '--size', size, '--seed', str(seed),
               '--spp', str(1 << 20), '--target-error', '0.01', '-o', os.path.join(work, 'run.pfm')] + args + [scene]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit('pass_phases.py: %s failed (exit %d): %s' % (shlex.join(command), done.returncode,
                                                              done.stderr.strip()))
    passes = []
    for line in done.stderr.splitlines():
        if line.startswith('phases: '):
            fields = line.split()[1:]
            values = dict(zip(fields[0::2], fields[1::2]))
            passes.append({k: float(v) for k, v in values.items()})
    if not passes:
        sys.exit('pass_phases.py: %s says no phases: is it the measuring build (-Dphases=true)?' % aoview)
    for p in passes:
        # The mean thread's time before its job: the render thread's start, and the workers' wake-up
        # on top of it, shared among the team's threads.
        p['before'] = p['start'] + p['wake'] * (threads - 1) / threads
    return passes


def table(size, runs, threads):
    """The markdown table of one size: per pass the medians over the runs that have it, then the
    totals (the median over the runs of each run's sums)."""
    most = max(len(r) for r in runs)
    lines = ['%s, %d threads, medians of %d runs (ms; in the pass, each thread\'s mean):\n\n' % (
                 size, threads, len(runs)),
             '| pass | rays | pass | before | (wake) | trace | add | idle | other | Mrays/s | survey | publish '
             '| plan |\n', '|' + '---|' * 13 + '\n']

    def row(label, values):
        cells = ['%.0f' % values['rays']] + ['%.3f' % values[c] for c in COLUMNS[:7]]
        cells.append('%.1f' % (values['rays'] / values['ms'] / 1e3))
        cells += ['%.3f' % values[c] for c in COLUMNS[7:]]
        lines.append('| %s | %s |\n' % (label, ' | '.join(cells)))

    for n in range(most):
        have = [r[n] for r in runs if len(r) > n]
        row('%d%s' % (n + 1, '' if len(have) == len(runs) else ' (%d runs)' % len(have)),
            {k: statistics.median(p[k] for p in have) for k in ('rays',) + COLUMNS})
    sums = [{k: sum(p[k] for p in r) for k in ('rays',) + COLUMNS} for r in runs]
    row('all', {k: statistics.median(s[k] for s in sums) for k in ('rays',) + COLUMNS})
    return ''.join(lines) + '\n'


def main():
    parser = argparse.ArgumentParser(usage=__doc__)
    parser.add_argument('--aoview', default=os.path.join(ROOT, 'build-phases', 'aoview'))
    parser.add_argument('--sizes', default='160x120,320x240,640x480')
    parser.add_argument('--seeds', type=int, default=5)
    parser.add_argument('--threads', type=int, default=2)
    parser.add_argument('--args', default='')
    parser.add_argument('scene', nargs='?', default=os.path.join(ROOT, 'assets', 'scenes', 'bunny.scene'))
    a = parser.parse_args()
    if not os.access(a.aoview, os.X_OK):
        sys.exit('pass_phases.py: %s is not built (meson setup build-phases -Dphases=true && ninja -C '
                 'build-phases aoview)' % a.aoview)
    sizes = a.sizes.split(',')
    runs = {s: [] for s in sizes}
    with tempfile.TemporaryDirectory() as work:
        for seed in range(1, a.seeds + 1):
            for size in sizes:
                runs[size].append(run(a.aoview, size, seed, a.threads, shlex.split(a.args), a.scene, work))
    load = ' '.join(open('/proc/loadavg').read().split()[:3])
    print('`%s` (load average %s at the end)\n' % (shlex.join(sys.argv), load))
    for size in sizes:
        print(table(size, runs[size], a.threads), end='')


if __name__ == '__main__':
    main()
