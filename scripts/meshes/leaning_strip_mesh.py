#!/usr/bin/env python3
"""Generate the leaning-strip Gmsh mesh of the self-contact tests (issue 33).

    python3 scripts/meshes/leaning_strip_mesh.py [OUTDIR]

Writes OUTDIR/leaning-strip-t3.msh (default OUTDIR: crates/drape/tests/meshes
of the repository holding this script): a 3 cm x 40 cm strip standing almost
upright, its width along y (-0.015 to 0.015 m), its length rising from
z = 0.005 m to z = 0.405 m while leaning along +x by 2 cm over its length
(x = 0.05 (z - 0.005)), meshed with unstructured linear triangles (T3) of
characteristic length 0.01 m by Gmsh's Frontal-Delaunay algorithm, in one
physical surface "fabric", Gmsh 4.1 binary. Dropped onto a plane, such a
strip buckles and folds onto itself: the strip-folding test of
tests/self_contact.rs.

After writing, the file is read back with meshio and checked: only
triangle cells, every node used, no degenerate triangle, the strip's area
(0.03 x 0.4 x sqrt(1 + 0.05^2) m^2), one piece.

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

HALF_WIDTH = 0.015   # m
BOTTOM = 0.005       # m
LENGTH = 0.4         # m (in height)
LEAN = 0.05          # dx / dz
SIZE = 0.01          # m: characteristic length


def build():
    geo = gmsh.model.geo
    pts = []
    for y, z in ((-HALF_WIDTH, BOTTOM), (HALF_WIDTH, BOTTOM),
                 (HALF_WIDTH, BOTTOM + LENGTH), (-HALF_WIDTH, BOTTOM + LENGTH)):
        pts.append(geo.addPoint(LEAN * (z - BOTTOM), y, z, SIZE))
    sides = [geo.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)]
    surface = geo.addPlaneSurface([geo.addCurveLoop(sides)])
    geo.synchronize()
    gmsh.model.addPhysicalGroup(2, [surface], name="fabric")


def check(path):
    mesh = meshio.read(path)
    assert [c.type for c in mesh.cells] == ["triangle"], [c.type for c in mesh.cells]
    cells = mesh.cells[0].data
    points = mesh.points
    assert set(np.unique(cells)) == set(range(len(points))), "unused nodes"
    a, b, c = points[cells[:, 0]], points[cells[:, 1]], points[cells[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    assert area.min() > 1e-8, "a degenerate triangle"
    expected = 2 * HALF_WIDTH * LENGTH * math.sqrt(1 + LEAN**2)
    assert abs(area.sum() - expected) < 1e-12, (area.sum(), expected)
    return len(cells), len(points)


def main():
    here = Path(__file__).resolve().parents[2]
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else here / "crates/drape/tests/meshes"
    out.mkdir(parents=True, exist_ok=True)
    path = out / "leaning-strip-t3.msh"
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.option.setNumber("Mesh.RandomSeed", 1)
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.model.add("leaning-strip")
        build()
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    triangles, nodes = check(path)
    print(f"{path}: {triangles} T3, {nodes} nodes")


if __name__ == "__main__":
    main()
