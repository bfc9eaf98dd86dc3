#!/usr/bin/env python3
"""Pieces shared by tests/convergence.{sh,py} and tests/tools/time_to_error.py (plain python3): PFM
reading and writing, the log-log crossing of an error curve, and cached references.

  benchlib.py reference --aoview BIN --exact BIN --size WxH --spp N --exact-spp N --work DIR
                        [--args 'AOVIEW ARGS'] --out OUT.pfm SCENE

writes SCENE's reference to OUT.pfm and prints its description, then the two runs it is the mean of
(none for an exact one), one a line: the command-line face of reference() for shell scripts.
"""
import argparse
import hashlib
import math
import os
import shlex
import struct
import subprocess
import sys


def read_pfm(path):
    """Width, height and values of a colour PFM as a flat list (file order; only pixel-wise
    statistics use it)."""
    with open(path, 'rb') as f:
        header = []
        while len(header) < 4:
            header += f.readline().split()
        if header[0] != b'PF':
            sys.exit('benchlib.py: %s: not a colour PFM' % path)
        width, height, scale = int(header[1]), int(header[2]), float(header[3])
        count = 3 * width * height
        return width, height, list(struct.unpack(('<' if scale < 0 else '>') + '%df' % count, f.read(4 * count)))


def write_pfm(path, width, height, values):
    with open(path + '.tmp', 'wb') as f:
        f.write(b'PF\n%d %d\n-1.0\n' % (width, height))
        f.write(struct.pack('<%df' % len(values), *values))
    os.replace(path + '.tmp', path)


def crossing(xs, ys, target):
    """First x where ys falls to target, interpolated in log-log between the two points around the
    crossing; None when it never does."""
    for k, y in enumerate(ys):
        if y <= target:
            if k == 0:
                return xs[0]
            t = (math.log(target) - math.log(ys[k - 1])) / (math.log(y) - math.log(ys[k - 1]))
            return math.exp(math.log(xs[k - 1]) + t * (math.log(xs[k]) - math.log(xs[k - 1])))
    return None


def checksum(path):
    """Short hash of a file's bytes: cached references are remade whenever the binary changes."""
    with open(path, 'rb') as f:
        return hashlib.sha256(f.read()).hexdigest()[:12]


REFERENCE_SEEDS = (1001, 1002)


def reference(aoview, exact, scene, size, spp, exact_spp, work, args, out):
    """Writes SCENE's reference image at SIZE to OUT and returns (description, pair): aoview-exact's
    image (exact_spp sub-pixel samples) when the scene has a closed form, pair None; else the mean
    of two aoview runs of spp samples each with ARGS (a list), seeds REFERENCE_SEEDS, 2 threads,
    pair their paths, whose difference measures the reference's own noise. Every image is cached
    in WORK under the checksum of the binary that made it (and of ARGS), so it is made once per
    binary. Progress goes to stderr."""
    name = os.path.splitext(os.path.basename(scene))[0]
    os.makedirs(work, exist_ok=True)
    exact_path = os.path.join(work, 'exact-%s-%s-%d-%s.pfm' % (name, size, exact_spp, checksum(exact)))
    if not os.path.exists(exact_path):
        made = subprocess.run([exact, '-q', '--size', size, '--spp', str(exact_spp), '-o', exact_path, scene],
                              stderr=subprocess.PIPE, text=True)
        if made.returncode != 0 and 'no closed form' not in made.stderr:
            sys.exit(made.stderr.strip() or '%s failed on %s' % (exact, scene))
    if os.path.exists(exact_path):
        width, height, values = read_pfm(exact_path)
        write_pfm(out, width, height, values)
        k = round(math.sqrt(exact_spp))
        return 'exact (aoview-exact --spp %d, a %dx%d sub-pixel grid)' % (exact_spp, k, k), None
    tag = hashlib.sha256(' '.join(args).encode()).hexdigest()[:6]
    pair = []
    for seed in REFERENCE_SEEDS:
        cached = os.path.join(work, 'reference-%s-%s-%d-%d-%s-%s.pfm' % (name, size, spp, seed, tag, checksum(aoview)))
        if not os.path.exists(cached):
            print('%s: reference run, seed %d, %d spp, %s (cached as %s)' % (name, seed, spp, ' '.join(args), cached),
                  file=sys.stderr, flush=True)
            subprocess.run([aoview, '--headless', '-q', '--threads', '2', '--size', size, '--spp', str(spp)] + args
                           + ['--seed', str(seed), '-o', cached, scene], check=True)
        pair.append(cached)
    (width, height, a), (_, _, b) = read_pfm(pair[0]), read_pfm(pair[1])
    write_pfm(out, width, height, [(x + y) / 2.0 for x, y in zip(a, b)])
    return 'the mean of two runs of %d spp with `%s` (seeds %s)' % (
        spp, ' '.join(args), ', '.join(map(str, REFERENCE_SEEDS))), pair


def pair_noise(pair):
    """RMS error (over all pixels and channels) of the mean of a reference pair: each run's error
    has variance E(a-b)^2 / 2, their mean's half that."""
    a, b = read_pfm(pair[0])[2], read_pfm(pair[1])[2]
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)) / len(a)) / 2.0


def main():
    parser = argparse.ArgumentParser(usage=__doc__)
    parser.add_argument('command', choices=['reference'])
    parser.add_argument('--aoview', required=True)
    parser.add_argument('--exact', required=True)
    parser.add_argument('--size', required=True)
    parser.add_argument('--spp', type=int, required=True)
    parser.add_argument('--exact-spp', type=int, required=True)
    parser.add_argument('--work', required=True)
    parser.add_argument('--args', default='')
    parser.add_argument('--out', required=True)
    parser.add_argument('scene')
    a = parser.parse_args()
    kind, pair = reference(a.aoview, a.exact, a.scene, a.size, a.spp, a.exact_spp, a.work, shlex.split(a.args), a.out)
    print('\n'.join([kind] + (pair or [])))


if __name__ == '__main__':
    main()
