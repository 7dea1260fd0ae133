"""Renders the last particle frame of a grainflow VTK series to a PNG with VTK's off-screen
renderer: spheres coloured by speed, the box walls as translucent faces.

    python render_snapshot.py OUT/vtk image.png
"""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import vtk


def last_frame(folder: Path, collection: str) -> Path:
    frames = ET.parse(folder / collection).getroot().iter("DataSet")
    return folder / list(frames)[-1].get("file")


def main(folder: str, png: str) -> None:
    folder = Path(folder)
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(str(last_frame(folder, "particles.pvd")))
    reader.Update()
    data = reader.GetOutput()
    data.GetPointData().SetActiveScalars("radius")

    sphere = vtk.vtkSphereSource()
    sphere.SetThetaResolution(16)
    sphere.SetPhiResolution(12)
    sphere.SetRadius(1.0)
    glyph = vtk.vtkGlyph3D()
    glyph.SetInputData(data)
    glyph.SetSourceConnection(sphere.GetOutputPort())
    glyph.SetScaleModeToScaleByScalar()
    glyph.SetScaleFactor(1.0)
    glyph.Update()

    speed = vtk.vtkArrayCalculator()
    speed.SetInputConnection(glyph.GetOutputPort())
    speed.AddVectorArrayName("velocity")
    speed.SetFunction("mag(velocity)")
    speed.SetResultArrayName("speed")
    speed.Update()
    out = speed.GetOutput()
    lo, hi = out.GetPointData().GetArray("speed").GetRange()

    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(speed.GetOutputPort())
    mapper.SetScalarModeToUsePointFieldData()
    mapper.SelectColorArray("speed")
    mapper.SetScalarRange(lo, max(hi, lo + 1e-12))
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)

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

    renderer = vtk.vtkRenderer()
    renderer.SetBackground(1.0, 1.0, 1.0)
    for a in (actor, wall_actor, edge_actor):
        renderer.AddActor(a)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.AddRenderer(renderer)
    window.SetSize(800, 800)
    camera = renderer.GetActiveCamera()
    renderer.ResetCamera()
    camera.Elevation(20)
    camera.Azimuth(30)
    renderer.ResetCamera()
    window.Render()

    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(png)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
