#!/usr/bin/env python3
"""Generate unstructured Gmsh meshes of the drape-tester fabric specimen.

    python3 scripts/meshes/drape_tester_meshes.py [OUTDIR]

Makes a flat disc of radius 0.15 m centred at the origin in the plane z = 0,
meshed with about 1,600 unstructured triangles, and writes it twice:

* OUTDIR/drape-tester-t3.msh: linear triangles (T3), Gmsh 4.1 ASCII;
* OUTDIR/drape-tester-t6.msh: the same mesh raised to quadratic triangles
  (T6), Gmsh 4.1 binary; the mid-edge nodes of the rim lie on the circle.

OUTDIR defaults to examples/meshes of the repository holding this script.
The meshes are for the drape-tester settle benchmark and the drape example
(examples/drape-tester.toml), as file-mesh alternatives to the built-in
structured disc. The centre of the disc is a mesh node, because the
simulation clamps the centre node, and every triangle is oriented
counter-clockwise seen from +z (normal +z). Only the triangles and their
nodes are saved (physical surface "fabric").

After writing, each file is read back with meshio and checked: cell type,
triangle count, z = 0, nodes within the radius, a node at the origin,
positive signed areas and the total area within 0.5 % of pi R^2.

Needs the pip packages gmsh and meshio (which brings numpy):

    python3 -m pip install gmsh meshio

The output is deterministic: one thread, a fixed random seed and a fixed
meshing algorithm (Frontal-Delaunay), so reruns give byte-identical files.
"""

import math
import sys
from pathlib import Path

import gmsh
import meshio
import numpy as np

RADIUS = 0.15        # m
MESH_SIZE = 0.0104   # m; gives about 1,600 triangles
FILES = {1: ("drape-tester-t3.msh", False, "triangle"),
         2: ("drape-tester-t6.msh", True, "triangle6")}


def signed_areas(points, corners):
    """Signed areas in the xy plane of triangles given by corner indices."""
    a, b, c = (points[corners[:, i], :2] for i in range(3))
    u, v = b - a, c - a
    return 0.5 * (u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])


def build_disc():
    """Disc surface with the centre point embedded; returns its tag."""
    geo = gmsh.model.geo
    centre = geo.addPoint(0, 0, 0, MESH_SIZE)
    rim = [geo.addPoint(RADIUS * x, RADIUS * y, 0, MESH_SIZE)
           for x, y in ((1, 0), (0, 1), (-1, 0), (0, -1))]
    arcs = [geo.addCircleArc(rim[i], centre, rim[(i + 1) % 4])
            for i in range(4)]
    surface = geo.addPlaneSurface([geo.addCurveLoop(arcs)])
    geo.synchronize()
    gmsh.model.mesh.embed(0, [centre], 2, surface)
    gmsh.model.addPhysicalGroup(2, [surface], name="fabric")
    return surface


def orient_up(surface):
    """Reverse the surface's triangles if they are not counter-clockwise."""
    node_tags, coords, _ = gmsh.model.mesh.getNodes()
    points = np.zeros((int(node_tags.max()) + 1, 3))
    points[node_tags.astype(int)] = coords.reshape(-1, 3)
    _, tri_nodes = gmsh.model.mesh.getElementsByType(2, surface)
    areas = signed_areas(points, tri_nodes.astype(int).reshape(-1, 3))
    if np.all(areas < 0):
        gmsh.model.mesh.reverse([(2, surface)])
    elif not np.all(areas > 0):
        raise RuntimeError("triangles of mixed orientation")


def write(path, order, binary):
    """Write the current mesh; return its (node, triangle) counts."""
    gmsh.option.setNumber("Mesh.Binary", int(binary))
    gmsh.write(str(path))
    element_type = gmsh.model.mesh.getElementType("Triangle", order)
    triangles, _ = gmsh.model.mesh.getElementsByType(element_type)
    return len(gmsh.model.mesh.getNodes()[0]), len(triangles)


def check(path, cell_type, n_triangles):
    """Read a written file back with meshio and check the mesh contract."""
    mesh = meshio.read(path, file_format="gmsh")
    assert [c.type for c in mesh.cells] == [cell_type], mesh.cells
    cells = mesh.cells[0].data
    assert len(cells) == n_triangles, (len(cells), n_triangles)
    points = mesh.points
    assert np.all(points[:, 2] == 0.0), "node off the plane z = 0"
    assert np.all(np.hypot(points[:, 0], points[:, 1]) <= RADIUS + 1e-9)
    assert np.any(np.all(points == 0.0, axis=1)), "no node at the origin"
    areas = signed_areas(points, cells[:, :3])
    assert np.all(areas > 0), f"{np.sum(areas <= 0)} triangles not CCW"
    disc = math.pi * RADIUS ** 2
    assert abs(areas.sum() - disc) <= 5e-3 * disc, (areas.sum(), disc)


def main():
    default = Path(__file__).resolve().parents[2] / "examples" / "meshes"
    outdir = Path(sys.argv[1]) if len(sys.argv) > 1 else default
    outdir.mkdir(parents=True, exist_ok=True)

    gmsh.initialize(["drape_tester_meshes"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.option.setNumber("Mesh.RandomSeed", 1)
        gmsh.option.setNumber("Mesh.Algorithm", 6)  # Frontal-Delaunay
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.model.add("drape-tester")
        surface = build_disc()
        gmsh.model.mesh.generate(2)
        orient_up(surface)
        counts = {}
        for order, (name, binary, _) in FILES.items():
            gmsh.model.mesh.setOrder(order)
            counts[order] = write(outdir / name, order, binary)
    finally:
        gmsh.finalize()

    for order, (name, _, cell_type) in FILES.items():
        nodes, triangles = counts[order]
        check(outdir / name, cell_type, triangles)
        print(f"{outdir / name}: {nodes} nodes, {triangles} {cell_type}")


if __name__ == "__main__":
    main()
