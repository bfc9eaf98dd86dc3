#!/usr/bin/env python3
"""The measurement behind --crease-angle's default (docs/formats.md, "Normals a file lacks"): each
test shape without normals (tests/tools/shapes.py: a cube, a coarse sphere, a CAD-like part; and the
shipped bunny) rendered bare at a range of crease angles, against what it should look like: the
cube flat (--shading flat), the sphere and the part with their exact normals (shapes.py --normals),
the bunny, a scan, smoothed everywhere (crease 180). Prints a Markdown table of the mean
|difference| over the pixels, per shape and the worst of them, and the noise of one render
(another seed) for scale:

    tests/tools/crease_angles.py AOVIEW [ao|normals]     (run from anywhere; needs numpy)
"""
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
CREASES = [0, 10, 20, 25, 30, 35, 40, 44, 50, 60, 90, 120, 180]


def main(argv):
    aoview, view = argv[1], argv[2] if len(argv) > 2 else 'ao'
    work = tempfile.mkdtemp()
    for shape in ('cube', 'sphere', 'part'):
        for extra in ([], ['--normals']):
            name = shape + ('_exact' if extra else '') + '.obj'
            subprocess.run([sys.executable, os.path.join(HERE, 'shapes.py'), shape, os.path.join(work, name)] + extra,
                           check=True)
    bunny = os.path.join(HERE, '..', '..', 'assets', 'bunny.obj')

    def render(model, *extra):
        out = os.path.join(work, 'out.pfm')
        subprocess.run([aoview, '--headless', '-q', '--size', '320x240', '--spp', '256', '--seed', '1',
                        '--view', view] + list(extra) + ['-o', out, model], check=True)
        head = open(out, 'rb').read().split(b'\n', 3)
        w, h = map(int, head[1].split())
        return np.frombuffer(head[3], '<f4').reshape(h, w, 3).astype(np.float64)

    shapes = {'bunny': (bunny, bunny, ['--crease-angle', '180']),
              'cube': (os.path.join(work, 'cube.obj'), os.path.join(work, 'cube.obj'), ['--shading', 'flat']),
              'sphere': (os.path.join(work, 'sphere.obj'), os.path.join(work, 'sphere_exact.obj'), []),
              'part': (os.path.join(work, 'part.obj'), os.path.join(work, 'part_exact.obj'), [])}
    refs = {k: render(ideal, *how) for k, (_, ideal, how) in shapes.items()}
    noise = {k: np.abs(render(ideal, '--seed', '2', *how) - refs[k]).mean() for k, (_, ideal, how) in shapes.items()}
    print('%s view, 320x240, 256 spp, mean |difference| from how each should look' % view)
    print('| crease | ' + ' | '.join(shapes) + ' | worst |')
    print('|---|' + '---|' * (len(shapes) + 1))
    print('| noise (seed 2) | ' + ' | '.join('%.5f' % noise[k] for k in shapes) + ' | |')
    for crease in CREASES:
        row = [np.abs(render(model, '--crease-angle', str(crease)) - refs[k]).mean()
               for k, (model, _, _) in shapes.items()]
        print('| %g | ' % crease + ' | '.join('%.5f' % x for x in row) + ' | %.5f |' % max(row))


if __name__ == '__main__':
    main(sys.argv)
