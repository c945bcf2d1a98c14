#!/usr/bin/env python3
"""Generate unstructured Gmsh meshes for the bending tests.

    python3 scripts/meshes/bending_meshes.py [OUTDIR]

Writes into OUTDIR (default crates/drape/tests/meshes of the repository
holding this script):

* plate-unstructured-{8,16,32}.msh: a 0.2 m x 0.2 m square plate in the
  plane z = 0, centred at the origin (x, y in [-0.1, 0.1]), unstructured
  linear triangles (T3) of characteristic length 0.2/n, Gmsh 4.1 ASCII;
  the four corners are mesh nodes and the boundary nodes lie exactly on
  the square's edges;
* plate-criss-cross-16.msh: the same plate as a structured transfinite
  mesh of 16 x 16 squares whose diagonals alternate like a checkerboard
  (Gmsh's "Alternate" arrangement), linear triangles, Gmsh 4.1 ASCII: the
  mesh on which drape's rotation-free bending does not converge and that
  it warns about (docs/validation.md);
* plate-unstructured-16-t6.msh: the n = 16 plate raised to quadratic
  triangles (T6), Gmsh 4.1 binary;
* cylinder-panel-t3.msh: a cylindrical panel of radius 0.1 m, axis along
  y, spanning the angles a in [-45, 45] degrees measured from +z (points
  (0.1 sin a, y, 0.1 cos a)) and y in [-0.1, 0.1]; T3 of characteristic
  length 0.015, Gmsh 4.1 ASCII;
* sphere-cap-t6.msh: the cap z >= 0.15 cos(40 deg) of the sphere of radius
  0.15 m centred at the origin (polar angle up to 40 degrees); T6 of
  characteristic length 0.02, Gmsh 4.1 binary; the mid-edge nodes lie on
  the sphere (OCC geometry, setOrder(2)).

All meshes but the criss-cross plate use Gmsh's Frontal-Delaunay 2D
algorithm (no transfinite meshing). Only the triangles and their nodes are saved (one physical
surface "fabric"). Triangles are oriented consistently: counter-clockwise
seen from +z on the plate (normal +z), normals pointing away from the axis
on the cylinder and away from the centre on the sphere; the script
reverses the surface's mesh where Gmsh orients it the other way.

After writing, each file is read back with meshio and checked: only
triangle / triangle6 cells, the triangle count, every node used by a
triangle, no degenerate triangle, the orientation above, the total area,
nodes on the surface (plate: z = 0 exactly and the corner nodes
(+-0.1, +-0.1, 0) present; cylinder and sphere: distance to the axis /
centre equal to the radius to 1e-9 relative) and the boundary nodes on the
surface's boundary.

Needs the pip packages gmsh and meshio (which brings numpy):

    python3 -m pip install gmsh meshio

The output is deterministic: one thread, a fixed random seed and a fixed
meshing algorithm (Frontal-Delaunay), and each mesh is made in a fresh
Gmsh session, so reruns give byte-identical files.
"""

import math
import sys
from pathlib import Path

import gmsh
import meshio
import numpy as np

PLATE_HALF = 0.1               # m; the plate is [-0.1, 0.1]^2
PLATE_SIZES = (8, 16, 32)      # n; characteristic length 0.2 / n
PLATE_T6 = 16                  # n of the quadratic plate
CYL_RADIUS = 0.1               # m
CYL_HALF_ANGLE = math.radians(45)
CYL_HALF_LENGTH = 0.1          # m; y in [-0.1, 0.1]
CYL_SIZE = 0.015               # m
SPHERE_RADIUS = 0.15           # m
SPHERE_POLAR = math.radians(40)
SPHERE_SIZE = 0.02             # m
SURFACE_TOL = 1e-9             # relative distance of a node off the surface
CELL_TYPES = {1: "triangle", 2: "triangle6"}


# ---------------------------------------------------------------- geometry

def build_plate(n):
    """Square plate, corners as geometry points; returns the surface tag."""
    geo = gmsh.model.geo
    size = 2 * PLATE_HALF / n
    h = PLATE_HALF
    corners = [geo.addPoint(x, y, 0, size)
               for x, y in ((-h, -h), (h, -h), (h, h), (-h, h))]
    sides = [geo.addLine(corners[i], corners[(i + 1) % 4]) for i in range(4)]
    surface = geo.addPlaneSurface([geo.addCurveLoop(sides)])
    geo.synchronize()
    return surface


def build_plate_criss_cross(n):
    """The square plate as a transfinite mesh of n x n squares, their
    diagonals alternating; returns the surface tag."""
    surface = build_plate(n)
    for _, curve in gmsh.model.getEntities(1):
        gmsh.model.mesh.setTransfiniteCurve(curve, n + 1)
    gmsh.model.mesh.setTransfiniteSurface(surface, "Alternate")
    return surface


def build_cylinder_panel():
    """Circle arc at y = -0.1 extruded along y; returns the surface tag."""
    occ = gmsh.model.occ
    r, a, y0 = CYL_RADIUS, CYL_HALF_ANGLE, -CYL_HALF_LENGTH
    centre = occ.addPoint(0, y0, 0)
    start = occ.addPoint(-r * math.sin(a), y0, r * math.cos(a))
    end = occ.addPoint(r * math.sin(a), y0, r * math.cos(a))
    arc = occ.addCircleArc(start, centre, end)
    extruded = occ.extrude([(1, arc)], 0, 2 * CYL_HALF_LENGTH, 0)
    occ.remove([(0, centre)])
    occ.synchronize()
    surfaces = [tag for dim, tag in extruded if dim == 2]
    assert len(surfaces) == 1, extruded
    assert gmsh.model.getType(2, surfaces[0]) == "Cylinder"
    return surfaces[0]


def build_sphere_cap():
    """OCC sphere segment of latitudes [50, 90] degrees, keeping only its
    spherical face (the flat disc and the volume are removed); returns the
    surface tag."""
    occ = gmsh.model.occ
    volume = occ.addSphere(0, 0, 0, SPHERE_RADIUS, -1,
                           math.pi / 2 - SPHERE_POLAR, math.pi / 2)
    occ.synchronize()
    faces = gmsh.model.getBoundary([(3, volume)], oriented=False)
    spherical = [tag for _, tag in faces
                 if gmsh.model.getType(2, tag) == "Sphere"]
    others = [(2, tag) for _, tag in faces if tag not in spherical]
    assert len(spherical) == 1, faces
    occ.remove([(3, volume)])
    occ.remove(others)
    occ.synchronize()
    # Removing the disc keeps the rim circle, which the cap also uses.
    assert gmsh.model.getEntities(2) == [(2, spherical[0])]
    return spherical[0]


# ------------------------------------------------------------ orientation

def corner_points(points, corners):
    return (points[corners[:, i]] for i in range(3))


def plate_normal(centroids):
    normals = np.zeros_like(centroids)
    normals[:, 2] = 1.0
    return normals


def cylinder_normal(centroids):
    normals = centroids.copy()
    normals[:, 1] = 0.0
    return normals


def sphere_normal(centroids):
    return centroids


def oriented_areas(points, corners, outward):
    """Triangle areas, signed by their normals' side of the outward
    direction outward(centroids)."""
    a, b, c = corner_points(points, corners)
    cross = np.cross(b - a, c - a)
    reference = outward((a + b + c) / 3)
    sign = np.sign(np.einsum("ij,ij->i", cross, reference))
    return 0.5 * np.linalg.norm(cross, axis=1) * sign


def orient(surface, outward):
    """Reverse the surface's triangles if their normals point inward."""
    node_tags, coords, _ = gmsh.model.mesh.getNodes()
    points = np.zeros((int(node_tags.max()) + 1, 3))
    points[node_tags.astype(int)] = coords.reshape(-1, 3)
    _, tri_nodes = gmsh.model.mesh.getElementsByType(2, surface)
    areas = oriented_areas(points, tri_nodes.astype(int).reshape(-1, 3),
                           outward)
    if np.all(areas < 0):
        gmsh.model.mesh.reverse([(2, surface)])
    elif not np.all(areas > 0):
        raise RuntimeError("triangles of mixed orientation")


# ---------------------------------------------------------------- meshing

def start(name):
    gmsh.initialize([name], readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 6)  # Frontal-Delaunay
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    gmsh.model.add(name)


def mesh_surface(surface, size, outward):
    """Mesh the surface with linear triangles of the given size (None: the
    sizes already on the geometry points) and orient them."""
    if size is not None:
        gmsh.model.mesh.setSize(gmsh.model.getEntities(0), size)
    gmsh.model.addPhysicalGroup(2, [surface], name="fabric")
    gmsh.model.mesh.generate(2)
    orient(surface, outward)


def write(path, order, binary):
    """Write the current mesh at the given order; return its (node,
    triangle) counts."""
    gmsh.model.mesh.setOrder(order)
    gmsh.option.setNumber("Mesh.Binary", int(binary))
    gmsh.write(str(path))
    element_type = gmsh.model.mesh.getElementType("Triangle", order)
    triangles, _ = gmsh.model.mesh.getElementsByType(element_type)
    return len(gmsh.model.mesh.getNodes()[0]), len(triangles)


# ----------------------------------------------------------------- checks

def boundary_nodes(cells):
    """Nodes on the edges that belong to one triangle only (with the
    mid-edge node of a T6)."""
    mids = cells.shape[1] == 6
    edges = {}
    for cell in cells:
        for i in range(3):
            j = (i + 1) % 3
            key = tuple(sorted((cell[i], cell[j])))
            nodes = [cell[i], cell[j]] + ([cell[3 + i]] if mids else [])
            edges.setdefault(key, []).append(nodes)
    return np.unique([node for uses in edges.values() if len(uses) == 1
                      for node in uses[0]])


def check_plate(points, boundary):
    h = PLATE_HALF
    assert np.all(points[:, 2] == 0.0), "node off the plane z = 0"
    assert np.all(np.abs(points[:, :2]) <= h), "node outside the square"
    for x in (-h, h):
        for y in (-h, h):
            assert np.any(np.all(points == (x, y, 0.0), axis=1)), \
                f"no corner node at ({x}, {y}, 0)"
    on_edge = np.any(np.abs(points[boundary, :2]) == h, axis=1)
    assert np.all(on_edge), "boundary node off the square's edges"
    return (2 * h) ** 2, 1e-12


def check_cylinder(points, boundary):
    r = CYL_RADIUS
    off = np.abs(np.hypot(points[:, 0], points[:, 2]) - r)
    assert np.all(off <= SURFACE_TOL * r), f"node off the cylinder {off.max()}"
    angles = np.arctan2(points[:, 0], points[:, 2])
    assert np.all(np.abs(angles) <= CYL_HALF_ANGLE + SURFACE_TOL)
    assert np.all(np.abs(points[:, 1]) <= CYL_HALF_LENGTH * (1 + SURFACE_TOL))
    on_edge = ((np.abs(np.abs(points[boundary, 1]) - CYL_HALF_LENGTH)
                <= SURFACE_TOL * CYL_HALF_LENGTH)
               | (np.abs(np.abs(angles[boundary]) - CYL_HALF_ANGLE)
                  <= SURFACE_TOL))
    assert np.all(on_edge), "boundary node off the panel's edges"
    return (r * 2 * CYL_HALF_ANGLE * 2 * CYL_HALF_LENGTH,
            (CYL_SIZE / r) ** 2)


def check_sphere(points, boundary):
    r = SPHERE_RADIUS
    off = np.abs(np.linalg.norm(points, axis=1) - r)
    assert np.all(off <= SURFACE_TOL * r), f"node off the sphere {off.max()}"
    rim = r * math.cos(SPHERE_POLAR)
    assert np.all(points[:, 2] >= rim - SURFACE_TOL * r), "node below the rim"
    on_rim = np.abs(points[boundary, 2] - rim) <= SURFACE_TOL * r
    assert np.all(on_rim), "boundary node off the rim"
    return (2 * math.pi * r ** 2 * (1 - math.cos(SPHERE_POLAR)),
            (SPHERE_SIZE / r) ** 2)


def check(path, cell_type, n_triangles, outward, check_surface):
    """Read a written file back with meshio and check the mesh contract."""
    mesh = meshio.read(path, file_format="gmsh")
    assert [c.type for c in mesh.cells] == [cell_type], mesh.cells
    cells = mesh.cells[0].data
    assert len(cells) == n_triangles, (len(cells), n_triangles)
    points = mesh.points
    used = np.zeros(len(points), dtype=bool)
    used[cells.ravel()] = True
    assert np.all(used), f"{np.sum(~used)} nodes not used by a triangle"
    areas = oriented_areas(points, cells[:, :3], outward)
    assert np.all(areas != 0), f"{np.sum(areas == 0)} degenerate triangles"
    assert np.all(areas > 0), f"{np.sum(areas < 0)} triangles misoriented"
    exact, tolerance = check_surface(points, boundary_nodes(cells))
    # The areas are those of the flat triangles through the corner nodes:
    # on a curved surface their sum falls short of the exact area by a
    # relative amount of order (mesh size / radius)^2.
    error = abs(areas.sum() - exact) / exact
    assert error <= tolerance, (areas.sum(), exact, error)


# ------------------------------------------------------------------- main

def make(outdir, name, build, size, outward, outputs):
    """Build and mesh one geometry in a fresh Gmsh session and write it as
    outputs [(file name, order, binary)]; returns [(file name, order,
    nodes, triangles)]."""
    start(name)
    try:
        surface = build()
        mesh_surface(surface, size, outward)
        written = []
        for file_name, order, binary in outputs:
            nodes, triangles = write(outdir / file_name, order, binary)
            written.append((file_name, order, binary, nodes, triangles))
    finally:
        gmsh.finalize()
    return written


def main():
    default = (Path(__file__).resolve().parents[2]
               / "crates" / "drape" / "tests" / "meshes")
    outdir = Path(sys.argv[1]) if len(sys.argv) > 1 else default
    outdir.mkdir(parents=True, exist_ok=True)

    jobs = []
    for n in PLATE_SIZES:
        outputs = [(f"plate-unstructured-{n}.msh", 1, False)]
        if n == PLATE_T6:
            outputs.append((f"plate-unstructured-{n}-t6.msh", 2, True))
        jobs.append((f"plate-{n}", lambda n=n: build_plate(n), None,
                     plate_normal, check_plate, outputs))
    jobs.append(("plate-criss-cross", lambda: build_plate_criss_cross(16),
                 None, plate_normal, check_plate,
                 [("plate-criss-cross-16.msh", 1, False)]))
    jobs.append(("cylinder-panel", build_cylinder_panel, CYL_SIZE,
                 cylinder_normal, check_cylinder,
                 [("cylinder-panel-t3.msh", 1, False)]))
    jobs.append(("sphere-cap", build_sphere_cap, SPHERE_SIZE,
                 sphere_normal, check_sphere,
                 [("sphere-cap-t6.msh", 2, True)]))

    for name, build, size, outward, check_surface, outputs in jobs:
        written = make(outdir, name, build, size, outward, outputs)
        for file_name, order, binary, nodes, triangles in written:
            cell_type = CELL_TYPES[order]
            check(outdir / file_name, cell_type, triangles, outward,
                  check_surface)
            form = "binary" if binary else "ASCII"
            print(f"{outdir / file_name}: {cell_type} ({form} 4.1), "
                  f"{triangles} elements, {nodes} nodes")


if __name__ == "__main__":
    main()
