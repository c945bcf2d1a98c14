#!/usr/bin/env python3
"""Generate the two-ply bags of the inflatables work (issue 47).

    python3 scripts/meshes/folded_bag.py [OUTDIR]

Writes into OUTDIR (default: examples/meshes of the repository holding
this script) two Wavefront OBJ files of the same bag: two square plies
of 0.2 m x 0.2 m, 12 x 12 squares each (two T3 a square), joined at
their rim (the rim's nodes shared, the inner ones doubled), the upper
ply's normals +z and the lower's -z (both out of the bag), the plies
2 g = 0.4 mm apart inside (so that self-contact, with a self_distance
below 0.4 mm, sees them apart), touching at the rim:

- flat-bag.obj: the bag lying flat, its mid-surface in z = 0.
- folded-bag.obj: the same bag folded in half along x = 0: the half
  x > 0 wrapped over a cylinder of radius r = 1 cm (axis along y at
  z = r) and laid back over the half x < 0, upside down, at z = 2 r.
  The fold is isometric for the mid-surface (arc length kept); each ply,
  offset by +-g along the normal, is stretched or shortened by g / r =
  2 % in the bend only, so the folded bag's reference (a positional
  finite element's stress-free state is its initial mesh) is the flat
  bag's up to that strip.

The corner squares (0, n - 1) and (n - 1, 0) are cut along the other
diagonal, so that no triangle has its three corners on the rim (it would
be the same triangle in both plies). No dependency beyond Python 3.
"""
import math
import os
import sys

N = 12        # squares along each side of a ply
A = 0.1       # half the side (m)
G = 2.0e-4    # half the gap between the plies inside (m)
R = 0.01      # the fold's radius (m)


def place(x, y, z, fold):
    """The point of the flat bag at (x, y), offset z along the mid-surface's
    normal, folded or not."""
    if not fold or x <= 0.0:
        return (x, y, z)
    if x <= math.pi * R:
        t = x / R
        mx, mz = R * math.sin(t), R - R * math.cos(t)
        nx, nz = -math.sin(t), math.cos(t)
    else:
        mx, mz = -(x - math.pi * R), 2.0 * R
        nx, nz = 0.0, -1.0
    return (mx + z * nx, y, mz + z * nz)


def bag(fold):
    ids, vertices, faces = {}, [], []

    def node(i, j, ply):
        rim = i in (0, N) or j in (0, N)
        key = (i, j, 0 if rim else ply)
        if key not in ids:
            ids[key] = len(vertices) + 1
            x, y = -A + 2 * A * i / N, -A + 2 * A * j / N
            z = 0.0 if rim else (G if ply == 0 else -G)
            vertices.append(place(x, y, z, fold))
        return ids[key]

    for ply in (0, 1):
        for i in range(N):
            for j in range(N):
                a, b = node(i, j, ply), node(i + 1, j, ply)
                c, d = node(i + 1, j + 1, ply), node(i, j + 1, ply)
                if (i, j) in ((0, N - 1), (N - 1, 0)):
                    triangles = [(a, b, d), (b, c, d)]
                else:
                    triangles = [(a, b, c), (a, c, d)]
                for p, q, r in triangles:
                    faces.append((p, q, r) if ply == 0 else (p, r, q))
    return vertices, faces


def write(path, fold):
    vertices, faces = bag(fold)
    with open(path, "w") as f:
        f.write("# %s two-ply bag: scripts/meshes/folded_bag.py\n" % ("folded" if fold else "flat"))
        for v in vertices:
            f.write("v %.17g %.17g %.17g\n" % v)
        for t in faces:
            f.write("f %d %d %d\n" % t)
    print("%s: %d vertices, %d triangles" % (path, len(vertices), len(faces)))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "..", "examples", "meshes")
    os.makedirs(out, exist_ok=True)
    write(os.path.join(out, "flat-bag.obj"), False)
    write(os.path.join(out, "folded-bag.obj"), True)


if __name__ == "__main__":
    main()
