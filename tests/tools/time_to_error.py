#!/usr/bin/env python3
"""Time to error: for every configuration of aoview, the render seconds (the `seconds` column of
--stats) until the RMSE against a reference falls to 10 %, 3 %, 1 % and 0.5 % of the reference's
mean, per scene and image size, the median over seeds; writes time-to-error.md (the tables) and
time-to-error.csv (every run) into --out. See docs/time-to-error.md for what the figures mean.

  time_to_error.py [--aoview BIN] [--exact BIN] [--sizes WxH,...] [--seeds N] [--cap S]
                   [--ref-spp N] [--work DIR] [--out DIR] [--quick] [--config NAME=ARGS]...
                   [--large WxH] [--large-config NAME=ARGS]... [--large-ref-spp N] [--steady-spp N] SCENE...

--config adds a configuration: NAME and the aoview arguments it adds (any, quoted as in a shell;
empty for the binary's defaults; `--binary BIN` first runs another aoview binary, e.g. an older
build); without any, the set in DEFAULT_CONFIGS. The ratios are the median time of the first
configuration (the baseline) over each configuration's. --quick: only the first size, one seed,
written into the work directory unless --out is given, and no large size.

Every table gives each configuration's ray rate over its run to 1 % RMSE (eye and AO rays over
render seconds, at the crossing). For the first SCENE at each of --sizes, every configuration also
renders --steady-spp samples a pixel (default 1024; 0: not) to the end, once per seed, and the
table gives its rate over that run and the ratio of the two.

At the large size (--large, default 1920x1080; empty for none) only the first SCENE runs, with
the configurations of --large-config (default LARGE_CONFIGS), to 1 % alone: the render seconds to
1 % RMSE and to 1 % estimated error (the `error` column of --stats), medians over the seeds.
"""
import argparse
import csv
import math
import os
import platform
import resource
import shlex
import signal
import statistics
import subprocess
import sys
import time

from benchlib import checksum, crossing, pair_noise, read_pfm, reference

LEVELS = (0.10, 0.03, 0.01, 0.005)
DEFAULT_CONFIGS = ['old-defaults=--sampler random --spppp 1 --adaptive off',
                   'sobol=--sampler sobol --spppp 1 --adaptive off',
                   'spppp8=--sampler random --spppp 8 --adaptive off',
                   'sobol-spppp8=--sampler sobol --spppp 8 --adaptive off',
                   'sobol-auto=--sampler sobol --spppp auto --adaptive off',
                   'defaults=']
LARGE_CONFIGS = ['spppp8=--spppp 8', 'defaults=']
LARGE_LEVEL = 0.01
LARGE_REF_SPP = 2048
STEADY_SPP = 1024
RATE_INDEX = LEVELS.index(0.01)   # the level whose ray rate the tables give
# References: Owen-scrambled Sobol points at one sample per pass (one eye ray per AO sample, so the
# anti-aliasing converges with the AO), seeds no timed run uses (benchlib.REFERENCE_SEEDS).
REFERENCE_ARGS = ['--sampler', 'sobol', '--spppp', '1', '--adaptive', 'off']
EXACT_SPP = 4096
SPP = 1 << 20          # far more than any run reaches: runs end on SIGINT
THREADS = 2
POLL = 0.05            # seconds between reads of a running render's --stats file
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RESULTS = ('<!-- results: written by tests/tools/time_to_error.py -->', '<!-- end of results -->')


def reference_spp(size):
    """Total spp of a reference (the two runs of its pair take half each): 32768 up to 160x120
    pixels, 8192 above."""
    width, height = map(int, size.split('x'))
    return 32768 if width * height <= 160 * 120 else 8192


def level_text(level):
    return '%g %%' % (100 * level)


def parse_rows(text):
    """Stats rows (pass, spp, seconds, eye_rays, shadow_rays, ..., rmse, mean_spp, error, ...) of
    complete lines, as (spp, seconds, rmse, estimated relative error, rays)."""
    rows = []
    for line in text.splitlines():
        if line and not line.startswith('pass'):
            fields = line.split(',')
            rows.append((int(fields[1]), float(fields[2]), float(fields[6]), float(fields[8]),
                         int(fields[3]) + int(fields[4])))
    return rows


def rate_to(rows, seconds):
    """Mrays/s over a run's first `seconds` render seconds (a crossing within its rows): the rays
    of the passes before and the share of the crossing pass's that its seconds give, as the pass
    traced them at its own rate; None when seconds is."""
    if seconds is None:
        return None
    before = (0.0, 0)
    for row in rows:
        if row[1] >= seconds:
            share = (seconds - before[0]) / (row[1] - before[0]) if row[1] > before[0] else 1.0
            return (before[1] + share * (row[4] - before[1])) / seconds / 1e6
        before = (row[1], row[4])
    return rows[-1][4] / rows[-1][1] / 1e6


def render(aoview, scene, size, seed, args, ref, lowest, cap, work, estimated=False, spp=SPP):
    """Runs one render of `spp` samples a pixel until its RMSE (and with `estimated` its estimated
    error) is at most lowest (None: to its end) or its render seconds reach cap, then interrupts it
    (aoview writes its image and exits 130); returns its stats rows. Args starting with `--binary
    BIN` run BIN instead of aoview."""
    stats, log = os.path.join(work, 'run.csv'), os.path.join(work, 'run.log')
    if os.path.exists(stats):
        os.remove(stats)
    if args[:1] == ['--binary']:
        aoview, args = args[1], args[2:]
    command = [aoview, '--headless', '-q', '--threads', str(THREADS), '--size', size, '--seed', str(seed),
               '--spp', str(spp)] + args + ['--reference', ref, '--stats', stats, '-o', os.path.join(work, 'run.pfm'),
                                           scene]
    with open(log, 'w') as err:
        proc = subprocess.Popen(command, stderr=err)
    started, interrupted, rows, pending, f = time.monotonic(), False, [], '', None
    while proc.poll() is None:
        time.sleep(POLL)
        if f is None and os.path.exists(stats):
            f = open(stats)
        if f is not None:
            pending += f.read()
            complete = pending.rfind('\n') + 1
            rows += parse_rows(pending[:complete])
            pending = pending[complete:]
        # The wall clock backs up the render seconds, should a pass never end.
        if not interrupted and ((rows and lowest is not None and
                                 ((rows[-1][2] <= lowest and (not estimated or rows[-1][3] <= lowest))
                                  or rows[-1][1] >= cap))
                                or time.monotonic() - started > 2 * cap + 30):
            proc.send_signal(signal.SIGINT)
            interrupted = True
    if f is not None:
        f.close()
    if proc.returncode not in (0, 130):
        with open(log) as f:
            sys.exit('time_to_error.py: %s failed (exit %d): %s' % (shlex.join(command), proc.returncode,
                                                                     f.read().strip()))
    with open(stats) as f:
        rows = parse_rows(f.read())
    if not rows:
        sys.exit('time_to_error.py: %s: no pass finished within %g s' % (shlex.join(command), 2 * cap + 30))
    return rows


def reaches(rows, targets, cap):
    """Per target: (seconds, spp) where the RMSE first falls to it, each interpolated log-log
    between the two rows around the crossing; None when it does not within cap seconds."""
    spp, seconds, rmse = [r[0] for r in rows], [r[1] for r in rows], [r[2] for r in rows]
    result = []
    for t in targets:
        s = crossing(seconds, rmse, t)
        result.append(None if s is None or s > cap else (s, crossing(spp, rmse, t)))
    return result


def large_block(a, scene, started):
    """The large size's runs: the first SCENE to LARGE_LEVEL RMSE and estimated error, per
    --large-config, interleaved per seed; returns the block of the results and the CSV rows."""
    configs = parse_configs(a.large_config or LARGE_CONFIGS)
    name, size = os.path.splitext(os.path.basename(scene))[0], a.large
    ref = os.path.join(a.work, 'reference-%s-%s.pfm' % (name, size))
    made = time.monotonic()
    kind, pair = reference(a.aoview, a.exact, scene, size, a.large_ref_spp // 2, EXACT_SPP, a.work, REFERENCE_ARGS, ref)
    made = time.monotonic() - made
    values = read_pfm(ref)[2]
    mean = sum(values) / len(values)
    noise = pair_noise(pair) if pair else 0.0
    results, rates, runs = {c[0]: [] for c in configs}, {c[0]: [] for c in configs}, []
    for seed in range(1, a.seeds + 1):
        for label, args in configs:
            rows = render(a.aoview, scene, size, seed, args, ref, LARGE_LEVEL * mean, a.cap, a.work, estimated=True)
            true = crossing([r[1] for r in rows], [r[2] for r in rows], LARGE_LEVEL * mean)
            known = [r for r in rows if not math.isnan(r[3])]
            estimated = crossing([r[1] for r in known], [r[3] for r in known], LARGE_LEVEL) if known else None
            reached = [None if v is None or v > a.cap else v for v in (true, estimated)]
            results[label].append(reached)
            rates[label].append(rate_to(rows, reached[0]))
            runs.append([name, size, label, shlex.join(args), seed, LARGE_LEVEL, '%.6g' % (LARGE_LEVEL * mean),
                         '' if reached[0] is None else '%.6f' % reached[0], '',
                         '' if reached[0] is None else '%.2f' % rates[label][-1], '%.6f' % rows[-1][1], rows[-1][0],
                         '%.6g' % rows[-1][2]])
            print('time_to_error.py: [%.0f s] %s %s %s seed %d: 1 %% RMSE %s, 1 %% estimated %s' % (
                time.monotonic() - started, name, size, label, seed,
                *('> cap' if v is None else '%.3g s' % v for v in reached)), file=sys.stderr, flush=True)
    medians = {label: [median([r[k] for r in per_seed]) for k in range(2)] for label, per_seed in results.items()}
    base = medians[configs[0][0]]
    lines = ['### %s, %s: time to 1 %%\n\n' % (name, size),
             'Reference: %s (%d spp in all); made in this run in %.0f s (0 when cached). Mean %.4f; its own RMS '
             'error %s. Each cell: the median render seconds over %d seeds to 1 %% RMSE against it, or to 1 %% '
             'estimated error (`--stats`\'s `error`), and %s\'s median over this one\'s; the ray rate: eye and AO '
             'rays over render seconds to 1 %% RMSE (median over the seeds).\n\n' % (
                 kind, a.large_ref_spp, made, mean,
                 '%.2g (%.3g %% of the mean)' % (noise, 100 * noise / mean) if pair else 'none (exact)', a.seeds,
                 configs[0][0]),
             '| config | aoview args | 1 % RMSE | 1 % estimated | Mrays/s to 1 % |\n|---|---|---|---|---|\n']
    for label, args in configs:
        cells = ['> %g s' % a.cap if math.isinf(m) else '%.3g s · ×%.3g' % (m, b / m if math.isfinite(b) else math.inf)
                 for m, b in zip(medians[label], base)]
        rate = rate_median(rates[label])
        cells.append('%.1f' % rate if math.isfinite(rate) else '')
        lines.append('| %s | %s | %s |\n' % (label, '`%s`' % shlex.join(args) if args else '(none)', ' | '.join(cells)))
    return ''.join(lines) + '\n', runs


def parse_configs(specs):
    """NAME=ARGS specs as (name, argument list), or exits on a malformed or repeated one."""
    configs = []
    for spec in specs:
        name, equals, args = spec.partition('=')
        if not name or not equals or name in (c[0] for c in configs):
            sys.exit("time_to_error.py: configuration '%s': expected a new NAME=ARGS" % spec)
        configs.append((name, shlex.split(args)))
    return configs


def median(values):
    """Median with a level not reached counting as infinitely late."""
    return statistics.median([math.inf if v is None else v for v in values])


def rate_median(rates):
    """Median of the ray rates of the runs that reached the level (NaN when none did)."""
    known = [r for r in rates if r is not None]
    return statistics.median(known) if known else math.nan


def cell(seconds, spp, base, cap):
    if math.isinf(seconds):
        return '> %g s%s' % (cap, ', ×< %.3g' % (base / cap) if math.isfinite(base) else '')
    ratio = '×%.3g' % (base / seconds) if math.isfinite(base) else '×> %.3g' % (cap / seconds)
    return '%.3g s · %.0f spp · %s' % (seconds, spp, ratio)


def child_cpu():
    """CPU seconds used so far by finished child processes."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def machine():
    model = next((line.split(':', 1)[1].strip() for line in open('/proc/cpuinfo') if line.startswith('model name')),
                 platform.processor())
    return '%s, %d cores, %s' % (model, os.cpu_count(), platform.platform())


def load():
    return ' '.join(open('/proc/loadavg').read().split()[:3])


def write_outputs(out, blocks, runs, header, started):
    """Writes the CSV, and the tables between the RESULTS markers of OUT/time-to-error.md (the
    whole file when it has none)."""
    with open(os.path.join(out, 'time-to-error.csv'), 'w', newline='') as f:
        table = csv.writer(f)
        table.writerow(['scene', 'size', 'config', 'args', 'seed', 'level', 'target_rmse', 'seconds', 'spp',
                        'mrays_per_s', 'last_seconds', 'last_spp', 'last_rmse'])
        table.writerows(runs)
    results = '%s- Run time: %.0f s; load average at the end: %s\n\n%s' % (
        header, time.monotonic() - started, load(), ''.join(blocks))
    path = os.path.join(out, 'time-to-error.md')
    text = open(path).read() if os.path.exists(path) else ''
    if RESULTS[0] in text and RESULTS[1] in text:
        results = text[:text.index(RESULTS[0]) + len(RESULTS[0])] + '\n' + results + text[text.index(RESULTS[1]):]
    with open(path + '.tmp', 'w') as f:
        f.write(results)
    os.replace(path + '.tmp', path)
    print('time_to_error.py: wrote %s/time-to-error.{md,csv}' % out, file=sys.stderr, flush=True)


def main():
    parser = argparse.ArgumentParser(usage=__doc__.replace('%', '%%'))
    parser.add_argument('--aoview', default=os.path.join(ROOT, 'build', 'aoview'))
    parser.add_argument('--exact')
    parser.add_argument('--sizes', default='160x120,640x480')
    parser.add_argument('--seeds', type=int, default=3)
    parser.add_argument('--cap', type=float, default=90.0)
    parser.add_argument('--ref-spp', type=int)
    parser.add_argument('--work')
    parser.add_argument('--out')
    parser.add_argument('--quick', action='store_true')
    parser.add_argument('--config', action='append')
    parser.add_argument('--large', default='1920x1080')
    parser.add_argument('--large-config', action='append')
    parser.add_argument('--large-ref-spp', type=int, default=LARGE_REF_SPP)
    parser.add_argument('--steady-spp', type=int, default=STEADY_SPP)
    parser.add_argument('scenes', nargs='+')
    a = parser.parse_args()
    a.exact = a.exact or os.path.join(os.path.dirname(a.aoview), 'aoview-exact')
    a.work = a.work or os.path.join(os.path.dirname(a.aoview), 'time-to-error')
    sizes = a.sizes.split(',')[:1 if a.quick else None]
    seeds = 1 if a.quick else a.seeds
    a.out = a.out or (a.work if a.quick else os.path.join(ROOT, 'docs'))
    configs = parse_configs(a.config or DEFAULT_CONFIGS)
    if a.quick:
        a.large = ''
    for size in sizes + ([a.large] if a.large else []):
        if len(size.split('x')) != 2 or not all(p.isdigit() and int(p) > 0 for p in size.split('x')):
            parser.error("--sizes: '%s' is not WxH" % size)
    if seeds < 1 or not a.cap > 0 or a.steady_spp < 0:
        parser.error('--seeds and --cap must be positive, --steady-spp not negative')
    for tool in (a.aoview, a.exact):
        if not os.access(tool, os.X_OK):
            sys.exit('time_to_error.py: %s is not built (try ninja -C %s)' % (tool, os.path.dirname(tool)))
    for scene in a.scenes:
        if not os.path.isfile(scene):
            sys.exit('time_to_error.py: %s: no such scene' % scene)
    os.makedirs(a.work, exist_ok=True)
    os.makedirs(a.out, exist_ok=True)

    version = subprocess.run([a.aoview, '--version'], capture_output=True, text=True).stdout.strip()
    base = configs[0][0]
    started, load_start = time.monotonic(), load()
    header = ('Render seconds (the `seconds` column of `--stats`) until the RMSE against the reference falls '
              'to %s of the reference\'s mean (over all pixels and channels, as `--stats` computes it); per '
              'configuration the median over %d seed%s (seeds 1 to %d), `--threads %d`; each cell `seconds · '
              'spp · ratio`, the ratio being %s\'s median time over this one\'s.\n\n'
              '- Command: `%s`\n- Date: %s\n- Machine: %s (load average %s at the '
              'start)\n- Binary: %s (sha256 %s…)\n- Cap per run: %g render seconds\n\n' % (
                  ', '.join(level_text(v) for v in LEVELS), seeds, '' if seeds == 1 else 's', seeds, THREADS, base,
                  shlex.join(os.path.relpath(v, ROOT) if v.startswith(ROOT + os.sep) else v
                             for v in [os.path.abspath(sys.argv[0])] + sys.argv[1:]),
                  time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime()), machine(), load_start, version,
                  checksum(a.aoview), a.cap))
    blocks, runs = [], []
    total, done = len(sizes) * len(a.scenes) * seeds * len(configs), 0
    for size in sizes:
        for scene in a.scenes:
            name = os.path.splitext(os.path.basename(scene))[0]
            ref = os.path.join(a.work, 'reference-%s-%s.pfm' % (name, size))
            spp = a.ref_spp or reference_spp(size)
            made, cpu = time.monotonic(), child_cpu()
            kind, pair = reference(a.aoview, a.exact, scene, size, spp // 2, EXACT_SPP, a.work, REFERENCE_ARGS, ref)
            made, cpu = time.monotonic() - made, child_cpu() - cpu
            values = read_pfm(ref)[2]
            mean = sum(values) / len(values)
            noise = pair_noise(pair) if pair else 0.0
            targets = [v * mean for v in LEVELS]
            print('time_to_error.py: %s %s: reference %s (%.0f s, %.0f CPU-s), mean %.4f, own RMS error %.2g (%.3g %% of the '
                  'mean)' % (name, size, kind, made, cpu, mean, noise, 100 * noise / mean), file=sys.stderr, flush=True)
            results, rates, steady = {c[0]: [] for c in configs}, {c[0]: [] for c in configs}, {c[0]: [] for c in configs}
            steady_spp = a.steady_spp if scene == a.scenes[0] else 0
            for seed in range(1, seeds + 1):
                for label, args in configs:
                    rows = render(a.aoview, scene, size, seed, args, ref, targets[-1], a.cap, a.work)
                    reached = reaches(rows, targets, a.cap)
                    results[label].append(reached)
                    rates[label].append(rate_to(rows, reached[RATE_INDEX] and reached[RATE_INDEX][0]))
                    for level, t, r in zip(LEVELS, targets, reached):
                        rate = r and rate_to(rows, r[0])
                        runs.append([name, size, label, shlex.join(args), seed, level, '%.6g' % t,
                                     '' if r is None else '%.6f' % r[0], '' if r is None else '%.1f' % r[1],
                                     '' if r is None else '%.2f' % rate, '%.6f' % rows[-1][1], rows[-1][0],
                                     '%.6g' % rows[-1][2]])
                    done += 1
                    print('time_to_error.py: [%d/%d, %.0f s] %s %s %s seed %d: %s' % (
                        done, total, time.monotonic() - started, name, size, label, seed,
                        ', '.join('%s %s' % (level_text(v), '> cap' if r is None else '%.3g s' % r[0])
                                  for v, r in zip(LEVELS, reached))), file=sys.stderr, flush=True)
                for label, args in configs if steady_spp else ():
                    rows = render(a.aoview, scene, size, seed, args, ref, None, a.cap, a.work, spp=steady_spp)
                    steady[label].append(rows[-1][4] / rows[-1][1] / 1e6)
                    print('time_to_error.py: [%.0f s] %s %s %s seed %d: %d spp at %.1f Mrays/s' % (
                        time.monotonic() - started, name, size, label, seed, steady_spp, steady[label][-1]),
                        file=sys.stderr, flush=True)
            medians = {label: [(median([s[k] and s[k][0] for s in per_seed]),
                                median([s[k] and s[k][1] for s in per_seed])) for k in range(len(LEVELS))]
                       for label, per_seed in results.items()}
            lines = ['### %s, %s\n\n' % (name, size),
                     'Reference: %s; made in this run in %.0f s, %.0f CPU-seconds (0 when cached). Mean %.4f; '
                     'its own RMS error %s.%s\n\n' % (kind, made, cpu, mean,
                         '%.2g (%.3g %% of the mean)' % (noise, 100 * noise / mean) if pair else 'none (exact)',
                         ' Ray rates: eye and AO rays over render seconds, to 1 %% RMSE and over a whole run of %d '
                         'spp (median over the seeds each), and the first over the second.' % steady_spp
                         if steady_spp else ' Ray rate: eye and AO rays over render seconds to 1 % RMSE (median '
                         'over the seeds).'),
                     '| config | aoview args | %s | Mrays/s to 1 %% |%s\n' % (
                         ' | '.join('%s (%.3g)' % (level_text(v), t) for v, t in zip(LEVELS, targets)),
                         ' Mrays/s, %d spp | ratio |' % steady_spp if steady_spp else ''),
                     '|---|---|%s\n' % ('---|' * (len(LEVELS) + (3 if steady_spp else 1)))]
            for label, args in configs:
                rate = rate_median(rates[label])
                cells = [cell(s, n, medians[base][k][0], a.cap) for k, (s, n) in enumerate(medians[label])]
                cells.append('%.1f' % rate if math.isfinite(rate) else '')
                if steady_spp:
                    cells += ['%.1f' % median(steady[label]),
                              '%.2f' % (rate / median(steady[label])) if math.isfinite(rate) else '']
                lines.append('| %s | %s | %s |\n' % (label, '`%s`' % shlex.join(args) if args else '(none)',
                                                     ' | '.join(cells)))
            blocks.append(''.join(lines) + '\n')
            write_outputs(a.out, blocks, runs, header, started)
    if a.large:
        block, large_runs = large_block(a, a.scenes[0], started)
        blocks.append(block)
        runs += large_runs
        write_outputs(a.out, blocks, runs, header, started)
    print('time_to_error.py: done in %.0f s, load average %s at the end' % (time.monotonic() - started, load()),
          file=sys.stderr, flush=True)


if __name__ == '__main__':
    main()
