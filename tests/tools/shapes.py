#!/usr/bin/env python3
"""Test shapes whose surfaces are flat or smooth by construction, as OBJ, for the normals a file
lacks (docs/formats.md, tests/sh/test_formats.sh):

  shapes.py SHAPE OUT.obj [--normals] [--unwelded]

  cube     a unit cube: six flat faces, 90 degrees apart
  sphere   a unit UV sphere of 16 x 8 facets, 22.5 degrees apart: smooth
  part     a CAD-like part: a 4 x 0.5 x 2 plate whose vertical edges are rounded (radius 0.4, four
           facets a quarter turn: smooth), flat on top and below (90 degrees to its sides), and a
           boss on it (radius 0.5, 24 facets: smooth) ending in a 45-degree chamfer and a flat top

Without options the vertices are welded (each position once, as an exporter indexing the mesh
writes it) and no normals are written. --normals writes each surface's exact normals (a flat
face's own; the sphere's, the rounded edges' and the boss's radial ones; the chamfer's cone normal),
each surface with vertices of its own: the shape as it should look. --unwelded gives every
triangle three vertices of its own (no normals). Triangles wind counterclockwise seen from outside.
"""
import math
import sys


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def unit(a):
    n = math.sqrt(dot(a, a))
    return tuple(x / n for x in a)


class Shape:
    """Surfaces of triangles, each corner a (position, exact normal) pair."""

    def __init__(self):
        self.surfaces = []

    def surface(self):
        self.surfaces.append([])
        return self.surfaces[-1]

    def triangle(self, surface, corners):
        """Adds the triangle of (position, normal) corners, turned to face its normals' way."""
        n = cross(sub(corners[1][0], corners[0][0]), sub(corners[2][0], corners[0][0]))
        if dot(n, tuple(sum(c[1][k] for c in corners) for k in range(3))) < 0:
            corners = [corners[0], corners[2], corners[1]]
        surface.append(corners)

    def quad(self, surface, a, b, c, d):
        self.triangle(surface, [a, b, c])
        self.triangle(surface, [a, c, d])


def cube():
    s = Shape()
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = tuple(sign if k == axis else 0.0 for k in range(3))
            u, v = [k for k in range(3) if k != axis]
            corners = []
            for a, b in ((-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)):
                p = [0.0, 0.0, 0.0]
                p[axis], p[u], p[v] = 0.5 * sign, a, b
                corners.append((tuple(p), n))
            s.quad(s.surface(), *corners)
    return s


def sphere(segments=16, rings=8):
    s = Shape()
    surface = s.surface()

    def point(ring, segment):
        lat = math.pi * (ring / rings - 0.5)
        lon = 2 * math.pi * (segment % segments) / segments
        p = (math.cos(lat) * math.cos(lon), math.sin(lat), math.cos(lat) * math.sin(lon))
        if ring in (0, rings):   # the poles, exactly
            p = (0.0, -1.0 if ring == 0 else 1.0, 0.0)
        return (p, p)

    for ring in range(rings):
        for segment in range(segments):
            a, b = point(ring, segment), point(ring, segment + 1)
            c, d = point(ring + 1, segment + 1), point(ring + 1, segment)
            if ring == 0:
                s.triangle(surface, [a, c, d])
            elif ring == rings - 1:
                s.triangle(surface, [a, b, c])
            else:
                s.quad(surface, a, b, c, d)
    return s


def part():
    s = Shape()
    half_x, half_z, radius, arc = 2.0, 1.0, 0.4, 4
    # The plate's outline: four rounded corners, each an arc of `arc` facets; the straight sides
    # join them. Each outline point has its outward normal (the arc's radial one, which the straight
    # sides share at their ends).
    outline = []
    for k, (cx, cz) in enumerate(((1, 1), (-1, 1), (-1, -1), (1, -1))):
        centre = (cx * (half_x - radius), cz * (half_z - radius))
        for j in range(arc + 1):
            angle = math.pi / 2 * (k + j / arc)
            n = (math.cos(angle), 0.0, math.sin(angle))
            outline.append(((centre[0] + radius * n[0], centre[1] + radius * n[2]), n))
    count = len(outline)
    bottom, top = 0.0, 0.5
    caps = {y: s.surface() for y in (bottom, top)}
    side = s.surface()
    for i in range(count):
        (p, n), (q, m) = outline[i], outline[(i + 1) % count]
        for y, sign in ((bottom, -1.0), (top, 1.0)):
            up = (0.0, sign, 0.0)
            s.triangle(caps[y], [((0.0, y, 0.0), up), ((p[0], y, p[1]), up), ((q[0], y, q[1]), up)])
        s.quad(side, ((p[0], bottom, p[1]), n), ((q[0], bottom, q[1]), m), ((q[0], top, q[1]), m),
               ((p[0], top, p[1]), n))
    # The boss: a cylinder of 24 facets from the plate's top, a 45-degree chamfer, a flat top.
    cx, cz, r, segments = 0.9, 0.0, 0.5, 24
    y0, y1, y2, r2 = top, 1.1, 1.2, 0.4
    wall, chamfer, cap = s.surface(), s.surface(), s.surface()
    slope = math.sqrt(0.5)
    for j in range(segments):
        ring = []
        for a in (j, (j + 1) % segments):
            angle = 2 * math.pi * a / segments
            ring.append((math.cos(angle), math.sin(angle)))
        (c0, s0), (c1, s1) = ring
        def at(c, sn, rad, y):
            return (cx + rad * c, y, cz + rad * sn)
        s.quad(wall, (at(c0, s0, r, y0), (c0, 0.0, s0)), (at(c1, s1, r, y0), (c1, 0.0, s1)),
               (at(c1, s1, r, y1), (c1, 0.0, s1)), (at(c0, s0, r, y1), (c0, 0.0, s0)))
        s.quad(chamfer, (at(c0, s0, r, y1), (c0 * slope, slope, s0 * slope)),
               (at(c1, s1, r, y1), (c1 * slope, slope, s1 * slope)),
               (at(c1, s1, r2, y2), (c1 * slope, slope, s1 * slope)),
               (at(c0, s0, r2, y2), (c0 * slope, slope, s0 * slope)))
        up = (0.0, 1.0, 0.0)
        s.triangle(cap, [((cx, y2, cz), up), (at(c0, s0, r2, y2), up), (at(c1, s1, r2, y2), up)])
    return s


def write(shape, path, normals, unwelded):
    positions, exact, faces, index = [], [], [], {}
    for surface in shape.surfaces:
        for corners in surface:
            face = []
            for p, n in corners:
                # Welded: one vertex per position (rounded to 9 digits, as written); with normals,
                # one per surface and position.
                key = ('%.9g %.9g %.9g' % p, id(surface) if normals else None)
                if unwelded or key not in index:
                    index[key] = len(positions)
                    positions.append(p)
                    exact.append(unit(n))
                face.append(index[key])
            faces.append(face)
    with open(path, 'w') as f:
        for p in positions:
            f.write('v %.9g %.9g %.9g\n' % p)
        if normals:
            for n in exact:
                f.write('vn %.9g %.9g %.9g\n' % n)
        for face in faces:
            f.write('f ' + ' '.join(('%d//%d' % (i + 1, i + 1)) if normals else '%d' % (i + 1) for i in face) + '\n')


def main(argv):
    shapes = {'cube': cube, 'sphere': sphere, 'part': part}
    if len(argv) < 3 or argv[1] not in shapes:
        sys.exit(__doc__)
    write(shapes[argv[1]](), argv[2], '--normals' in argv, '--unwelded' in argv)


if __name__ == '__main__':
    main(sys.argv)
