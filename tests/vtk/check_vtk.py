"""Reads a grainflow VTK series back with VTK's own XML reader and checks every array
against what the engine wrote (the CSV snapshot of the same step), the contact bookkeeping,
the wall polygons against the domain box, and that a rendered PNG shows a settled bed at the
bottom of its box with a labelled colour bar beside it.

    python check_vtk.py RUN_DIR XMIN YMIN ZMIN XMAX YMAX ZMAX [image.png]

Exits non-zero with a message on the first mismatch.
"""
import csv
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import vtk
from vtk.util.numpy_support import vtk_to_numpy

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from render_snapshot import SCENE_FRACTION  # noqa: E402  the image layout both scripts share


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def read(path):
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(str(path))
    r.Update()
    if r.GetErrorCode() != 0:
        fail(f"VTK could not read {path}")
    return r.GetOutput()


def array(data, name, cells=False):
    arrays = data.GetCellData() if cells else data.GetPointData()
    a = arrays.GetArray(name)
    if a is None:
        fail(f"array {name} missing")
    return vtk_to_numpy(a)


def main():
    run = Path(sys.argv[1])
    lo = np.array([float(v) for v in sys.argv[2:5]])
    hi = np.array([float(v) for v in sys.argv[5:8]])
    folder = run / "vtk"
    checked = 0
    for collection in ("particles.pvd", "contacts.pvd"):
        frames = list(ET.parse(folder / collection).getroot().iter("DataSet"))
        times = [float(f.get("timestep")) for f in frames]
        if len(frames) < 2 or any(b <= a for a, b in zip(times, times[1:])):
            fail(f"{collection}: frames {times} not increasing")
        for f in frames:
            read(folder / f.get("file"))
    frames = list(ET.parse(folder / "particles.pvd").getroot().iter("DataSet"))
    cframes = list(ET.parse(folder / "contacts.pvd").getroot().iter("DataSet"))
    for frame, cframe in zip(frames, cframes):
        step = int(frame.get("file").split("_")[1].split(".")[0])
        snap = run / "snapshots" / f"particles_{step:09d}.csv"
        if not snap.exists():
            continue
        rows = list(csv.DictReader(open(snap)))
        p = read(folder / frame.get("file"))
        n = p.GetNumberOfPoints()
        if n != len(rows) or p.GetNumberOfVerts() != n:
            fail(f"step {step}: {n} points / {p.GetNumberOfVerts()} verts vs {len(rows)} particles")
        pts = vtk_to_numpy(p.GetPoints().GetData())
        want = lambda *cols: np.array([[float(r[c]) for c in cols] for r in rows])
        # The CSV holds the same doubles printed with 17 significant digits ({:e} shortest
        # round-trip), so the comparison is exact up to the last bit.
        for name, got, exp in [
            ("position", pts, want("x", "y", "z")),
            ("velocity", array(p, "velocity"), want("u", "v", "w")),
            ("angular_velocity", array(p, "angular_velocity"), want("wx", "wy", "wz")),
            ("radius", array(p, "radius"), want("radius")[:, 0]),
            ("id", array(p, "id"), want("id")[:, 0]),
            ("phase", array(p, "phase"), want("phase")[:, 0]),
        ]:
            if not np.allclose(got, exp, rtol=1e-15, atol=0):
                fail(f"step {step}: {name} differs from the snapshot")
        c = read(folder / cframe.get("file"))
        nlines = c.GetNumberOfLines()
        if c.GetNumberOfPoints() != 2 * nlines:
            fail(f"step {step}: {c.GetNumberOfPoints()} points for {nlines} lines")
        counts = array(p, "contacts")
        # Each particle-particle line adds one contact to both ends, each wall line to one.
        ends = vtk_to_numpy(c.GetPoints().GetData()).reshape(-1, 2, 3)
        wall_lines = sum(1 for a, b in ends if not any(np.array_equal(b, q) for q in pts))
        if counts.sum() != 2 * nlines - wall_lines:
            fail(f"step {step}: contact counts {counts.sum()} vs {nlines} lines ({wall_lines} with walls)")
        fn = array(c, "normal_force", cells=True)
        ov = array(c, "overlap", cells=True)
        ft = array(c, "tangential_force", cells=True)
        if len(fn) != nlines or (ov < 0).any() or (fn < 0).any() or (ft < 0).any():
            fail(f"step {step}: contact cell data inconsistent")
        force = array(p, "force")
        if nlines > 0 and not (np.abs(force).sum() > 0):
            fail(f"step {step}: contacts but no forces")
        checked += 1
    if checked < 2:
        fail(f"only {checked} frames had a snapshot to compare with")
    w = read(folder / "walls.vtp")
    if w.GetNumberOfPolys() != 6:
        fail(f"{w.GetNumberOfPolys()} wall polygons, expected the 6 faces of the box")
    area = vtk.vtkMassProperties()
    tri = vtk.vtkTriangleFilter()
    tri.SetInputData(w)
    area.SetInputConnection(tri.GetOutputPort())
    area.Update()
    e = hi - lo
    expected = 2 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0])
    if abs(area.GetSurfaceArea() - expected) > 1e-9 * expected:
        fail(f"wall area {area.GetSurfaceArea()} vs box {expected}")
    if len(sys.argv) > 8:
        image = sys.argv[8]
        r = vtk.vtkPNGReader()
        r.SetFileName(image)
        r.Update()
        img = vtk_to_numpy(r.GetOutput().GetPointData().GetScalars())
        nx, ny, _ = r.GetOutput().GetDimensions()
        img = img.reshape(ny, nx, -1)[::-1]  # row 0 at the top
        rgb = img[:, :, :3].astype(int)
        # Sphere and colour-bar pixels are saturated colours (the darkest viridis colour,
        # (68, 1, 84), has a channel spread of 83); walls, edges, text and background are grey.
        coloured = (rgb.max(axis=2) - rgb.min(axis=2)) > 60
        split = int(SCENE_FRACTION * nx)
        scene, legend = coloured[:, :split], coloured[:, split:]
        # The bed (about 11 mm deep in the 200 mm tall box: 486 beads of 33.5 mm³ at a packing
        # fraction near 0.6 over 50 × 50 mm) is visible, and at least 99 % of it lies in the
        # bottom third of the image: nothing floats higher up.
        visible = scene.mean()
        low = scene[2 * ny // 3 :].sum() / max(scene.sum(), 1)
        if not (visible > 0.005 and low > 0.99):
            fail(f"rendered bed not at the bottom: {visible:.4f} of the scene coloured, {low:.4f} of that in the bottom third")
        # The colour bar: a coloured column over at least half the height, running from one
        # end of the colour map to the other (top and bottom rows differ by more than 100 in
        # some channel: viridis goes from (68, 1, 84) to (253, 231, 37)).
        rows = np.flatnonzero(legend.any(axis=1))
        if len(rows) == 0 or rows[-1] - rows[0] < ny // 2:
            fail("no colour bar beside the scene")
        bar = rgb[:, split:][legend.any(axis=1)]
        mask = legend[legend.any(axis=1)]
        ends = [bar[k][mask[k]].mean(axis=0) for k in (0, -1)]
        if np.abs(ends[0] - ends[1]).max() < 100:
            fail(f"colour bar shows one colour only: top {ends[0]}, bottom {ends[1]}")
        # Its title and labels: dark grey text pixels beside the bar.
        dark = (rgb[:, split:].max(axis=2) < 100) & ~legend
        if dark.sum() < 200:
            fail(f"colour bar has no labels ({dark.sum()} text pixels)")
        print(f"image: {visible:.4f} of the scene coloured, {low:.4f} of it in the bottom third; colour bar over rows {rows[0]}-{rows[-1]}")
    print(f"OK: {checked} frames compared with snapshots, walls and contacts consistent")


if __name__ == "__main__":
    main()
