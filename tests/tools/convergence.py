#!/usr/bin/env python3
"""Analysis half of tests/tools/convergence.sh (plain python3, no third-party modules).

  convergence.py report --name N --runs DIR --out DIR --methods L... [--reference-pair A B] ...

report reads DIR/reference.pfm and, per method label L and seed S, DIR/L-S.csv (aoview --stats
with --reference) and DIR/L-S.pfm (the final image), and writes into --out:
  convergence-N.csv       every run's rows at log-spaced spp (ROWS_PER_DECADE a decade, and the last)
  convergence-N.png/.svg  RMSE against seconds and against spp, log-log: per method the RMS over
                          seeds as a line (dashed for a label SAMPLING+VARIANT) and the min-max over
                          seeds as a band, the ideal slope -1/2 (a guide a factor 2 below the best
                          random-number method) and the 1 % target
  convergence-N.md        the table: fitted slope, RMSE at equal time, time and spp to 1 % RMSE, mean
                          signed error of the final images with its z-score
Definitions are in the table's notes and in docs/accuracy.md.
"""
import argparse
import csv
import math
import os
import subprocess
import sys

from benchlib import crossing, pair_noise, read_pfm

ROWS_PER_DECADE = 20
COLOURS = {'uniform': '#d62728', 'hemisphere': '#1f77b4', 'cosine': '#2ca02c'}
EXTRA_COLOURS = ['#9467bd', '#ff7f0e', '#8c564b', '#e377c2', '#17becf']


def pixel_means(values):
    """Mean of the three channels of each pixel."""
    return [(values[k] + values[k + 1] + values[k + 2]) / 3.0 for k in range(0, len(values), 3)]


def log_spaced(last):
    """spp values kept in the CSV and the charts: ROWS_PER_DECADE per decade, and the last."""
    keep = {max(1, round(10 ** (k / ROWS_PER_DECADE))) for k in range(0, ROWS_PER_DECADE * 10)}
    return sorted(n for n in keep if n <= last) + ([last] if last not in keep else [])


def fit_line(xs, ys):
    """Least-squares slope and intercept of log y against log x."""
    lx, ly = [math.log(x) for x in xs], [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    slope = sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)
    return slope, my - slope * mx


def interpolate(xs, ys, x):
    """ys at x, linear in log-log between the neighbouring points (xs increasing)."""
    for k in range(1, len(xs)):
        if xs[k] >= x:
            t = (math.log(x) - math.log(xs[k - 1])) / (math.log(xs[k]) - math.log(xs[k - 1]))
            return math.exp(math.log(ys[k - 1]) + t * (math.log(ys[k]) - math.log(ys[k - 1])))
    return ys[-1]


def reach(xs, ys, target, unit):
    """Text for where the curve reaches target: measured, or extrapolated along its fitted line."""
    x = crossing(xs, ys, target)
    if x is not None:
        return unit % x
    slope, intercept = fit_line(xs, ys)
    return '≈ ' + unit % math.exp((math.log(target) - intercept) / slope) + ' (extrapolated)'


def read_runs(runs, label, seeds):
    """The stats rows of each seed's run, as dicts from spp to a row of numbers."""
    result = []
    for seed in range(1, seeds + 1):
        with open(os.path.join(runs, '%s-%d.csv' % (label, seed))) as f:
            rows = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]
        result.append({int(r['spp']): r for r in rows})
    return result


def aggregate(rows_per_seed, keep):
    """Per kept spp: mean seconds, RMS of RMSE over seeds, min and max RMSE."""
    points = []
    for spp in keep:
        rows = [rows[spp] for rows in rows_per_seed]
        errors = [r['rmse'] for r in rows]
        points.append((spp, sum(r['seconds'] for r in rows) / len(rows),
                       math.sqrt(sum(e * e for e in errors) / len(errors)), min(errors), max(errors)))
    return points


def bias(runs, label, seeds, reference, ref_pair):
    """Mean signed error of the final images over pixels and seeds, and its standard error: pixels
    are independent (each has its own random streams), so the error of the mean is the root of the
    summed per-pixel variances over seeds, divided by pixels; a two-run reference adds its own."""
    ref = pixel_means(reference)
    errors = [[v - r for v, r in zip(pixel_means(read_pfm(os.path.join(runs, '%s-%d.pfm' % (label, s)))[2]), ref)]
              for s in range(1, seeds + 1)]
    n = len(ref)
    mean = sum(sum(e) for e in errors) / (n * seeds)
    variance = 0.0
    for p in range(n):
        m = sum(e[p] for e in errors) / seeds
        variance += sum((e[p] - m) ** 2 for e in errors) / (seeds - 1) / seeds
    if ref_pair:
        a, b = pixel_means(ref_pair[0]), pixel_means(ref_pair[1])
        variance += sum((x - y) ** 2 / 4.0 for x, y in zip(a, b))
    return mean, math.sqrt(variance) / n


def gnuplot_script(name, data, methods, target, floor, anchor, title, terminal, output):
    lines = [terminal, "set output '%s'" % output,
             "set multiplot layout 1,2 title \"%s\" font ',11'" % title,
             'set logscale xy', 'set autoscale xfix', 'set grid xtics ytics mxtics mytics lc rgb "#dddddd"', 'set key bottom left',
             "set format y '%g'", "set ylabel 'RMSE (all pixels and channels)'"]
    for column, xlabel, (x0, y0) in ((2, 'seconds (one thread)', anchor[1]), (1, 'samples per pixel', anchor[0])):
        plots = []
        for index, (label, colour) in enumerate(methods):
            plots.append("'%s' index %d using %d:4:5 with filledcurves fs transparent solid 0.18 noborder "
                         "lc rgb '%s' notitle" % (data, index, column, colour))
            plots.append("'' index %d using %d:3 with lines lw 2 dt %d lc rgb '%s' title '%s'"
                         % (index, column, 2 if '+' in label else 1, colour, label))
        plots.append("%g * (x / %g) ** -0.5 with lines dt 2 lw 1.5 lc rgb '#555555' title 'ideal slope -1/2'"
                     % (y0 / 2, x0))
        plots.append("%g with lines dt 3 lw 1.5 lc rgb '#000000' title '1 %% of mean reference'" % target)
        if floor:
            plots.append("%g with lines dt 4 lw 1.5 lc rgb '#999999' title 'reference noise'" % floor)
        lines += ["set xlabel '%s'" % xlabel, 'plot ' + ', \\\n  '.join(plots)]
    lines.append('unset multiplot')
    return '\n'.join(lines) + '\n'


def report(args):
    width, height, reference = read_pfm(os.path.join(args.runs, 'reference.pfm'))
    ref_pair = [read_pfm(p)[2] for p in args.reference_pair] if args.reference_pair else None
    mean_ref = sum(reference) / len(reference)
    target = 0.01 * mean_ref
    floor = pair_noise(args.reference_pair) if ref_pair else 0.0

    # The CSV of all runs' kept rows, and the curves.
    curves, runs_rows = {}, {}
    with open(os.path.join(args.out, 'convergence-%s.csv' % args.name), 'w', newline='') as f:
        out = csv.writer(f)
        out.writerow(['scene', 'method', 'seed', 'pass', 'spp', 'seconds', 'eye_rays', 'shadow_rays',
                      'mrays_per_s', 'rmse'])
        for label in args.methods:
            rows_per_seed = read_runs(args.runs, label, args.seeds)
            common = set.intersection(*(set(rows) for rows in rows_per_seed))
            keep = [n for n in log_spaced(max(common)) if n in common]
            for seed, rows in enumerate(rows_per_seed, 1):
                for spp in keep:
                    r = rows[spp]
                    out.writerow([args.name, label, seed, int(r['pass']), int(r['spp']), '%.6f' % r['seconds'],
                                  int(r['eye_rays']), int(r['shadow_rays']), '%.3f' % r['mrays_per_s'],
                                  '%.9g' % r['rmse']])
            curves[label] = aggregate(rows_per_seed, keep)
            runs_rows[label] = rows_per_seed

    # The table.
    equal_time = min(c[-1][1] for c in curves.values())
    rows = []
    for label in args.methods:
        c = curves[label]
        spp, seconds, rms = [p[0] for p in c], [p[1] for p in c], [p[2] for p in c]
        slope, _ = fit_line(spp, rms)
        mrays = sum(r[max(r)]['mrays_per_s'] for r in runs_rows[label]) / args.seeds
        mean, se = bias(args.runs, label, args.seeds, reference, ref_pair)
        rows.append('| %s | %d | %.1f | %.3f | %.3g | %s | %s | %+.2e ± %.1e (%+.1f σ) |' % (
            label, spp[-1], mrays, slope, interpolate(seconds, rms, equal_time), reach(seconds, rms, target, '%.3g s'),
            reach(spp, rms, target, '%.0f'), mean, se, mean / se))
    # The ideal slope runs parallel to the best plain (random-number) method's curve, a factor 2
    # below the middle of it, so that it does not hide it.
    plain = [m for m in args.methods if '+' not in m] or args.methods
    best = min(plain, key=lambda m: curves[m][-1][2])
    mid = curves[best][len(curves[best]) // 2]
    title = '%s, %s, %d seeds per method, about %g s per run' % (args.name, args.size, args.seeds, args.budget)
    with open(os.path.join(args.out, 'convergence-%s.md' % args.name), 'w') as f:
        f.write('### Convergence: %s\n\n' % args.name)
        f.write('![RMSE against time and spp, %s](convergence-%s.png)\n\n' % (args.name, args.name))
        f.write('%s; AA on, `--spppp 1`, `--threads 1`. Reference: %s. Mean reference value %.4f, so 1 %% '
                'RMSE = %.3g.%s\n\n' % (title, args.reference_kind, mean_ref, target,
                                        ' Reference noise (RMS): %.2g.' % floor if floor else ''))
        f.write('| method | spp per run | Mrays/s | fitted slope | RMSE at %.3g s | time to 1 %% RMSE | spp to 1 %% RMSE '
                '| mean error of the final images |\n' % equal_time)
        f.write('|---|---|---|---|---|---|---|---|\n' + '\n'.join(rows) + '\n\n')
        f.write('Fitted slope: least squares on log RMSE against log spp over the log-spaced points. RMSE is '
                'the root mean square over seeds; times are the mean over seeds. "Extrapolated": 1 % was not '
                'reached within the budget, so the fitted line in log RMSE against log seconds (or spp) is '
                'extended. Mean error: over all pixels and seeds of the final images, ± its standard error.\n')

    # The charts.
    data = os.path.join(args.runs, 'curves.dat')
    with open(data, 'w') as f:
        for label in args.methods:
            f.write('# %s: spp seconds rmse_rms rmse_min rmse_max\n' % label)
            f.write(''.join('%d %.6f %.9g %.9g %.9g\n' % p for p in curves[label]) + '\n\n')
    # A label "SAMPLING+VARIANT" (for example cosine+sobol) takes its sampler's colour, dashed.
    colours = [(m, COLOURS.get(m.split('+')[0], EXTRA_COLOURS[k % len(EXTRA_COLOURS)]))
               for k, m in enumerate(args.methods)]
    for terminal, ext in (("set terminal pngcairo size 1200,480 font 'sans,10'", 'png'),
                          ("set terminal svg size 1200,480 dynamic font 'sans,10'", 'svg')):
        output = os.path.join(args.out, 'convergence-%s.%s' % (args.name, ext))
        script = gnuplot_script(args.name, data, colours, target, floor, ((mid[0], mid[2]), (mid[1], mid[2])),
                                title, terminal, output)
        subprocess.run(['gnuplot'], input=script.encode(), check=True)
    print('convergence.py: wrote %s/convergence-%s.{csv,md,png,svg}' % (args.out, args.name), file=sys.stderr)


def main():
    parser = argparse.ArgumentParser(usage=__doc__)
    parser.add_argument('command', choices=['report'])
    parser.add_argument('--name', required=True)
    parser.add_argument('--runs', required=True)
    parser.add_argument('--out', required=True)
    parser.add_argument('--seeds', type=int, required=True)
    parser.add_argument('--budget', type=float, required=True)
    parser.add_argument('--size', required=True)
    parser.add_argument('--reference-kind', required=True)
    parser.add_argument('--reference-pair', nargs=2)
    parser.add_argument('--methods', nargs='+', required=True)
    report(parser.parse_args())


if __name__ == '__main__':
    main()
