#!/usr/bin/env python3
"""Writes sphere.obj: a geodesic sphere (an icosahedron whose faces are split into a
12 x 12 triangular grid, projected onto the sphere), 1,442 vertices and 2,880 triangles,
centre (0.5, 0.3, 0.3), radius 0.3, coordinates written with six decimals (as mesh tools
commonly export them, so that no four vertices are exactly coplanar by accident of
symmetry). Outward oriented, closed, edge-manifold.

usage: make_sphere.py [OUT.obj]   (default: sphere.obj beside this script)
"""
import math
import os
import sys

FREQUENCY = 12
CENTRE = (0.5, 0.3, 0.3)
RADIUS = 0.3


def icosahedron():
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    return v, f


def geodesic(n):
    """Every icosahedron face split into n * n triangles; points shared along edges by
    keying them on their exact barycentric position (integer weights of the corners)."""
    corners, faces = icosahedron()
    index, points, triangles = {}, [], []

    def point(weights):
        key = tuple(sorted(weights))
        if key not in index:
            p = [sum(w * corners[c][k] for c, w in weights) for k in range(3)]
            length = math.sqrt(sum(x * x for x in p))
            index[key] = len(points)
            points.append(tuple(CENTRE[k] + RADIUS * p[k] / length for k in range(3)))
        return index[key]

    def grid(a, b, c, i, j):
        w = {a: n - i - j, b: i, c: j}
        return point(tuple((corner, weight) for corner, weight in w.items() if weight))

    for a, b, c in faces:
        for i in range(n):
            for j in range(n - i):
                triangles.append((grid(a, b, c, i, j), grid(a, b, c, i + 1, j),
                                  grid(a, b, c, i, j + 1)))
                if i + j < n - 1:
                    triangles.append((grid(a, b, c, i + 1, j), grid(a, b, c, i + 1, j + 1),
                                      grid(a, b, c, i, j + 1)))
    return points, triangles


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__),
                                                             'sphere.obj')
    points, triangles = geodesic(FREQUENCY)
    with open(out, 'w') as f:
        f.write('# geodesic sphere, frequency %d, written by make_sphere.py\n' % FREQUENCY)
        for p in points:
            f.write('v %.6f %.6f %.6f\n' % p)
        for t in triangles:
            f.write('f %d %d %d\n' % tuple(i + 1 for i in t))


if __name__ == '__main__':
    main()
