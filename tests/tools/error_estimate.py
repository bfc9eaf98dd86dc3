#!/usr/bin/env python3
"""The error estimate against the truth: for each scene, aoview runs with --stats against a
reference, and every row's estimated relative RMSE (the `error` column, from the even and odd
passes, no reference) is set beside the true one (rmse / the reference's mean). Writes
error-estimate.png (gnuplot) and error-estimate.md into --out, and every row into
error-estimate.csv in --work.

  tests/tools/error_estimate.py [--aoview BIN] [--exact BIN] [--size WxH] [--spp N] [--work DIR]
                          [--out DIR] SCENE...

References are tests/tools/benchlib.py's, as tests/tools/time_to_error.py makes them (and shares through the
default --work): aoview-exact's image where the scene has a closed form, else the mean of two
16384-spp Sobol runs, whose own error (about 0.04 % of the mean) is far below the errors
compared here."""
import argparse, csv, math, os, subprocess, sys

from benchlib import read_pfm, reference

CONFIGS = [('defaults', []), ('adaptive off', ['--adaptive', 'off']),
           ('random, spppp 1, adaptive off', ['--sampler', 'random', '--spppp', '1', '--adaptive', 'off'])]
# The references of tests/tools/time_to_error.py at 160x120 (shared through the same work directory).
REFERENCE_ARGS = ['--sampler', 'sobol', '--spppp', '1', '--adaptive', 'off']
REFERENCE_SPP, EXACT_SPP = 16384, 4096


def main():
    p = argparse.ArgumentParser()
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    p.add_argument('--aoview', default=os.path.join(root, 'build', 'aoview'))
    p.add_argument('--exact')
    p.add_argument('--size', default='160x120')
    p.add_argument('--spp', default='1024')
    p.add_argument('--work')
    p.add_argument('--out', default=os.path.join(root, 'docs'))
    p.add_argument('scenes', nargs='+')
    args = p.parse_args()
    args.exact = args.exact or os.path.join(os.path.dirname(args.aoview), 'aoview-exact')
    args.work = args.work or os.path.join(os.path.dirname(args.aoview), 'time-to-error')
    os.makedirs(args.work, exist_ok=True)
    os.makedirs(args.out, exist_ok=True)
    rows, table = [], []
    for scene in args.scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        ref = os.path.join(args.work, 'reference-%s.pfm' % name)
        kind = reference(args.aoview, args.exact, scene, args.size, REFERENCE_SPP, EXACT_SPP, args.work,
                         REFERENCE_ARGS, ref)[0]
        values = read_pfm(ref)[2]
        mean = sum(values) / len(values)
        for label, extra in CONFIGS:
            stats = os.path.join(args.work, 'stats.csv')
            subprocess.run([args.aoview, '--headless', '-q', '--threads', '2', '--size', args.size, '--spp',
                            args.spp, '--seed', '1', '--reference', ref, '--stats', stats, '-o',
                            os.path.join(args.work, 'run.pfm'), scene] + extra, check=True)
            ratios = []
            for r in csv.DictReader(open(stats)):
                # A black image (the closed box) has no relative error: its RMSE is 0 as it is.
                true, est = float(r['rmse']) / mean if mean > 0 else float(r['rmse']), float(r['error'])
                rows.append([name, label, r['pass'], r['mean_spp'], '%.6g' % est, '%.6g' % true])
                if float(r['mean_spp']) >= 10 and true > 0:
                    ratios.append(est / true)
            last = rows[-1]
            worst = max(ratios, key=lambda x: abs(math.log(x))) if ratios else float('nan')
            table.append((name, kind, label, len(ratios), min(ratios, default=float('nan')),
                          max(ratios, default=float('nan')), worst, last[3], float(last[4]), float(last[5])))
            print('%s, %s: %d rows from 10 spp, estimate/true %.3f to %.3f' % (name, label, len(ratios),
                  table[-1][4], table[-1][5]), file=sys.stderr)
    with open(os.path.join(args.work, 'error-estimate.csv'), 'w', newline='') as f:
        w = csv.writer(f)
        w.writerow(['scene', 'config', 'pass', 'mean_spp', 'estimate', 'true'])
        w.writerows(rows)
    chart(args, rows)
    with open(os.path.join(args.out, 'error-estimate.md'), 'w') as f:
        f.write('| scene | reference | settings | rows from 10 spp | estimate / true, min | max | at the end: mean spp, estimate, true |\n')
        f.write('|---|---|---|---|---|---|---|\n')
        for name, kind, label, n, lo, hi, worst, spp, est, true in table:
            f.write('| %s | %s | %s | %d | %.3f | %.3f | %s, %.4f, %.4f |\n' % (name, kind, label, n, lo, hi, spp, est, true))


def chart(args, rows):
    """Estimate against truth, one panel, log-log, a point per row from 10 spp, the diagonal and
    the factor-1.25 band."""
    data = os.path.join(args.work, 'points.dat')
    names = sorted({r[0] for r in rows if float(r[3]) >= 10 and float(r[5]) > 0})
    with open(data, 'w') as f:
        for name in names:
            f.write('# %s\n' % name)
            for r in rows:
                if r[0] == name and float(r[3]) >= 10 and float(r[5]) > 0:
                    f.write('%s %s\n' % (r[5], r[4]))
            f.write('\n\n')
    plot = ', '.join("'%s' index %d using 1:2 with points pt 7 ps 0.6 title '%s'" % (data, k, n)
                     for k, n in enumerate(names))
    script = """set terminal pngcairo size 720,540 font ',10'
set output '%s'
set logscale xy
set xlabel 'true RMSE / image mean'
set ylabel 'estimated (even and odd passes, no reference)'
set key top left
set grid
plot x title 'estimate = true' lc 'black', 1.25*x dt 2 lc 'grey' title 'x 1.25', x/1.25 dt 2 lc 'grey' notitle, %s
""" % (os.path.join(args.out, 'error-estimate.png'), plot)
    subprocess.run(['gnuplot'], input=script, text=True, check=True)


if __name__ == '__main__':
    main()
