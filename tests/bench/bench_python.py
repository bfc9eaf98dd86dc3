"""Benchmark of the Python module aoview (prints figures, asserts nothing but sanity):

  ray_mesh_intersect: N M rays/s
      1M random rays (float64 in and out, conversions included) at the bunny (assets/bunny.obj),
      median of 5 calls on --threads (default 2);
  ray_mesh_intersect_precompute, 1M triangles: X s for 20 calls of 10,000 rays, Y s for one call of
      the same 200,000 rays (ratio)
      a 1M-triangle bumpy height field: the BVH built once (ray_mesh_intersect_precompute) and 20
      batches of 10,000 rays through it, against one plain ray_mesh_intersect call of the 200,000
      (which builds the BVH too), and 20 plain calls of 10,000 (a build each); medians of 3, the
      answers checked equal;
  progressive AO, 160x120 sphere on a plane: numpy X s, aoview Y s to 1 % RMSE (ratio)
      wall seconds until the running average is within 0.01 RMSE of aoview.exact's image: the
      assignment's estimator written here in plain vectorized numpy (one jittered eye ray and one
      cosine-weighted AO ray per pixel a pass, analytic sphere and ground quad, one thread), against
      aoview.passes with its defaults on the same threads; median of 3 runs each, interleaved.

Run: PYTHONPATH=build/python /usr/bin/python3 tests/bench/bench_python.py [--threads N]
(or meson test -C build --benchmark python)."""
import argparse
import os
import statistics
import time

import numpy as np

import aoview

ROOT = os.environ.get('AO_SOURCE_ROOT', os.path.join(os.path.dirname(__file__), '..', '..'))


def read_obj(path):
    v, f = [], []
    for line in open(path):
        p = line.split()
        if p and p[0] == 'v':
            v.append([float(x) for x in p[1:4]])
        elif p and p[0] == 'f':
            f.append([int(x.split('/')[0]) - 1 for x in p[1:4]])
    return np.array(v), np.array(f)


def bench_rays(threads):
    v, f = read_obj(os.path.join(ROOT, 'assets/bunny.obj'))
    rng = np.random.default_rng(1)
    n = 1_000_000
    lo, hi = v.min(axis=0), v.max(axis=0)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo)
    u = rng.normal(size=(n, 3))
    origins = centre + radius * u / np.linalg.norm(u, axis=1, keepdims=True)
    directions = rng.uniform(lo, hi, size=(n, 3)) - origins
    times = []
    for _ in range(5):
        start = time.perf_counter()
        t, ids, _ = aoview.ray_mesh_intersect(origins, directions, v, f, threads=threads)
        times.append(time.perf_counter() - start)
    hits = (ids >= 0).mean()
    print(f'ray_mesh_intersect: {n / statistics.median(times) / 1e6:.1f} M rays/s '
          f'({n} rays, {len(f)} triangles, {100 * hits:.0f} % hit, {threads} threads, '
          f'median of 5: {statistics.median(times) * 1e3:.0f} ms)')


def height_field(n):
    """A bumpy n x n grid over [-1, 1]^2: 2 n^2 triangles."""
    x, z = np.meshgrid(np.linspace(-1, 1, n + 1), np.linspace(-1, 1, n + 1))
    v = np.stack([x.ravel(), 0.1 * (np.sin(9 * x) * np.cos(7 * z)).ravel(), z.ravel()], axis=1)
    a = (np.arange(n)[None, :] + (n + 1) * np.arange(n)[:, None]).ravel()
    f = np.concatenate([np.stack([a, a + n + 1, a + 1], axis=1), np.stack([a + 1, a + n + 1, a + n + 2], axis=1)])
    return v, f


def bench_precompute(threads):
    v, f = height_field(708)   # 1,002,528 triangles
    rng = np.random.default_rng(2)
    n, calls = 10_000, 20
    origins = rng.uniform(-1, 1, (n * calls, 3)) * (1, 0, 1) + (0, 1, 0)
    directions = rng.normal(size=(n * calls, 3)) * (0.3, 0, 0.3) - (0, 1, 0)

    def precomputed():
        rmi = aoview.ray_mesh_intersect_precompute(v, f)
        return [rmi.intersect(origins[k * n:(k + 1) * n], directions[k * n:(k + 1) * n], threads=threads)
                for k in range(calls)]

    def plain_each():
        return [aoview.ray_mesh_intersect(origins[k * n:(k + 1) * n], directions[k * n:(k + 1) * n], v, f,
                                          threads=threads) for k in range(calls)]

    def timed(run):
        times, result = [], None
        for _ in range(3):
            start = time.perf_counter()
            result = run()
            times.append(time.perf_counter() - start)
        return statistics.median(times), result

    x, batches = timed(precomputed)
    y, whole = timed(lambda: aoview.ray_mesh_intersect(origins, directions, v, f, threads=threads))
    z, _ = timed(plain_each)
    for got, expected in zip((np.concatenate(a) for a in zip(*batches)), whole):
        assert np.array_equal(got, expected)
    print(f'ray_mesh_intersect_precompute, {len(f)} triangles: {x:.3f} s for {calls} calls of {n} rays, '
          f'{y:.3f} s for one call of the same {n * calls} ({x / y:.2f}x; {calls} plain calls: {z:.3f} s, '
          f'{z / y:.1f}x), {threads} threads, medians of 3')


# ---------------------------------------------------------------- the assignment's estimator in numpy

def camera_rays(eye, target, up, fov, w, h, jitter):
    """Unit eye ray directions through each pixel at the jitter offsets (h, w, 2), as aoview's camera."""
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    t = np.tan(np.radians(fov) / 2)
    j, i = np.mgrid[0:h, 0:w]
    x = (2 * (i + jitter[..., 0]) / w - 1) * t * w / h
    y = (1 - 2 * (j + jitter[..., 1]) / h) * t
    d = x[..., None] * right + y[..., None] * up + forward
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def hit_sphere(o, d, c, r):
    oc = o - c
    b = np.einsum('...k,...k', oc, d)
    disc = b * b - (np.einsum('...k,...k', oc, oc) - r * r)
    s = np.sqrt(np.maximum(disc, 0))
    t0, t1 = -b - s, -b + s
    t = np.where(t0 > 1e-6, t0, np.where(t1 > 1e-6, t1, np.inf))
    return np.where(disc >= 0, t, np.inf)


def hit_ground(o, d, half):
    with np.errstate(divide='ignore', invalid='ignore'):
        t = -o[..., 1] / d[..., 1]
    p = o + t[..., None] * d
    inside = (np.abs(p[..., 0]) <= half) & (np.abs(p[..., 2]) <= half) & (t > 1e-6)
    return np.where(inside, t, np.inf)


def numpy_pass(rng, w, h, scene):
    eye, target, up, fov, c, r, rho, half = scene
    d = camera_rays(eye, target, up, fov, w, h, rng.random((h, w, 2)))
    o = np.broadcast_to(eye, d.shape)
    ts, tg = hit_sphere(o, d, c, r), hit_ground(o, d, half)
    t = np.minimum(ts, tg)
    hit = np.isfinite(t)
    p = o + np.where(hit, t, 0)[..., None] * d
    n = np.where((ts < tg)[..., None], (p - c) / r, np.array([0.0, 1.0, 0.0]))
    n = np.where((np.einsum('...k,...k', n, d) > 0)[..., None], -n, n)
    # A cosine-weighted direction about n (a uniform disc point lifted to the hemisphere).
    u1, u2 = rng.random((h, w)), rng.random((h, w))
    radius, phi = np.sqrt(u1), 2 * np.pi * u2
    a = np.where((np.abs(n[..., 0]) > 0.9)[..., None], np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0]))
    tx = np.cross(n, a)
    tx /= np.linalg.norm(tx, axis=-1, keepdims=True)
    ty = np.cross(n, tx)
    dirs = (radius * np.cos(phi))[..., None] * tx + (radius * np.sin(phi))[..., None] * ty + \
        np.sqrt(np.maximum(0, 1 - u1))[..., None] * n
    q = p + 1e-4 * n
    blocked = np.isfinite(hit_sphere(q, dirs, c, r)) | np.isfinite(hit_ground(q, dirs, half))
    return np.where(hit, rho * ~blocked, 1.0)   # background 1 where the eye ray misses


def bench_progressive(threads):
    scene = aoview.Scene.load(os.path.join(ROOT, 'assets/scenes/sphere-on-plane.scene'))
    w, h = 160, 120
    reference = aoview.exact(scene, size=(w, h))
    geometry = (np.array([0, 1.6, 3.2]), np.array([0, 0.35, 0]), np.array([0.0, 1.0, 0.0]), 40.0,
                np.array([0, 0.5, 0]), 0.5, 0.8, 1e4)   # sphere-on-plane.scene

    def with_numpy(seed):
        rng = np.random.default_rng(seed)
        start, total, k = time.perf_counter(), np.zeros((h, w)), 0
        while True:
            total += numpy_pass(rng, w, h, geometry)
            k += 1
            if np.sqrt(np.mean((total / k - reference) ** 2)) <= 0.01:
                return time.perf_counter() - start, k

    def with_aoview(seed):
        start = time.perf_counter()
        for p in aoview.passes(scene, size=(w, h), spp=1 << 20, reference=reference, seed=seed, threads=threads):
            if p.rmse <= 0.01:
                return time.perf_counter() - start, p.spp

    numpy_runs, aoview_runs = [], []
    for seed in (1, 2, 3):
        numpy_runs.append(with_numpy(seed))
        aoview_runs.append(with_aoview(seed))
    x = statistics.median(t for t, _ in numpy_runs)
    y = statistics.median(t for t, _ in aoview_runs)
    print(f'progressive AO, 160x120 sphere on a plane: numpy {x:.2f} s, aoview {y:.3f} s to 1 % RMSE '
          f'({x / y:.0f}x; numpy {statistics.median(k for _, k in numpy_runs)} spp on one thread, aoview '
          f'{statistics.median(k for _, k in aoview_runs)} spp on {threads} threads)')


if __name__ == '__main__':
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--threads', type=int, default=2)
    args = parser.parse_args()
    bench_rays(args.threads)
    bench_precompute(args.threads)
    bench_progressive(args.threads)
