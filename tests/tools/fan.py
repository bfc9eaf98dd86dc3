#!/usr/bin/env python3
"""A fan of random planes around one welded vertex, as binary PLY without normals: the worst case
of the crease pass (docs/formats.md), a vertex that N triangles share, each in a plane of its own.

  fan.py N OUT.ply [--seed S]

Triangle i is (0, i + 1, i + 2): vertex 0 at the origin, the others at random points of the unit
sphere (numpy's generator, seed S, default 1), so that consecutive triangles share an edge through
vertex 0 and meet at a random angle. Made by the program, not committed (N = 1,000,000: 24 MB).
"""
import sys

import numpy as np


def main(argv):
    args = [a for a in argv[1:] if not a.startswith('--')]
    seed = int(argv[argv.index('--seed') + 1]) if '--seed' in argv else 1
    if '--seed' in argv:
        args.remove(str(seed))
    if len(args) != 2 or int(args[0]) < 1:
        sys.exit('usage: fan.py N OUT.ply [--seed S]')
    n, out = int(args[0]), args[1]
    rng = np.random.default_rng(seed)
    rim = rng.normal(size=(n + 1, 3))
    rim /= np.linalg.norm(rim, axis=1)[:, None]
    positions = np.vstack([np.zeros((1, 3)), rim]).astype('<f4')
    faces = np.empty(n, dtype=[('count', 'u1'), ('v', '<i4', 3)])
    faces['count'] = 3
    k = np.arange(n, dtype=np.int64)
    faces['v'] = np.stack([np.zeros(n, dtype=np.int64), k + 1, k + 2], axis=1)
    with open(out, 'wb') as f:
        f.write(('ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n'
                 'property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n'
                 % (len(positions), n)).encode())
        f.write(positions.tobytes())
        f.write(faces.tobytes())


if __name__ == '__main__':
    main(sys.argv)
