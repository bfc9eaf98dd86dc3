#!/usr/bin/env python3
"""Writes the triangles of an OBJ file (v and f lines; polygons fanned; no normals) as another
mesh format, for tests and load-time measurements:

  mesh_convert.py IN.obj OUT.stl            binary STL (header starting with "solid")
  mesh_convert.py IN.obj OUT.stl --ascii    ASCII STL
  mesh_convert.py IN.obj OUT.gltf           glTF, buffer in OUT.bin beside it
  mesh_convert.py IN.obj OUT.gltf --embed   glTF, buffer as a base64 data URI
  mesh_convert.py IN.obj OUT.glb            GLB
  mesh_convert.py IN.obj OUT.gltf --FORM    glTF as exporters also write it, under one node:
      --strip      one triangle strip (mode 5), the triangles joined by zero-area ones
      --fan        triangle fans (mode 6), one primitive per run of triangles around a corner
      --sparse     positions as a sparse accessor without a bufferView (every vertex an entry)
      --quantized  positions as normalized shorts under a node that scales them back
                   (KHR_mesh_quantization)
      --quantized-packed  the same shorts packed 6 bytes apart (no byteStride: off glTF's
                   4-byte alignment), without declaring KHR_mesh_quantization, as cesium-native's
                   test file cubeQuantized.glb has them
  mesh_convert.py --grid N OUT.obj          an N x N height field of 2 N^2 triangles as OBJ

glTF and GLB files place the mesh under two nested nodes whose transforms (a matrix, then
translation/rotation/scale) cancel out, so the loaded mesh equals the OBJ's up to rounding. The
strip, fan and sparse forms decode to exactly the OBJ's positions and triangles, corners in the
same order; the quantized forms to positions within 1/65534 of the mesh's size.
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
        'asset': {'version': '2.0', 'generator': 'aoview tests/tools/mesh_convert.py'},
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


def strip_of(triangles):
    """One strip whose triangles at even positions are the list's, in order and winding, joined
    by zero-area triangles: ... z, then a repeated until a stands at an even position, then b c."""
    strip = list(triangles[0])
    for a, b, c in triangles[1:]:
        strip += [strip[-1], a, a]
        if (len(strip) - 1) % 2:
            strip.append(a)
        strip += [b, c]
    return strip


def fans_of(triangles):
    """Fans whose triangles (v[k+1], v[k+2], v[0]) are the list's in order: (a, b, c) starts the
    fan c a b, and a following (b, e, c) extends it by e."""
    fans = []
    for a, b, c in triangles:
        if fans and fans[-1][0] == c and fans[-1][-1] == a:
            fans[-1].append(b)
        else:
            fans.append([c, a, b])
    return fans


def write_form(path, positions, triangles, form):
    """glTF with an embedded buffer in one of the forms exporters write (see the module's help)."""
    n = len(positions)
    flat = [c for p in positions for c in p]
    accessors, views, blob, primitives = [], [], b'', []
    node = {'mesh': 0}

    def add(data, **accessor):
        nonlocal blob
        views.append({'buffer': 0, 'byteOffset': len(blob), 'byteLength': len(data)})
        blob += data + b'\0' * ((4 - len(data) % 4) % 4)
        accessors.append(dict(accessor, bufferView=len(views) - 1))
        return len(accessors) - 1

    if form in ('quantized', 'quantized-packed'):
        lo = [min(p[k] for p in positions) for k in range(3)]
        size = max(max(p[k] for p in positions) - lo[k] for k in range(3))
        q = []
        for p in positions:
            q += [round((p[k] - lo[k]) / size * 32767) for k in range(3)] + ([0] if form == 'quantized' else [])
        position = add(struct.pack('<%dh' % len(q), *q), componentType=5122, normalized=True, count=n, type='VEC3')
        if form == 'quantized':
            views[-1]['byteStride'] = 8
        node = {'mesh': 0, 'translation': lo, 'scale': [size] * 3}
    elif form == 'sparse':
        at = struct.pack('<%dI' % n, *range(n))
        values = struct.pack('<%df' % len(flat), *flat)
        add(at, componentType=5125, count=n, type='SCALAR')
        add(values, componentType=5126, count=n, type='VEC3')
        accessors[:] = [{'componentType': 5126, 'count': n, 'type': 'VEC3', 'sparse': {
            'count': n, 'indices': {'bufferView': 0, 'componentType': 5125}, 'values': {'bufferView': 1}}}]
        position = 0
    else:
        position = add(struct.pack('<%df' % len(flat), *flat), componentType=5126, count=n, type='VEC3')
    if form == 'strip':
        runs, mode = [strip_of(triangles)], 5
    elif form == 'fan':
        runs, mode = fans_of(triangles), 6
    else:
        runs, mode = [[v for t in triangles for v in t]], 4
    for run in runs:
        index = add(struct.pack('<%dI' % len(run), *run), componentType=5125, count=len(run), type='SCALAR')
        primitives.append({'attributes': {'POSITION': position}, 'indices': index, 'mode': mode})
    doc = {'asset': {'version': '2.0', 'generator': 'aoview tests/tools/mesh_convert.py'},
           'nodes': [node], 'meshes': [{'primitives': primitives}], 'accessors': accessors, 'bufferViews': views,
           'buffers': [{'byteLength': len(blob),
                        'uri': 'data:application/octet-stream;base64,' + base64.b64encode(blob).decode()}]}
    if form == 'quantized':
        doc['extensionsUsed'] = doc['extensionsRequired'] = ['KHR_mesh_quantization']
    with open(path, 'w') as f:
        json.dump(doc, f, separators=(',', ':'))


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
    elif out.endswith('.gltf') and len(argv) > 3 and argv[3] in ('--strip', '--fan', '--sparse', '--quantized',
                                                                 '--quantized-packed'):
        write_form(out, positions, triangles, argv[3][2:])
    elif out.endswith('.gltf'):
        write_gltf(out, positions, triangles, '--embed' in argv)
    elif out.endswith('.glb'):
        write_glb(out, positions, triangles)
    else:
        sys.exit('unknown output format: ' + out)


if __name__ == '__main__':
    main(sys.argv)
