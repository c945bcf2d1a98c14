#!/usr/bin/env python3
"""Generate the two-ply Gmsh mesh of the self-contact work (issue 33).

    python3 scripts/meshes/two_plies_mesh.py [OUTDIR]

Writes OUTDIR/two-plies-t3.msh (default OUTDIR: crates/drape/tests/meshes
of the repository holding this script): two 0.2 m x 0.2 m square plies,
centred on the z axis, the lower in the plane z = 0 and the upper in
z = 0.01 m, each meshed with unstructured linear triangles (T3) of
characteristic length 0.025 m by Gmsh's Frontal-Delaunay algorithm, in one
physical surface "fabric" and one file, Gmsh 4.1 ASCII: a mesh of two
disconnected pieces, as a layup or a garment's front and back arrive.
Triangles are counter-clockwise seen from +z (normals +z).

After writing, the file is read back with meshio and checked: only
triangle cells, every node used, no degenerate triangle, the orientation,
each ply's area (0.04 m^2) and that the triangles form exactly two
connected pieces, one per plane.

Needs the pip packages gmsh and meshio (which brings numpy):

    python3 -m pip install gmsh meshio

The output is deterministic (one thread, a fixed seed, a fixed algorithm).
"""

import sys
from pathlib import Path

import gmsh
import meshio
import numpy as np

HALF = 0.1        # m: each ply is [-0.1, 0.1]^2
GAP = 0.01        # m: the upper ply's height
SIZE = 0.025      # m: characteristic length


def build():
    geo = gmsh.model.geo
    surfaces = []
    for z in (0.0, GAP):
        corners = [geo.addPoint(x, y, z, SIZE)
                   for x, y in ((-HALF, -HALF), (HALF, -HALF), (HALF, HALF), (-HALF, HALF))]
        sides = [geo.addLine(corners[i], corners[(i + 1) % 4]) for i in range(4)]
        surfaces.append(geo.addPlaneSurface([geo.addCurveLoop(sides)]))
    geo.synchronize()
    gmsh.model.addPhysicalGroup(2, surfaces, name="fabric")


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


def check(path):
    mesh = meshio.read(path)
    # One cell block per Gmsh surface: one per ply.
    assert [c.type for c in mesh.cells] == ["triangle"] * 2, [c.type for c in mesh.cells]
    cells = np.vstack([c.data for c in mesh.cells])
    points = mesh.points
    assert set(np.unique(cells)) == set(range(len(points))), "unused nodes"
    a, b, c = points[cells[:, 0]], points[cells[:, 1]], points[cells[:, 2]]
    normal = np.cross(b - a, c - a)
    assert (normal[:, 2] > 0).all(), "a triangle is not counter-clockwise from +z"
    area = 0.5 * normal[:, 2]
    for z in (0.0, GAP):
        on = np.isclose(a[:, 2], z)
        assert abs(area[on].sum() - (2 * HALF) ** 2) < 1e-12, area[on].sum()
    assert len(pieces(cells)) == 2, "not two pieces"
    return len(cells), len(points)


def main():
    here = Path(__file__).resolve().parents[2]
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else here / "crates/drape/tests/meshes"
    out.mkdir(parents=True, exist_ok=True)
    path = out / "two-plies-t3.msh"
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.option.setNumber("Mesh.RandomSeed", 1)
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.model.add("two-plies")
        build()
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    triangles, nodes = check(path)
    print(f"{path}: {triangles} T3, {nodes} nodes, two pieces")


if __name__ == "__main__":
    main()
