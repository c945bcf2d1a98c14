#!/usr/bin/env python3
"""Check a drape output directory's field frames with an independent reader.

    python3 scripts/check_vtu.py OUTDIR

Reads OUTDIR/fields.pvd, opens every VTU file it lists with meshio and checks
the contract of the README's "Outputs":

* at least one point, all coordinates finite;
* exactly one cell block, of type triangle (order 1), triangle6 (order 2) or
  VTK_LAGRANGE_TRIANGLE (order 3, 10 nodes), whose node indices are in range;
* point data displacement, velocity, contact_force with 3 components;
* cell data stress (3 components), principal_stress (2) and wrinkle_state
  (1 component, values 0 taut, 1 wrinkled, 2 slack).

Prints one line per frame and exits 0 when every frame passes; otherwise
prints every problem found to stderr and exits 1 (2 for a usage error or a
missing meshio).
"""

import math
import os
import sys
import xml.etree.ElementTree as ET

CELL_TYPES = {"triangle": 3, "triangle6": 6, "VTK_LAGRANGE_TRIANGLE": 10}
POINT_DATA = {"displacement": 3, "velocity": 3, "contact_force": 3}
CELL_DATA = {"stress": 3, "principal_stress": 2, "wrinkle_state": 1}


def components(array):
    """Number of components of a per-point or per-cell array."""
    if array.ndim == 1:
        return 1
    if array.ndim == 2:
        return array.shape[1]
    return -1


def frames_of(pvd_path):
    """(timestep, path) of every DataSet in a ParaView collection file."""
    try:
        root = ET.parse(pvd_path).getroot()
    except (OSError, ET.ParseError) as e:
        raise ValueError(f"{pvd_path}: cannot read the collection: {e}") from e
    if root.tag != "VTKFile" or root.get("type") != "Collection":
        raise ValueError(f"{pvd_path}: not a VTK collection (root <{root.tag}>)")
    base = os.path.dirname(pvd_path)
    frames = []
    for ds in root.iter("DataSet"):
        file = ds.get("file")
        if not file:
            raise ValueError(f"{pvd_path}: a DataSet has no file attribute")
        try:
            time = float(ds.get("timestep", "nan"))
        except ValueError:
            raise ValueError(f"{pvd_path}: {file}: bad timestep {ds.get('timestep')!r}")
        frames.append((time, os.path.join(base, file)))
    if not frames:
        raise ValueError(f"{pvd_path}: the collection lists no frame")
    return frames


def check_frame(meshio, path):
    """Problems of one VTU file (an empty list when it passes) and a summary."""
    import numpy as np

    try:
        mesh = meshio.read(path)
    except Exception as e:  # meshio raises many kinds of errors
        return [f"{path}: meshio cannot read it: {type(e).__name__}: {e}"], ""
    problems = []
    npts = len(mesh.points)
    if npts == 0:
        problems.append(f"{path}: no points")
    elif not np.all(np.isfinite(mesh.points)):
        problems.append(f"{path}: non-finite point coordinates")

    blocks = mesh.cells
    ncells = 0
    if len(blocks) != 1:
        kinds = [b.type for b in blocks]
        problems.append(f"{path}: expected one cell block, found {len(blocks)} {kinds}")
    for block in blocks:
        if block.type not in CELL_TYPES:
            problems.append(
                f"{path}: cell type {block.type!r}, expected one of {sorted(CELL_TYPES)}"
            )
            continue
        data = np.asarray(block.data)
        ncells += len(data)
        if len(data) == 0:
            problems.append(f"{path}: the {block.type} block is empty")
        elif data.shape[1] != CELL_TYPES[block.type]:
            problems.append(
                f"{path}: {block.type} cells have {data.shape[1]} nodes, "
                f"expected {CELL_TYPES[block.type]}"
            )
        elif data.min() < 0 or data.max() >= npts:
            problems.append(f"{path}: cell node index out of range 0..{npts - 1}")

    for name, ncomp in POINT_DATA.items():
        array = mesh.point_data.get(name)
        if array is None:
            problems.append(f"{path}: no point data {name!r} (has {sorted(mesh.point_data)})")
            continue
        array = np.asarray(array)
        if components(array) != ncomp:
            problems.append(
                f"{path}: point data {name!r} has {components(array)} components, expected {ncomp}"
            )
        if len(array) != npts:
            problems.append(f"{path}: point data {name!r} has {len(array)} tuples for {npts} points")
        elif not np.all(np.isfinite(array)):
            problems.append(f"{path}: point data {name!r} is not finite")

    for name, ncomp in CELL_DATA.items():
        arrays = mesh.cell_data.get(name)
        if arrays is None:
            problems.append(f"{path}: no cell data {name!r} (has {sorted(mesh.cell_data)})")
            continue
        if len(arrays) != len(blocks):
            problems.append(f"{path}: cell data {name!r} has {len(arrays)} blocks for {len(blocks)}")
        for block, array in zip(blocks, arrays):
            array = np.asarray(array)
            if array.ndim == 2 and array.shape[1] == 1 and ncomp == 1:
                array = array[:, 0]
            if components(array) != ncomp:
                problems.append(
                    f"{path}: cell data {name!r} has {components(array)} components, expected {ncomp}"
                )
            if len(array) != len(block.data):
                problems.append(
                    f"{path}: cell data {name!r} has {len(array)} tuples for {len(block.data)} cells"
                )
            elif not np.all(np.isfinite(array)):
                problems.append(f"{path}: cell data {name!r} is not finite")
            elif name == "wrinkle_state" and not set(np.unique(array).tolist()) <= {0, 1, 2}:
                problems.append(
                    f"{path}: wrinkle_state values {sorted(set(np.unique(array).tolist()))} "
                    "are not all in {0, 1, 2}"
                )

    kind = blocks[0].type if blocks else "none"
    return problems, f"{npts} points, {ncells} {kind} cells"


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    out = argv[1]
    try:
        import meshio
    except ImportError:
        print("check_vtu.py: the Python package meshio is needed: pip install meshio", file=sys.stderr)
        return 2

    pvd = os.path.join(out, "fields.pvd")
    if not os.path.isfile(pvd):
        print(f"check_vtu.py: {pvd}: fields.pvd not found (is {out} a drape output directory?)",
              file=sys.stderr)
        return 1
    try:
        frames = frames_of(pvd)
    except ValueError as e:
        print(f"check_vtu.py: {e}", file=sys.stderr)
        return 1

    problems = []
    previous = -math.inf
    for time, path in frames:
        if not math.isfinite(time) or time < previous:
            problems.append(f"{pvd}: timestep {time} of {path} is not finite or decreases")
        previous = time
        if not os.path.isfile(path):
            problems.append(f"{pvd} lists {path}, which does not exist")
            continue
        found, summary = check_frame(meshio, path)
        problems.extend(found)
        if not found:
            print(f"ok  t = {time:<12g} {path}: {summary}")
    if problems:
        for p in problems:
            print(f"check_vtu.py: {p}", file=sys.stderr)
        print(f"check_vtu.py: {len(problems)} problem(s) in {out}", file=sys.stderr)
        return 1
    print(f"check_vtu.py: {len(frames)} frame(s) in {out} pass")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
