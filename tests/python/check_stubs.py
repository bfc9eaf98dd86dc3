"""The type stubs (python/aoview/__init__.pyi) under Debian's mypy: an example of every entry point
passes with no error, and a wrong one gets its four errors (an unknown setting, a setting of the
wrong type, a result used as what it is not, a sampling the course has not). Exits 77 without mypy.
Run by `meson test --suite python` as "python types" (PYTHONPATH set there to the built package)."""
import os
import subprocess
import sys
import tempfile

GOOD = '''
import numpy as np
import numpy.typing as npt
import aoview
from aoview import ray_mesh_intersect

scene = aoview.Scene.from_arrays(np.zeros((3, 3)), [[0, 1, 2]], ground=True, camera=None)
other = aoview.Scene.load('scene.obj', crease_angle=30.0, bvh='compact', scene_budget='1G')
image: npt.NDArray[np.float32] = aoview.render(scene, size=(64, 48), spp=16, sampling='cosine', aa=False,
                                               target_error=0.01, threads=2, below_surface='trace')
for p in aoview.passes(scene, spppp='auto', sampler='sobol', reference=image):
    print(p.number, p.image.shape, p.error)
for p in aoview.progressive(scene, True, 10, 4, aoview.UNIFORM_SAMPLING, size=(32, 24)):
    print(f'spp {p.mean_spp:.0f} of {p.target_spp}')
t, ids, barys = ray_mesh_intersect(np.zeros((1, 3)), np.ones((1, 3)), np.zeros((3, 3)), [[0, 1, 2]],
                                   use_embree=True)
rmi = aoview.ray_mesh_intersect_precompute(np.zeros((3, 3)), [[0, 1, 2]])
t2, ids2, barys2 = rmi.intersect(np.zeros((1, 3)), np.ones((1, 3)), tnear=0.0)
t3 = ray_mesh_intersect(t, t, None, None, intersector=rmi)[0]
exact: npt.NDArray[np.float32] = aoview.exact(scene, size=(16, 12), aa=True)
version: str = aoview.__version__
'''

BAD = '''
import aoview
scene = aoview.Scene.load('x.obj')
aoview.render(scene, spp='many')
aoview.render(scene, colour=True)
n: int = aoview.ray_mesh_intersect([[0, 0, 0]], [[0, 0, 1]], [[0, 0, 0]], [[0, 0, 0]])[0]
aoview.progressive(scene, sampling_type='gaussian')
'''


def main():
    if subprocess.run([sys.executable, '-m', 'mypy', '--version'], capture_output=True).returncode != 0:
        print('mypy is not installed (Debian: mypy)')
        return 77
    with tempfile.TemporaryDirectory() as folder:
        for name, text in (('good.py', GOOD), ('bad.py', BAD)):
            with open(os.path.join(folder, name), 'w') as out:
                out.write(text)
        run = subprocess.run([sys.executable, '-m', 'mypy', '--no-incremental', '--cache-dir', os.devnull, 'good.py',
                              'bad.py'], capture_output=True, text=True, cwd=folder, env=dict(os.environ, MYPYPATH=''))
    print(run.stdout, run.stderr, sep='')
    errors = [line for line in run.stdout.splitlines() if ': error:' in line]
    good = [e for e in errors if e.startswith('good.py')]
    bad = sorted(int(e.split(':')[1]) for e in errors if e.startswith('bad.py'))
    if good or bad != [4, 5, 6, 7]:
        print(f'expected no error in good.py and errors at lines 4-7 of bad.py, got {good} and lines {bad}')
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
