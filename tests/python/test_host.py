"""The module as a library is called: from many threads at once, each call's messages its own and
descriptor 2 never touched; with arrays another thread changes under it; with values Embree cannot
take (NaN, infinities, magnitudes past its range), each a ValueError naming the array and the row,
never an abort or a silent miss, while the far values it can take give the right hits. Run by
`meson test --suite python` (AO_SOURCE_ROOT, PYTHONPATH set there)."""
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import aoview

ROOT = os.environ['AO_SOURCE_ROOT']
BUNNY_OBJ = os.path.join(ROOT, 'assets/bunny.obj')
sys.path.insert(0, os.path.join(ROOT, 'tests', 'bench'))
from bench_python import read_obj  # noqa: E402 (the benchmark's OBJ reader)


def run_python(code, tmp_path):
    """code run by this Python in a process of its own (a crash there fails the test, not pytest)."""
    return subprocess.run([sys.executable, '-c', textwrap.dedent(code)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=600)


# ---------------------------------------------------------------- threads and messages

def test_threads_get_their_own_messages_and_stderr_stays(tmp_path):
    """4 threads x 100 calls, each of Scene.load, Scene.from_arrays and ray_mesh_intersect in turn,
    every other one bad in a way that names the call (its file, its scene's name, its row): each
    exception carries its own call's text and no other call's; descriptor 2 is the same file
    afterwards and a line written to it then arrives."""
    run = run_python(r'''
        import os, re, threading
        import numpy as np
        import aoview

        before = os.fstat(2)
        v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
        f = np.array([[0, 1, 2], [0, 2, 3]])
        with open('good.obj', 'w') as out:
            out.write('v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n')
        for i in range(4):
            for j in range(100):
                with open(f'bad-{i}-{j}.scene', 'w') as out:
                    out.write('sphere center 0 0 0\n')
        wrong = []

        def call(i, j):
            bad, kind = j % 2, j // 2 % 3
            mark = f'-{i}-{j}.'
            try:
                if kind == 0:
                    aoview.Scene.load(f'bad{mark}scene' if bad else 'good.obj')
                elif kind == 1:
                    aoview.Scene.from_arrays(v, f[:, [0, 0, 1]] if bad else f, name=f'a{mark}')
                else:
                    o = np.tile([0.5, 0.5, 1.0], (200 + 4 * j + i, 1))
                    if bad:
                        o[100 + 4 * j + i, 0] = np.nan
                    t, ids, _ = aoview.ray_mesh_intersect(o, np.tile([0, 0, -1.0], (len(o), 1)), v, f, threads=2)
                    assert (ids >= 0).all() and np.allclose(t, 1.0)
                if bad:
                    wrong.append(f'{i} {j}: no exception')
            except ValueError as error:
                text = str(error)
                if kind == 2:
                    own = re.findall(r'row (\d+)', text) == [str(100 + 4 * j + i)]
                else:
                    own = re.findall(r'-\d+-\d+\.', text) == [mark]
                if not bad or not own:
                    wrong.append(f'{i} {j}: {text!r}')

        threads = [threading.Thread(target=lambda i=i: [call(i, j) for j in range(100)]) for i in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        after = os.fstat(2)
        print('same descriptor 2' if (before.st_dev, before.st_ino) == (after.st_dev, after.st_ino) else 'moved')
        print('\n'.join(wrong) or 'all own')
        os.write(2, b'a line after the threads\n')
    ''', tmp_path)
    assert run.returncode == 0, run.stderr
    assert run.stdout.split('\n')[:2] == ['same descriptor 2', 'all own'], run.stdout
    assert run.stderr.endswith('a line after the threads\n'), run.stderr


def test_a_loads_notes_are_warnings_and_not_stderr(tmp_path, capfd):
    """What a load leaves out (here one degenerate triangle) is a UserWarning of that call, with the
    line the program prints, and nothing reaches descriptor 2."""
    path = tmp_path / 'degenerate.obj'
    path.write_text('v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n')
    with pytest.warns(UserWarning, match='^aoview: skipped 1 degenerate triangle$'):
        aoview.Scene.load(str(path))
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], dtype=np.float64)
    with pytest.warns(UserWarning, match='^aoview: skipped 1 degenerate triangle$'):
        aoview.Scene.from_arrays(vertices, np.array([[0, 1, 2], [0, 1, 3]]))
    assert capfd.readouterr().err == ''


# ---------------------------------------------------------------- arrays changed by another thread

def test_an_index_flipped_by_another_thread_never_crashes(tmp_path):
    """1,000 calls of Scene.from_arrays and 1,000 of ray_mesh_intersect while another thread flips
    one index of the faces between a good value and one out of range: each call gives a result of
    either value or a ValueError of the bad one, never a crash (the module checks its own copy)."""
    run = run_python(r'''
        import threading
        import numpy as np
        import aoview

        n = 12
        x, z = np.meshgrid(np.linspace(-1, 1, n + 1), np.linspace(-1, 1, n + 1))
        v = np.stack([x.ravel(), 0.1 * np.sin(3 * x).ravel(), z.ravel()], axis=1)
        f = np.array([[j * (n + 1) + i, (j + 1) * (n + 1) + i, j * (n + 1) + i + 1]
                      for j in range(n) for i in range(n)], dtype=np.uint32)
        o = np.tile([0.0, 2.0, 0.0], (64, 1)) + np.linspace(-0.5, 0.5, 64)[:, None] * [1, 0, 0]
        d = np.tile([0.0, -1.0, 0.0], (64, 1))
        stop = threading.Event()

        def flip():
            while not stop.is_set():
                f[5, 1] = 10 ** 9
                f[5, 1] = 1

        flipper = threading.Thread(target=flip)
        flipper.start()
        outcomes = {'scene': 0, 'rays': 0, 'refused': 0}
        try:
            for k in range(1000):
                try:
                    aoview.Scene.from_arrays(v, f, ground=False)
                    outcomes['scene'] += 1
                except ValueError as error:
                    assert 'row 5' in str(error), error
                    outcomes['refused'] += 1
                try:
                    aoview.ray_mesh_intersect(o, d, v, f, threads=1)
                    outcomes['rays'] += 1
                except ValueError as error:
                    assert 'row 5' in str(error), error
                    outcomes['refused'] += 1
        finally:
            stop.set()
            flipper.join()
        print(outcomes)
    ''', tmp_path)
    assert run.returncode == 0, run.stderr
    outcomes = eval(run.stdout)
    assert sum(outcomes.values()) == 2000 and outcomes['scene'] and outcomes['rays'], outcomes


# ---------------------------------------------------------------- values Embree cannot take

def bunny():
    return read_obj(BUNNY_OBJ)


@pytest.mark.parametrize('array,row', [('origins', 3), ('directions', 7), ('vertices', 11)])
@pytest.mark.parametrize('value', [1e19, -1e19, np.inf, np.nan, 3e38])
def test_values_embree_cannot_take_raise(array, row, value):
    v, f = bunny()
    rng = np.random.default_rng(4)
    arrays = {'origins': rng.uniform(-1, 1, (20, 3)) + (0, 0, 5), 'directions': np.tile([0, 0, -1.0], (20, 1)),
              'vertices': v.copy()}
    arrays[array][row, 1] = value
    with pytest.raises(ValueError, match=f'{array}: row {row} '):
        aoview.ray_mesh_intersect(arrays['origins'], arrays['directions'], arrays['vertices'], f)


def test_meshes_outside_the_scenes_range_raise():
    """A mesh scaled by 1e19 (past magnitudes) or 1e10 (2^31 across, the scenes' range: the
    triangle test's products would pass the float range) or 1e-5 (under 2^-12 across: they would
    flush to zero): ValueError naming the rows, never a miss."""
    v, f = bunny()
    for scale, message in [(1e19, 'vertices: row'), (1e10, 'across'), (1e-5, 'across')]:
        with pytest.raises(ValueError, match=message):
            aoview.ray_mesh_intersect([[0, 0, 5 * scale]], [[0, 0, -1]], v * scale, f)
    with pytest.raises(ValueError, match=r'vertices: the mesh is \d\.\d+e\+10 across \(rows \d+ and \d+\)'):
        aoview.ray_mesh_intersect_precompute(v * 1e10, f)


def test_far_origins_and_long_directions_hit_what_near_ones_hit():
    """Rays along the axes into the bunny from 1e18 away (within Embree's 1.84e18), with directions
    of 1e18 and of 1e-30, hit the triangle the same rays hit from nearby, the nearest one (a closed
    mesh has a back face on every such line, which the float rounding of 1e18 would tie with the
    front one), at t within the rounding of the distance."""
    v, f = bunny()
    lo, hi = v.min(axis=0), v.max(axis=0)
    rng = np.random.default_rng(6)
    for axis in range(3):
        for sign in (1, -1):
            o = rng.uniform(lo + 0.3 * (hi - lo), hi - 0.3 * (hi - lo), (500, 3))
            d = np.zeros((500, 3))
            d[:, axis] = -sign
            near = o.copy()
            near[:, axis] = (hi[axis] if sign > 0 else lo[axis]) + sign
            far = o.copy()
            far[:, axis] = sign * 1e18
            t, ids, barys = aoview.ray_mesh_intersect(near, d, v, f, tnear=0.0)
            assert (ids >= 0).mean() > 0.5
            for origins, directions, scale in [(far, d, 1.0), (near, d * 1e18, 1e18), (near, d * 1e-30, 1e-30)]:
                # tnear=0: tnear is in the directions' units (1e-4 of a direction of 1e18 is 1e14).
                t2, ids2, barys2 = aoview.ray_mesh_intersect(origins, directions, v, f, tnear=0.0)
                assert np.array_equal(ids2, ids)
                hit = ids >= 0
                assert np.allclose(barys2[hit], barys[hit], atol=1e-5)
                offset = np.abs(origins[hit, axis] - near[hit, axis])
                assert np.allclose(t2[hit] * scale, t[hit] + offset, rtol=1e-6, atol=1e-5)
    # A zero direction meets nothing.
    t, ids, barys = aoview.ray_mesh_intersect([[0, 0, 0]], [[0, 0, 0]], v, f)
    assert ids[0] == -1 and np.isinf(t[0]) and not barys.any()
