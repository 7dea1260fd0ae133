"""Renders the last particle frame of a grainflow VTK series to a PNG with VTK's off-screen
renderer: spheres coloured by a point array of the frame, with a colour bar naming the
quantity and its unit, the frame's time, and the box walls as translucent faces.

    python render_snapshot.py OUT/vtk image.png [--field speed|contacts]

    speed     |velocity| in m/s, on a logarithmic scale in whole decades from the slowest 5 %
              of the particles to the fastest (at most four; slower ones take the lowest
              colour): a settling bed spans decades, and on a linear scale every bead at rest
              would look the same
    contacts  number of contacts of each particle (coordination number), 0 to the largest

The scene takes the left SCENE_FRACTION of the image and the colour bar the right part
(check_vtk.py relies on that split).
"""
import argparse
import xml.etree.ElementTree as ET
from pathlib import Path

import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy

import numpy as np

SCENE_FRACTION = 0.75
MAX_DECADES = 4

# Viridis (perceptually uniform, readable in grey and by colour-blind readers), 9 stops.
VIRIDIS = [
    (0.267, 0.005, 0.329),
    (0.279, 0.175, 0.483),
    (0.230, 0.322, 0.546),
    (0.173, 0.449, 0.558),
    (0.128, 0.567, 0.551),
    (0.158, 0.684, 0.502),
    (0.369, 0.789, 0.383),
    (0.678, 0.864, 0.190),
    (0.993, 0.906, 0.144),
]


def last_frame(folder: Path, collection: str):
    frames = list(ET.parse(folder / collection).getroot().iter("DataSet"))
    return folder / frames[-1].get("file"), float(frames[-1].get("timestep"))


def lookup_table(lo: float, hi: float, log: bool, colours: int = 256) -> vtk.vtkLookupTable:
    lut = vtk.vtkLookupTable()
    lut.SetNumberOfTableValues(colours)
    if log:
        lut.SetScaleToLog10()
    lut.SetRange(lo, hi)
    stops = np.array(VIRIDIS)
    x = np.linspace(0.0, 1.0, len(stops))
    for k in range(colours):
        f = k / (colours - 1)
        lut.SetTableValue(k, *(float(np.interp(f, x, stops[:, c])) for c in range(3)), 1.0)
    lut.Build()
    return lut


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", help="the vtk/ folder of a run")
    ap.add_argument("png", help="image to write")
    ap.add_argument("--field", choices=["speed", "contacts"], default="speed")
    args = ap.parse_args()
    folder = Path(args.folder)
    frame, time = last_frame(folder, "particles.pvd")
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(str(frame))
    reader.Update()
    data = reader.GetOutput()
    points = data.GetPointData()

    if args.field == "speed":
        values = np.linalg.norm(vtk_to_numpy(points.GetArray("velocity")), axis=1)
        # Whole decades (the bar's labels fall on powers of ten), from the slowest 5 % to the
        # fastest particle, at most MAX_DECADES.
        top = np.ceil(np.log10(max(float(values.max()), 1e-300)))
        bottom = np.floor(np.log10(max(float(np.percentile(values, 5)), 1e-300)))
        decades = int(min(max(top - bottom, 1), MAX_DECADES))
        lo, hi = 10.0 ** (top - decades), 10.0**top
        title, fmt, log = "speed (m/s)", "%.0e", True
    else:
        values = vtk_to_numpy(points.GetArray("contacts")).astype(float)
        lo, hi = 0.0, max(float(values.max()), 1.0)
        decades = 0
        title, fmt, log = "contacts (count)", "%.0f", False
    colour = numpy_to_vtk(np.ascontiguousarray(values), deep=True)
    colour.SetName("colour")
    points.AddArray(colour)
    points.SetActiveScalars("radius")

    sphere = vtk.vtkSphereSource()
    sphere.SetThetaResolution(20)
    sphere.SetPhiResolution(14)
    sphere.SetRadius(1.0)
    glyph = vtk.vtkGlyph3D()
    glyph.SetInputData(data)
    glyph.SetSourceConnection(sphere.GetOutputPort())
    glyph.SetScaleModeToScaleByScalar()
    glyph.SetScaleFactor(1.0)
    glyph.Update()

    lut = lookup_table(lo, hi, log)
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(glyph.GetOutputPort())
    mapper.SetScalarModeToUsePointFieldData()
    mapper.SelectColorArray("colour")
    mapper.SetLookupTable(lut)
    mapper.UseLookupTableScalarRangeOn()
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    # Some ambient light, so that the shaded side of a sphere keeps its colour.
    actor.GetProperty().SetAmbient(0.35)
    actor.GetProperty().SetDiffuse(0.65)

    walls = vtk.vtkXMLPolyDataReader()
    walls.SetFileName(str(folder / "walls.vtp"))
    wall_mapper = vtk.vtkPolyDataMapper()
    wall_mapper.SetInputConnection(walls.GetOutputPort())
    wall_mapper.ScalarVisibilityOff()
    wall_actor = vtk.vtkActor()
    wall_actor.SetMapper(wall_mapper)
    wall_actor.GetProperty().SetOpacity(0.15)
    wall_actor.GetProperty().SetColor(0.6, 0.6, 0.6)
    edges = vtk.vtkFeatureEdges()
    edges.SetInputConnection(walls.GetOutputPort())
    edge_mapper = vtk.vtkPolyDataMapper()
    edge_mapper.SetInputConnection(edges.GetOutputPort())
    edge_mapper.ScalarVisibilityOff()
    edge_actor = vtk.vtkActor()
    edge_actor.SetMapper(edge_mapper)
    edge_actor.GetProperty().SetColor(0.2, 0.2, 0.2)

    scene = vtk.vtkRenderer()
    scene.SetViewport(0.0, 0.0, SCENE_FRACTION, 1.0)
    scene.SetBackground(1.0, 1.0, 1.0)
    for a in (actor, wall_actor, edge_actor):
        scene.AddActor(a)
    label = vtk.vtkTextActor()
    label.SetInput(f"t = {time:g} s, {data.GetNumberOfPoints()} particles")
    label.GetTextProperty().SetColor(0.1, 0.1, 0.1)
    label.GetTextProperty().SetFontSize(20)
    label.SetDisplayPosition(12, 12)
    scene.AddViewProp(label)

    legend = vtk.vtkRenderer()
    legend.SetViewport(SCENE_FRACTION, 0.0, 1.0, 1.0)
    legend.SetBackground(1.0, 1.0, 1.0)
    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle(title)
    bar.SetLabelFormat(fmt)
    bar.SetNumberOfLabels(decades + 1 if log else int(min(hi, 10)) + 1)
    bar.SetMaximumNumberOfColors(256)
    bar.UnconstrainedFontSizeOn()
    for text in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
        text.SetColor(0.1, 0.1, 0.1)
        text.SetFontFamilyToArial()
        text.BoldOff()
        text.ItalicOff()
        text.ShadowOff()
    bar.GetTitleTextProperty().SetFontSize(22)
    bar.GetLabelTextProperty().SetFontSize(18)
    bar.SetPosition(0.12, 0.1)
    bar.SetPosition2(0.8, 0.8)
    legend.AddViewProp(bar)

    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.AddRenderer(scene)
    window.AddRenderer(legend)
    window.SetSize(1000, 800)
    camera = scene.GetActiveCamera()
    scene.ResetCamera()
    camera.Elevation(20)
    camera.Azimuth(30)
    scene.ResetCamera()
    window.Render()

    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(args.png)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()


if __name__ == "__main__":
    main()
