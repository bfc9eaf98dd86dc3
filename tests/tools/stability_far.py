#!/usr/bin/env python3
"""The sphere-on-ground scene placed at a given distance from the origin, rendered by aoview and
compared with aoview-exact, pixel by pixel, as docs/stability.md reports it:

    tests/tools/stability_far.py AOVIEW AOVIEW_EXACT SHIFT [SHIFT...]

A sphere of radius 1 resting on a ground quad of +-2e4 at (s, s, s); cosine sampling, 2048 spp,
no AA, 96x72. Without AA a pixel's value is rho K / N, K ~ binomial(N, q), q = exact / rho; the
worst pixel's one-sided binomial tail is given as the z of a normal tail of the same probability,
and the mean error over the pixels as a t statistic (standard error sqrt(sum rho^2 q (1-q) / N) /
pixels). Pixels that miss (background 1, more than any point of albedo 0.8 can give) are left out."""
import math
import os
import struct
import subprocess
import sys
import tempfile

N, RHO, W, H = 2048, 0.8, 96, 72


def read_pfm(path):
    parts = open(path, 'rb').read().split(b'\n', 3)
    w, h = map(int, parts[1].split())
    return struct.unpack('<%df' % (3 * w * h), parts[3])[0::3]


def tail(n, p, k):
    """One-sided binomial tail on k's side of the mean, summed outward from k."""
    if p <= 0.0 or p >= 1.0:
        return 1.0 if k == n * p else 0.0
    step = -1 if k < n * p else 1
    total, j = 0.0, k
    while 0 <= j <= n:
        term = math.exp(math.lgamma(n + 1) - math.lgamma(j + 1) - math.lgamma(n - j + 1) + j * math.log(p) +
                        (n - j) * math.log1p(-p))
        total += term
        if term < 1e-17 * total:
            break
        j += step
    return min(1.0, total)


def z_of(p):
    lo, hi = 0.0, 40.0
    for _ in range(100):
        mid = (lo + hi) / 2
        if 0.5 * math.erfc(mid / math.sqrt(2)) > p:
            lo = mid
        else:
            hi = mid
    return lo


def measure(aoview, exact, shift, work):
    s = shift
    scene = os.path.join(work, 'far.scene')
    with open(scene, 'w') as f:
        f.write('camera eye %r %r %r target %r %r %r fov 40\nbackground 1\n' % (s, s + 3.2, s + 6.4, s, s + 0.7, s))
        f.write('quad corner %r %r %r edge1 0 0 4e4 edge2 4e4 0 0 albedo 0.8\n' % (s - 2e4, s, s - 2e4))
        f.write('sphere center %r %r %r radius 1 albedo 0.8\n' % (s, s + 1, s))
    common = ['--no-aa', '--size', '%dx%d' % (W, H), '-q']
    subprocess.run([exact] + common + ['-o', os.path.join(work, 'exact.pfm'), scene], check=True)
    subprocess.run([aoview, '--headless', '--sampling', 'cosine', '--spp', str(N), '--spppp', '64'] + common +
                   ['-o', os.path.join(work, 'ao.pfm'), scene], check=True)
    ref, img = read_pfm(os.path.join(work, 'exact.pfm')), read_pfm(os.path.join(work, 'ao.pfm'))
    worst, where, err, var, count = 0.0, None, 0.0, 0.0, 0
    for i, (e, v) in enumerate(zip(ref, img)):
        if e > RHO:
            continue
        q = min(1.0, max(0.0, e / RHO))
        k = round(v * N / RHO)
        z = z_of(tail(N, q, k))
        if z > worst:
            worst, where = z, (i % W, H - 1 - i // W, v, e)  # PFM rows run bottom to top
        err += v - e
        var += RHO * RHO * q * (1 - q) / N
        count += 1
    print('at %g: %d pixels, worst z %.1f at (%d, %d): %.4f against %.4f; mean bias %+.6f (t %+.1f)' %
          ((shift, count, worst) + where + (err / count, err / math.sqrt(var))))


def main():
    aoview, exact = sys.argv[1:3]
    with tempfile.TemporaryDirectory() as work:
        for shift in sys.argv[3:]:
            measure(aoview, exact, float(shift), work)


main()
