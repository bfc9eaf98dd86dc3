#!/usr/bin/env python3
"""Writes the triangles of an OBJ file (v and f lines; polygons fanned; no normals) as another
mesh format, for tests and load-time measurements:

  mesh_convert.py IN.obj OUT.stl            binary STL (header starting with "solid")
  mesh_convert.py IN.obj OUT.stl --ascii    ASCII STL
  mesh_convert.py IN.obj OUT.gltf           glTF, buffer in OUT.bin beside it
  mesh_convert.py IN.obj OUT.gltf --embed   glTF, buffer as a base64 data URI
  mesh_convert.py IN.obj OUT.glb            GLB
  mesh_convert.py --grid N OUT.obj          an N x N height field of 2 N^2 triangles as OBJ

glTF and GLB files place the mesh under two nested nodes whose transforms (a matrix, then
translation/rotation/scale) cancel out, so the loaded mesh equals the OBJ's up to rounding.
"""
import base64
import json
import math
import struct
import sys


def read_obj(path):
    positions, triangles = [], []
    with open(path) as f:
        for line in f:
            words = line.split('#', 1)[0].split()
            if not words:
                continue
            if words[0] == 'v':
                positions.append(tuple(float(w) for w in words[1:4]))
            elif words[0] == 'f':
                corners = [int(w.split('/')[0]) for w in words[1:]]
                corners = [c - 1 if c > 0 else len(positions) + c for c in corners]
                for i in range(1, len(corners) - 1):
                    triangles.append((corners[0], corners[i], corners[i + 1]))
    return positions, triangles


def write_stl(path, positions, triangles, ascii_form):
    if ascii_form:
        with open(path, 'w') as f:
            f.write('solid converted\n')
            for t in triangles:
                f.write('  facet normal 0 0 0\n    outer loop\n')
                for v in t:
                    f.write('      vertex %r %r %r\n' % positions[v])
                f.write('    endloop\n  endfacet\n')
            f.write('endsolid converted\n')
        return
    with open(path, 'wb') as f:
        f.write(b'solid converted (binary)'.ljust(80, b' '))
        f.write(struct.pack('<I', len(triangles)))
        for t in triangles:
            f.write(struct.pack('<3f', 0, 0, 0))
            for v in t:
                f.write(struct.pack('<3f', *positions[v]))
            f.write(b'\0\0')


def gltf_document(positions, triangles, buffer_uri):
    """The JSON and the binary buffer: float positions, then uint32 (or uint16) indices."""
    lo = [min(p[k] for p in positions) for k in range(3)]
    hi = [max(p[k] for p in positions) for k in range(3)]
    small = len(positions) < 65536
    vertex_bytes = struct.pack('<%df' % (3 * len(positions)), *[c for p in positions for c in p])
    flat = [v for t in triangles for v in t]
    index_bytes = struct.pack(('<%dH' if small else '<%dI') % len(flat), *flat)
    pad = (4 - len(index_bytes) % 4) % 4
    blob = vertex_bytes + index_bytes + b'\0' * pad
    # Parent: a matrix scaling by 2 and moving by (1, 2, 3); child: the inverse as TRS (a
    # rotation by 90 degrees about y and back is folded in to exercise the quaternion path).
    half = math.sqrt(0.5)
    doc = {
        'asset': {'version': '2.0', 'generator': 'aoview tests/mesh_convert.py'},
        'scene': 0,
        'scenes': [{'nodes': [0]}],
        'nodes': [
            {'matrix': [0, 0, -2, 0, 0, 2, 0, 0, 2, 0, 0, 0, 1, 2, 3, 1], 'children': [1]},
            {'rotation': [0, -half, 0, half], 'scale': [0.5, 0.5, 0.5],
             'translation': [1.5, -1, -0.5], 'mesh': 0},
        ],
        'meshes': [{'primitives': [{'attributes': {'POSITION': 0}, 'indices': 1, 'mode': 4}]}],
        'accessors': [
            {'bufferView': 0, 'componentType': 5126, 'count': len(positions), 'type': 'VEC3',
             'min': lo, 'max': hi},
            {'bufferView': 1, 'componentType': 5123 if small else 5125, 'count': len(flat),
             'type': 'SCALAR'},
        ],
        'bufferViews': [
            {'buffer': 0, 'byteOffset': 0, 'byteLength': len(vertex_bytes), 'target': 34962},
            {'buffer': 0, 'byteOffset': len(vertex_bytes), 'byteLength': len(index_bytes),
             'target': 34963},
        ],
        'buffers': [{'byteLength': len(blob)}],
    }
    if buffer_uri is not None:
        doc['buffers'][0]['uri'] = buffer_uri
    return doc, blob


def write_gltf(path, positions, triangles, embed):
    if embed:
        doc, blob = gltf_document(positions, triangles, '')
        doc['buffers'][0]['uri'] = ('data:application/octet-stream;base64,' +
                                    base64.b64encode(blob).decode())
    else:
        bin_path = path[:-5] + '.bin'
        doc, blob = gltf_document(positions, triangles, bin_path.rsplit('/', 1)[-1])
        with open(bin_path, 'wb') as f:
            f.write(blob)
    with open(path, 'w') as f:
        json.dump(doc, f, indent=1)


def write_glb(path, positions, triangles):
    doc, blob = gltf_document(positions, triangles, None)
    text = json.dumps(doc).encode()
    text += b' ' * ((4 - len(text) % 4) % 4)
    with open(path, 'wb') as f:
        f.write(struct.pack('<3I', 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(blob)))
        f.write(struct.pack('<2I', len(text), 0x4E4F534A) + text)
        f.write(struct.pack('<2I', len(blob), 0x004E4942) + blob)


def write_grid(n, path):
    with open(path, 'w') as f:
        for j in range(n + 1):
            for i in range(n + 1):
                x, z = i / n - 0.5, j / n - 0.5
                f.write('v %.6f %.6f %.6f\n' % (x, 0.05 * math.sin(20 * x) * math.cos(20 * z) + 0.1, z))
        for j in range(n):
            for i in range(n):
                a = j * (n + 1) + i + 1
                f.write('f %d %d %d\nf %d %d %d\n' % (a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2))


def main(argv):
    if argv[1] == '--grid':
        write_grid(int(argv[2]), argv[3])
        return
    positions, triangles = read_obj(argv[1])
    out = argv[2]
    if out.endswith('.stl'):
        write_stl(out, positions, triangles, '--ascii' in argv)
    elif out.endswith('.gltf'):
        write_gltf(out, positions, triangles, '--embed' in argv)
    elif out.endswith('.glb'):
        write_glb(out, positions, triangles)
    else:
        sys.exit('unknown output format: ' + out)


if __name__ == '__main__':
    main(sys.argv)
