"""The Python module aoview against the programs it shares its code with: render() is the PFM that
`aoview --headless` writes, bit for bit (the bunny, and a scene from arrays against the OBJ file of
the same arrays); passes() are the rows of --stats; exact() is aoview-exact's PFM;
ray_mesh_intersect() agrees with a brute-force Moller-Trumbore in numpy; bad arrays and settings
raise ValueError or TypeError with the command line's messages, never crash (a property test
fuzzes the checks); Ctrl-C interrupts a render within a pass; the GIL is released while tracing.
Run by `meson test --suite python` (AO_BINARY, AO_EXACT, AO_SOURCE_ROOT, PYTHONPATH set there)."""
import csv
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import aoview

ROOT = os.environ['AO_SOURCE_ROOT']
AOVIEW = os.environ['AO_BINARY']
EXACT = os.environ['AO_EXACT']
BUNNY = os.path.join(ROOT, 'assets/scenes/bunny.scene')
SPHERE_ON_PLANE = os.path.join(ROOT, 'assets/scenes/sphere-on-plane.scene')
BUNNY_OBJ = os.path.join(ROOT, 'assets/bunny.obj')
sys.path.insert(0, os.path.join(ROOT, 'tests', 'bench'))
from bench_python import read_obj  # noqa: E402 (the benchmark's OBJ reader, on the path set above)


def read_pfm(path):
    """A PFM (PF, colour) as an (h, w, 3) float32 array, row 0 at the top."""
    with open(path, 'rb') as f:
        assert f.readline() == b'PF\n'
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype='<f4' if scale < 0 else '>f4')
    return data.reshape(h, w, 3)[::-1].astype(np.float32)


def cli(tmp_path, scene, *args, stats=False):
    """aoview --headless's PFM (and --stats rows) for scene with args."""
    out = tmp_path / 'cli.pfm'
    cmd = [AOVIEW, '--headless', '-q', '-o', str(out)] + list(args) + [str(scene)]
    if stats:
        cmd[1:1] = ['--stats', str(tmp_path / 'stats.csv')]
    subprocess.run(cmd, check=True)
    rows = list(csv.DictReader(open(tmp_path / 'stats.csv'))) if stats else None
    return read_pfm(out), rows


def as_rgb(image):
    return image if image.ndim == 3 else np.repeat(image[:, :, None], 3, axis=2)


# ---------------------------------------------------------------- render and passes against the CLI

@pytest.mark.parametrize('settings,args', [
    (dict(size=(160, 120), spp=64), ['--size', '160x120', '--spp', '64']),
    (dict(size=(96, 64), spp=32, sampling='uniform', sampler='random', adaptive=False, spppp=4, seed=7, threads=1),
     ['--size', '96x64', '--spp', '32', '--sampling', 'uniform', '--sampler', 'random', '--adaptive', 'off',
      '--spppp', '4', '--seed', '7', '--threads', '1']),
    (dict(size=(80, 60), spp=16, aa=False, sampling='hemisphere', shading='flat'),
     ['--size', '80x60', '--spp', '16', '--no-aa', '--sampling', 'hemisphere', '--shading', 'flat']),
])
def test_render_is_the_cli_pfm(tmp_path, settings, args):
    scene = aoview.Scene.load(BUNNY)
    image = aoview.render(scene, **settings)
    expected, _ = cli(tmp_path, BUNNY, *args)
    assert image.dtype == np.float32 and image.shape[:2] == expected.shape[:2]
    assert np.array_equal(as_rgb(image), expected)


def bumpy_grid(n=12, seed=3):
    """A bumpy height field of (n+1)^2 vertices (float64) with a spike, and its 2 n^2 triangles."""
    rng = np.random.default_rng(seed)
    x, z = np.meshgrid(np.linspace(-1, 1, n + 1), np.linspace(-1, 1, n + 1))
    y = 0.15 * rng.random(x.shape)
    y[n // 2, n // 2] = 0.8
    v = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    faces = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            faces += [[a, a + n + 1, a + 1], [a + 1, a + n + 1, a + n + 2]]
    return v, np.array(faces, dtype=np.int64)


def write_obj(path, v, f):
    with open(path, 'w') as out:
        for p in v.astype(np.float32):
            out.write('v %.9g %.9g %.9g\n' % tuple(float(x) for x in p))
        for t in f:
            out.write('f %d %d %d\n' % tuple(int(i) + 1 for i in t))


def test_from_arrays_is_the_obj_scene(tmp_path):
    v, f = bumpy_grid()
    obj = tmp_path / 'grid.obj'
    write_obj(obj, v, f)
    args = ['--size', '120x90', '--spp', '32']
    expected, _ = cli(tmp_path, obj, *args)
    for vertices, faces in [(v, f), (v.astype(np.float32), f.astype(np.uint16))]:
        image = aoview.render(aoview.Scene.from_arrays(vertices, faces), size=(120, 90), spp=32)
        assert image.ndim == 2   # a grey scene
        assert np.array_equal(as_rgb(image), expected)
    assert np.array_equal(aoview.render(aoview.Scene.load(obj), size=(120, 90), spp=32), image)
    # Without the ground, as --ground off.
    expected, _ = cli(tmp_path, obj, '--ground', 'off', *args)
    image = aoview.render(aoview.Scene.from_arrays(v, f, ground=False), size=(120, 90), spp=32)
    assert np.array_equal(as_rgb(image), expected)


def test_from_arrays_with_spheres_camera_and_albedo():
    v, f = bumpy_grid()
    scene = aoview.Scene.from_arrays(v, f, spheres=[((0, 0.5, 0), 0.3), ((0.5, 0.4, 0.5), 0.2, (1, 0.5, 0.5))],
                                     albedo=(0.5, 0.6, 0.7), camera=dict(eye=(0, 2, 3), target=(0, 0, 0), fov=30))
    image = aoview.render(scene, size=(64, 48), spp=16)
    assert image.shape == (48, 64, 3) and np.isfinite(image).all()
    assert 0.0 < image.min() and image.max() <= 1.0
    # The sphere over the centre darkens the grid under it: the picture differs from the one without.
    bare = aoview.render(aoview.Scene.from_arrays(v, f, albedo=(0.5, 0.6, 0.7),
                                                  camera=dict(eye=(0, 2, 3), target=(0, 0, 0), fov=30)),
                         size=(64, 48), spp=16)
    assert np.abs(bare - image).max() > 0.1


def test_passes_are_the_stats_rows(tmp_path):
    scene = aoview.Scene.load(BUNNY)
    reference = aoview.render(scene, size=(96, 72), spp=512, seed=99)
    ref_path = tmp_path / 'ref.pfm'
    with open(ref_path, 'wb') as out:   # the same reference as a file, for the CLI
        out.write(b'PF\n96 72\n-1.0\n' + np.ascontiguousarray(reference[::-1], dtype='<f4').tobytes())
    expected, rows = cli(tmp_path, BUNNY, '--size', '96x72', '--spp', '64', '--reference', str(ref_path), stats=True)
    got = list(aoview.passes(scene, size=(96, 72), spp=64, reference=reference))
    assert len(got) == len(rows) and got[-1].done and not any(p.done for p in got[:-1])
    for p, row in zip(got, rows):
        assert p.number == int(row['pass']) and p.spp == int(row['spp'])
        assert p.eye_rays == int(row['eye_rays']) and p.shadow_rays == int(row['shadow_rays'])
        assert f'{p.mean_spp:.3f}' == row['mean_spp'] and f'{p.converged:.4f}' == row['converged']
        assert f'{p.error:.6g}' == row['error'] and f'{p.rmse:.9g}' == row['rmse']
    assert np.array_equal(got[-1].image, expected)
    assert all(np.isfinite(p.image).all() for p in got)
    assert got[0].image is not got[1].image and not np.array_equal(got[0].image, got[-1].image)
    # A reference file gives the same RMSE as the array.
    by_file = list(aoview.passes(scene, size=(96, 72), spp=64, reference=str(ref_path)))
    assert [p.rmse for p in by_file] == [p.rmse for p in got]


def test_breaking_out_of_passes_stops_the_render():
    scene = aoview.Scene.load(BUNNY)
    start = time.monotonic()
    for p in aoview.passes(scene, size=(320, 240), spp=1 << 20, spppp=1):
        if p.number == 3:
            break
    assert p.number == 3 and time.monotonic() - start < 10


def test_exact_is_aoview_exact(tmp_path):
    scene = aoview.Scene.load(SPHERE_ON_PLANE)
    for args, settings in [([], {}), (['--no-aa'], dict(aa=False)), (['--spp', '64'], dict(spp=64))]:
        out = tmp_path / 'exact.pfm'
        subprocess.run([EXACT, '-q', '--size', '80x60', '-o', str(out)] + args + [SPHERE_ON_PLANE], check=True)
        image = aoview.exact(scene, size=(80, 60), **settings)
        assert np.array_equal(as_rgb(image), read_pfm(out))
    with pytest.raises(ValueError, match='no closed form'):
        aoview.exact(aoview.Scene.load(BUNNY), size=(16, 12))


# ---------------------------------------------------------------- ray_mesh_intersect

def moller_trumbore(origins, directions, v, f):
    """Closest hits by brute force in float64: (t, ids, barys) with gpytoolbox's conventions."""
    t = np.full(len(origins), np.inf)
    ids = np.full(len(origins), -1)
    barys = np.zeros((len(origins), 3))
    p0, p1, p2 = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    for i, (o, d) in enumerate(zip(origins, directions)):
        h = np.cross(d, e2)
        a = np.einsum('ij,ij->i', e1, h)
        with np.errstate(divide='ignore', invalid='ignore'):
            inv = 1.0 / a
            s = o - p0
            u = inv * np.einsum('ij,ij->i', s, h)
            q = np.cross(s, e1)
            w = inv * (q @ d)
            tt = inv * np.einsum('ij,ij->i', e2, q)
        ok = (np.abs(a) > 1e-14) & (u >= 0) & (w >= 0) & (u + w <= 1) & (tt > 0)
        if ok.any():
            k = np.flatnonzero(ok)[np.argmin(tt[ok])]
            t[i], ids[i], barys[i] = tt[k], k, (1 - u[k] - w[k], u[k], w[k])
    return t, ids, barys


def test_ray_mesh_intersect_against_brute_force():
    v, f = read_obj(BUNNY_OBJ)
    rng = np.random.default_rng(5)
    n = 3000
    lo, hi = v.min(axis=0), v.max(axis=0)
    origins = rng.uniform(lo - (hi - lo), hi + (hi - lo), size=(n, 3))
    targets = rng.uniform(lo, hi, size=(n, 3))
    directions = (targets - origins) * rng.uniform(0.5, 2.0, size=(n, 1))   # not unit
    directions[:200] = -directions[:200]   # mostly misses
    t, ids, barys = aoview.ray_mesh_intersect(origins, directions, v, f)
    assert t.shape == (n,) and ids.shape == (n,) and barys.shape == (n, 3)
    assert t.dtype == np.float64 and ids.dtype == np.int32 and barys.dtype == np.float64
    bt, bids, bbarys = moller_trumbore(origins, directions, v, f)
    same = ids == bids
    # Rays the two disagree on must be ties: a hit within rounding of an edge (the other triangle
    # sharing it at the same t) or of a silhouette. 99.9 % must agree exactly.
    assert same.mean() >= 0.999, f'{(~same).sum()} of {n} rays differ'
    for i in np.flatnonzero(~same):
        assert ids[i] >= 0 and bids[i] >= 0 and abs(t[i] - bt[i]) <= 1e-4 * bt[i] or \
            min(barys[i].min() if ids[i] >= 0 else 1, bbarys[i].min() if bids[i] >= 0 else 1) < 1e-4
    hit = same & (ids >= 0)
    assert 0.2 * n < hit.sum() < 0.95 * n
    # Single precision against double: t and the weights within float rounding of the scene's size.
    assert np.allclose(t[hit], bt[hit], rtol=1e-4, atol=1e-6)
    assert np.allclose(barys[hit], bbarys[hit], atol=1e-3)
    miss = ids < 0
    assert np.isinf(t[miss]).all() and (barys[miss] == 0).all()


def test_ray_mesh_intersect_any_layout():
    """Strides, byte order, integer vertices and any integer faces give the same answer."""
    v, f = bumpy_grid()
    rng = np.random.default_rng(1)
    o = rng.uniform(-1, 1, size=(500, 3)) + (0, 2, 0)
    d = rng.normal(size=(500, 3)) - (0, 2, 0)
    base = aoview.ray_mesh_intersect(o, d, v, f)
    variants = [
        (o.astype('>f8'), d.astype('>f4'), v.astype('>f8'), f.astype('>i4')),
        (np.asfortranarray(o), d[::1], np.repeat(v, 2, axis=0)[::2], f.astype(np.uint8)),
        (np.ascontiguousarray(np.hstack([o, o])[:, ::2][:, :3]) if False else o, d.tolist(), v.tolist(), f.tolist()),
    ]
    for vo, vd, vv, vf in variants:
        got = aoview.ray_mesh_intersect(vo, vd, vv, vf)
        for a, b in zip(got, base):
            assert np.array_equal(a, b)
    strided = np.zeros((500, 6))
    strided[:, ::2] = o
    got = aoview.ray_mesh_intersect(strided[:, ::2], d, v, f)
    assert all(np.array_equal(a, b) for a, b in zip(got, base))
    empty = aoview.ray_mesh_intersect(np.zeros((0, 3)), np.zeros((0, 3)), v, f)
    assert [a.shape for a in empty] == [(0,), (0,), (0, 3)]


# ---------------------------------------------------------------- bad input

def test_bad_arrays_raise():
    v, f = bumpy_grid(4)
    cases = [
        (TypeError, 'dtype', lambda: aoview.Scene.from_arrays(v.astype(complex), f)),
        (TypeError, 'integers', lambda: aoview.Scene.from_arrays(v, f.astype(float))),
        (TypeError, 'dtype', lambda: aoview.Scene.from_arrays(np.array([['a', 'b', 'c']]), f)),
        (ValueError, r'shape \(n, 3\)', lambda: aoview.Scene.from_arrays(v[:, :2], f)),
        (ValueError, r'shape \(m, 3\)', lambda: aoview.Scene.from_arrays(v, f.ravel())),
        (ValueError, 'empty', lambda: aoview.Scene.from_arrays(v[:0], f)),
        (ValueError, 'empty', lambda: aoview.Scene.from_arrays(v, f[:0])),
        (ValueError, 'not finite', lambda: aoview.Scene.from_arrays(np.where(v == v[3], np.nan, v), f)),
        (ValueError, 'not finite', lambda: aoview.Scene.from_arrays(v * 1e300, f)),
        (ValueError, 'out of range', lambda: aoview.Scene.from_arrays(v, f + len(v) - 1)),
        (ValueError, 'out of range', lambda: aoview.Scene.from_arrays(v, -f)),
        (ValueError, 'no triangles', lambda: aoview.Scene.from_arrays(v, np.zeros((3, 3), int))),
        (ValueError, 'normals', lambda: aoview.Scene.from_arrays(v, f, normals=v[:-1])),
        (ValueError, 'radius', lambda: aoview.Scene.from_arrays(v, f, spheres=[((0, 0, 0), -1)])),
        (ValueError, r'\[0,1\]', lambda: aoview.Scene.from_arrays(v, f, albedo=1.5)),
        (ValueError, 'camera', lambda: aoview.Scene.from_arrays(v, f, camera=dict(eye=(0, 0, 1), target=(0, 0, 1)))),
        (ValueError, 'fov', lambda: aoview.Scene.from_arrays(v, f, camera=dict(eye=(0, 0, 1), target=(0, 0, 0), fov=180))),
        (TypeError, 'camera', lambda: aoview.Scene.from_arrays(v, f, camera=(0, 0, 1))),
        (ValueError, 'origins and directions', lambda: aoview.ray_mesh_intersect(v[:2], v[:3], v, f)),
        (ValueError, 'not finite', lambda: aoview.ray_mesh_intersect([[0, 0, np.inf]], [[0, 0, 1]], v, f)),
        (FileNotFoundError, 'no such file', lambda: aoview.Scene.load('/nonexistent.obj')),
    ]
    for kind, message, call in cases:
        with pytest.raises(kind, match=message):
            call()


def test_bad_settings_have_the_cli_messages(tmp_path):
    scene = aoview.Scene.from_arrays(*bumpy_grid(4))
    for settings, option in [(dict(spp=0), '--spp'), (dict(sampling='gaussian'), '--sampling'),
                             (dict(size=(0, 10)), '--size'), (dict(threads=1000), '--threads'),
                             (dict(spppp='sometimes'), '--spppp'), (dict(target_error=-1.0), '--target-error')]:
        with pytest.raises(ValueError, match=option):
            aoview.render(scene, **settings)
        # The very message of the command line.
        args = [a for k, x in settings.items() for a in aoview._argv({k: x}, [k], 'render')[1:]]
        cmd = subprocess.run([AOVIEW, '--headless', '-o', str(tmp_path / 'x.pfm')] + args, capture_output=True,
                             text=True)
        assert cmd.returncode == 2
        with pytest.raises(ValueError) as raised:
            aoview.render(scene, **settings)
        assert str(raised.value) in cmd.stderr
    for settings in [dict(colour=True), dict(aa='yes'), dict(size=640), dict(spp=[1])]:
        with pytest.raises(TypeError):
            aoview.render(scene, **settings)
    with pytest.raises(ValueError, match=r'reference: expected the image size 32x24'):
        aoview.render(scene, size=(32, 24), reference=np.zeros((10, 10)))
    with pytest.raises(ValueError, match='no-such.pfm'):
        aoview.render(scene, size=(32, 24), reference=str(tmp_path / 'no-such.pfm'))
    with pytest.raises(ValueError, match='crease'):
        aoview.Scene.load(BUNNY, crease_angle=500)
    with pytest.raises(ValueError, match="--crease-angle: expected degrees from 0 to 180, got ''"):
        aoview.Scene.load(BUNNY, crease_angle='')   # the command line's parser: '' is no number
    with pytest.raises(ValueError, match='--scene-budget'):
        aoview.Scene.load(BUNNY, scene_budget='1K')
    with pytest.raises(ValueError, match='nothing.scene:1: '):   # the loader's file:line message
        (tmp_path / 'nothing.scene').write_text('sphere center 0 0 0\n')
        aoview.Scene.load(tmp_path / 'nothing.scene')


def test_fuzzed_arrays_never_crash():
    """Random shapes, dtypes, byte orders and values: every call returns or raises ValueError or
    TypeError (a crash would end the test process)."""
    rng = np.random.default_rng(2026)
    specials = [np.nan, np.inf, -np.inf, 1e39, -1e300, 0.0, 1e-40]

    def random_array(kind, rows=None):
        """Mostly a good array of its kind ('v' positions, 'f' faces into `rows` vertices), else broken
        in one way: a shape, an emptiness, a dtype, a value, an order or a stride."""
        n = int(rng.integers(1, 8)) if rows is None else int(rng.integers(1, 8))
        a = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-3, 4) if kind == 'v' else \
            rng.integers(0, max(rows, 1), size=(n, 3))
        flaw = rng.integers(0, 12)
        with np.errstate(all='ignore'):
            if flaw == 0:
                a = a.reshape(-1)[:int(rng.integers(0, a.size + 1))]
            elif flaw == 1:
                a = a[:0]
            elif flaw == 2:
                a = a[:, :int(rng.integers(0, 3))]
            elif flaw == 3:
                a = a.astype([complex, bool, object, 'U3'][rng.integers(0, 4)])
            elif flaw == 4 and kind == 'v':
                a.flat[rng.integers(0, a.size)] = specials[rng.integers(0, len(specials))]
            elif flaw == 4:
                a.flat[rng.integers(0, a.size)] = [-1, rows, 2 ** 40][rng.integers(0, 3)]
            elif flaw == 5:
                a = a[:, :, None]
            a = a.astype(good[kind][rng.integers(0, len(good[kind]))]) if flaw >= 6 else a
        return a if rng.random() < 0.7 or a.ndim == 0 else a[::-1]

    good = {'v': [np.float64, np.float32, '>f8', np.float16, np.int32], 'f': [np.int64, np.uint16, '>i4', np.int8]}
    outcomes = {'ok': 0, 'refused': 0}
    for _ in range(400):
        v = random_array('v')
        f = random_array('f', len(v) if v.ndim else 1)
        try:
            if rng.random() < 0.5:
                aoview.Scene.from_arrays(v, f, ground=bool(rng.random() < 0.5))
            else:
                aoview.ray_mesh_intersect(random_array('v'), random_array('v'), v, f, threads=int(rng.integers(1, 3)))
            outcomes['ok'] += 1
        except (ValueError, TypeError):
            outcomes['refused'] += 1
    assert outcomes['ok'] > 10 and outcomes['refused'] > 10, outcomes


# ---------------------------------------------------------------- threads and signals

def test_ctrl_c_interrupts_a_pass():
    scene = aoview.Scene.load(BUNNY)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        # One pass of 4096 spp at 640x480 takes tens of seconds on two cores: the interrupt comes
        # within it.
        aoview.render(scene, size=(640, 480), spp=4096, spppp=4096, adaptive=False)
    assert time.monotonic() - start < 3.0
    timer.join()
    # The module still works afterwards.
    assert aoview.render(scene, size=(32, 24), spp=4).shape == (24, 32, 3)


def test_ctrl_c_in_passes():
    scene = aoview.Scene.load(BUNNY)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        for _ in aoview.passes(scene, size=(640, 480), spp=4096, spppp=4096, adaptive=False):
            pass
    assert time.monotonic() - start < 3.0
    timer.join()


def test_the_gil_is_released_while_tracing():
    scene = aoview.Scene.load(BUNNY)
    done = threading.Event()
    count = 0

    def work():
        aoview.render(scene, size=(320, 240), spp=256, threads=1)
        done.set()

    worker = threading.Thread(target=work)
    worker.start()
    while not done.is_set():
        count += 1
        time.sleep(0.001)
    worker.join()
    assert count > 20   # the main thread ran throughout the render


# ---------------------------------------------------------------- the examples run

@pytest.mark.parametrize('example,args', [('progressive.py', []), ('error_chart.py', ['--seconds', '0.2'])])
def test_examples_write_their_png(tmp_path, example, args):
    pytest.importorskip('matplotlib')
    out = tmp_path / 'out.png'
    env = dict(os.environ)
    env.pop('DISPLAY', None)
    subprocess.run([sys.executable,
                    os.path.join(ROOT, 'examples', example), '-o', str(out)] + args, check=True, env=env,
                   cwd=tmp_path, capture_output=True)
    assert out.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
