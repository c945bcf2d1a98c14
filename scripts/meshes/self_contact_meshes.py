#!/usr/bin/env python3
"""Generate the Gmsh meshes of the self-contact work (issue 33).

    python3 scripts/meshes/self_contact_meshes.py [OUTDIR]

Writes into OUTDIR (default: crates/drape/tests/meshes of the repository
holding this script), each meshed with unstructured linear triangles (T3)
by Gmsh's Frontal-Delaunay algorithm in one physical surface "fabric":

- two-plies-t3.msh (Gmsh 4.1 ASCII): two 0.2 m x 0.2 m square plies
  centred on the z axis, the lower in the plane z = 0 and the upper in
  z = 0.01 m, characteristic length 0.025 m: a mesh of two disconnected
  pieces, as a layup or a garment's front and back arrive.
- ply-on-ply-t3.msh (Gmsh 4.1 ASCII): a 0.2 m x 0.2 m lower ply in z = 0
  and a 0.06 m x 0.06 m upper ply in z = 0.0015 m, characteristic length
  0.01 m: a small ply lying on a large one, for friction between them.
- leaning-strip-t3.msh (Gmsh 4.1 binary): a 3 cm x 40 cm strip standing
  almost upright, its width along y (-0.015 to 0.015 m), its length rising
  from z = 0.005 m to z = 0.405 m while leaning along +x (x = 0.05 (z -
  0.005)), characteristic length 0.01 m: dropped onto a plane it buckles
  and folds onto itself.

The plies' triangles are counter-clockwise seen from +z (normals +z).
After writing, each file is read back with meshio and checked: only
triangle cells, every node used, no degenerate triangle, the orientation
(plies), each piece's area, and the number of connected pieces.

Needs the pip packages gmsh and meshio (which brings numpy):

    python3 -m pip install gmsh meshio

The output is deterministic (one thread, a fixed seed, a fixed algorithm).
"""

import math
import sys
from pathlib import Path

import gmsh
import meshio
import numpy as np

# The plies: (half side, height) of each, and the characteristic length.
TWO_PLIES = ([(0.1, 0.0), (0.1, 0.01)], 0.025)
PLY_ON_PLY = ([(0.1, 0.0), (0.03, 0.0015)], 0.01)

# The leaning strip.
HALF_WIDTH = 0.015   # m
BOTTOM = 0.005       # m
LENGTH = 0.4         # m (in height)
LEAN = 0.05          # dx / dz
STRIP_SIZE = 0.01    # m


def build_plies(plies, size):
    geo = gmsh.model.geo
    surfaces = []
    for half, z in plies:
        corners = [geo.addPoint(x, y, z, size)
                   for x, y in ((-half, -half), (half, -half), (half, half), (-half, half))]
        sides = [geo.addLine(corners[i], corners[(i + 1) % 4]) for i in range(4)]
        surfaces.append(geo.addPlaneSurface([geo.addCurveLoop(sides)]))
    geo.synchronize()
    gmsh.model.addPhysicalGroup(2, surfaces, name="fabric")


def build_strip():
    geo = gmsh.model.geo
    pts = []
    for y, z in ((-HALF_WIDTH, BOTTOM), (HALF_WIDTH, BOTTOM),
                 (HALF_WIDTH, BOTTOM + LENGTH), (-HALF_WIDTH, BOTTOM + LENGTH)):
        pts.append(geo.addPoint(LEAN * (z - BOTTOM), y, z, STRIP_SIZE))
    sides = [geo.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)]
    surface = geo.addPlaneSurface([geo.addCurveLoop(sides)])
    geo.synchronize()
    gmsh.model.addPhysicalGroup(2, [surface], name="fabric")


def pieces(cells):
    """The connected pieces of the triangles (union-find over their nodes)."""
    parent = list(range(int(cells.max()) + 1))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b, c in cells:
        for u, v in ((a, b), (b, c)):
            ru, rv = find(u), find(v)
            if ru != rv:
                parent[ru] = rv
    return {find(int(n)) for n in np.unique(cells)}


def read_back(path, blocks):
    """The triangles and points of `path`, checked: `blocks` triangle cell
    blocks (one per Gmsh surface), every node used, none degenerate."""
    mesh = meshio.read(path)
    assert [c.type for c in mesh.cells] == ["triangle"] * blocks, [c.type for c in mesh.cells]
    cells = np.vstack([c.data for c in mesh.cells])
    points = mesh.points
    assert set(np.unique(cells)) == set(range(len(points))), "unused nodes"
    a, b, c = points[cells[:, 0]], points[cells[:, 1]], points[cells[:, 2]]
    normal = np.cross(b - a, c - a)
    assert np.linalg.norm(normal, axis=1).min() > 1e-8, "a degenerate triangle"
    return cells, points, a, normal


def check_plies(path, plies):
    cells, points, a, normal = read_back(path, len(plies))
    assert (normal[:, 2] > 0).all(), "a triangle is not counter-clockwise from +z"
    area = 0.5 * normal[:, 2]
    for half, z in plies:
        on = np.isclose(a[:, 2], z)
        assert abs(area[on].sum() - (2 * half) ** 2) < 1e-12, area[on].sum()
    assert len(pieces(cells)) == len(plies), "not one piece per ply"
    return f"{len(cells)} T3, {len(points)} nodes, {len(plies)} pieces"


def check_strip(path):
    cells, points, _, normal = read_back(path, 1)
    area = 0.5 * np.linalg.norm(normal, axis=1)
    expected = 2 * HALF_WIDTH * LENGTH * math.sqrt(1 + LEAN**2)
    assert abs(area.sum() - expected) < 1e-12, (area.sum(), expected)
    assert len(pieces(cells)) == 1, "not one piece"
    return f"{len(cells)} T3, {len(points)} nodes"


def write(path, name, build, binary):
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.option.setNumber("Mesh.RandomSeed", 1)
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 1 if binary else 0)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.model.add(name)
        build()
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def main():
    here = Path(__file__).resolve().parents[2]
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else here / "crates/drape/tests/meshes"
    out.mkdir(parents=True, exist_ok=True)
    for name, (plies, size) in (("two-plies", TWO_PLIES), ("ply-on-ply", PLY_ON_PLY)):
        path = out / f"{name}-t3.msh"
        write(path, name, lambda: build_plies(plies, size), binary=False)
        print(f"{path}: {check_plies(path, plies)}")
    path = out / "leaning-strip-t3.msh"
    write(path, "leaning-strip", build_strip, binary=True)
    print(f"{path}: {check_strip(path)}")


if __name__ == "__main__":
    main()
