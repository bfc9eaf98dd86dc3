#!/usr/bin/env python3
"""How much adaptive sampling could save at best: from the per-pixel variance of independent
renders (seeds 1..N, no adaptive sampling), the factor by which the ideal allocation of samples
would cut the rays (or time) needed for a given image RMSE, with one sample count per pixel or per
block of pixels, against every pixel taking the same number. Prints a table.

  tests/tools/allocation_bound.py [--aoview BIN] [--size WxH] [--spp N] [--seeds N] [--eye-cost C]
                            [--work DIR] SCENE

The ideal allocation of a budget of work W minimizes sum_k v_k / n_k (v_k: a block's summed
per-sample variance, n_k its samples per pixel) subject to sum_k n_k c_k = W (c_k: its summed
cost per sample): n_k proportional to sqrt(v_k / c_k), giving an error-times-work product of
(sum_k sqrt(v_k c_k))^2 against (sum_k v_k)(sum_k c_k) for equal n. A sample costs an AO ray
(1) where the pixel's eye rays hit something and none where they miss, plus its share of an eye
ray: --eye-cost (an eye ray's cost in AO rays; 2 measured on the bunny) over the 8 AO samples an
eye ray carries. The variances come from --seeds renders, so the bound is itself an estimate
(about 6 % spread at 24 seeds); finer blocks also need finer, hence noisier, decisions, which the
bound does not charge for.
"""
import argparse
import os
import statistics
import subprocess

from benchlib import read_pfm

BLOCKS = (1, 2, 4, 8, 16)
AO_PER_EYE_RAY = 8


def render(aoview, scene, size, spp, seed, args, out):
    subprocess.run([aoview, '--headless', '-q', '--threads', '2', '--size', size, '--spp', str(spp), '--seed',
                    str(seed), '--adaptive', 'off', '-o', out, scene] + args, check=True)
    width, height, values = read_pfm(out)
    return width, height, [sum(values[3 * p:3 * p + 3]) / 3.0 for p in range(width * height)]


def bound(width, height, variance, cost, block):
    """(sum v)(sum c) / (sum sqrt(v c))^2 over blocks of block x block pixels."""
    v, c = {}, {}
    for p in range(width * height):
        key = (p % width // block, p // width // block)
        v[key] = v.get(key, 0.0) + variance[p]
        c[key] = c.get(key, 0.0) + cost[p]
    best = sum((v[k] * c[k]) ** 0.5 for k in v) ** 2
    return sum(v.values()) * sum(c.values()) / best


def main():
    p = argparse.ArgumentParser(usage=__doc__)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    p.add_argument('--aoview', default=os.path.join(root, 'build', 'aoview'))
    p.add_argument('--size', default='160x120')
    p.add_argument('--spp', type=int, default=128)
    p.add_argument('--seeds', type=int, default=24)
    p.add_argument('--eye-cost', type=float, default=2.0)
    p.add_argument('--work', default=os.path.join(root, 'build', 'allocation-bound'))
    p.add_argument('scene')
    args = p.parse_args()
    os.makedirs(args.work, exist_ok=True)
    out = os.path.join(args.work, 'run.pfm')

    # Per-pixel variance of the spp-sample estimate over the seeds, then per sample.
    images = [render(args.aoview, args.scene, args.size, args.spp, s, [], out) for s in range(1, args.seeds + 1)]
    width, height = images[0][0], images[0][1]
    variance = [statistics.variance([img[2][p] for img in images]) * args.spp for p in range(width * height)]
    # Where every eye ray misses: black in the normals view (a unit normal's colour is never black).
    normals = render(args.aoview, args.scene, args.size, 64, 1, ['--view', 'normals', '--spppp', '1'], out)[2]
    eye_share = args.eye_cost / AO_PER_EYE_RAY
    cost = [(1.0 if n > 0.0 else 0.0) + eye_share for n in normals]

    zero = sum(1 for v in variance if v == 0.0) / len(variance)
    print('%s at %s, %d spp, %d seeds: %.0f %% of the pixels without variance, %.0f %% missed by the eye rays'
          % (os.path.basename(args.scene), args.size, args.spp, args.seeds, 100 * zero,
             100 * sum(1 for n in normals if n == 0.0) / len(normals)))
    print('| decisions on | ' + ' | '.join('per pixel' if b == 1 else '%dx%d' % (b, b) for b in BLOCKS) + ' |')
    print('|---' * (len(BLOCKS) + 1) + '|')
    print('| bound on the work saved | ' + ' | '.join('%.2f' % bound(width, height, variance, cost, b)
                                                     for b in BLOCKS) + ' |')


if __name__ == '__main__':
    main()
