"""What the pvbatch checks of the ExaBricks representation share: the shared sample, its finest
cell, the view and transfer function they use, images read back, and `exabricks render` of the
same camera and transfer function."""
import json
import math
import os
import subprocess
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOImage import vtkPNGReader

WIDTH, HEIGHT = 160, 120
POSITION, FOCUS, UP, ANGLE = (1.9, -1.1, 1.4), (0.5, 0.5, 0.5), (0.0, 0.0, 1.0), 30.0
RANGE = (1.0, 2.0)
COLORS = ((0.1, 0.2, 0.9), (1.0, 0.8, 0.1))  # the colour map's two ends, as VTK blends them
ALPHA = (0.0, 0.8)  # opacity per finest cell width at the ends
TERMINATION_OPACITY = 1.0 - 0.5 / 255.0  # where the representation ends rays (8-bit images)


def plotfile_or_skip(data_dir):
    """The shared plt_small, or exits with "skipped: ..." where it is absent."""
    if data_dir is None:
        data_dir = os.environ.get("EXABRICKS_DATA",
                                  os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data"))
    plotfile = os.path.abspath(os.path.join(data_dir, "amrex", "advection_3d", "plt_small"))
    if not os.path.isdir(plotfile):
        print("skipped: shared sample %s is absent (set EXABRICKS_DATA to the folder of shared samples)" % plotfile)
        sys.exit(0)
    return plotfile


def finest_cell(cli, plotfile):
    """ParaView's opacity is per ScalarOpacityUnitDistance, exabricks' per finest cell: with this
    unit distance the two opacity functions are the same numbers."""
    info = json.loads(subprocess.run([cli, "info", "--json", plotfile], check=True, capture_output=True).stdout)
    world, lattice = info["bounds"]["world"], info["bounds"]["lattice"]
    return (world["upper"][0] - world["lower"][0]) / (lattice["upper"][0] - lattice["lower"][0])


def read_png(path):
    r = vtkPNGReader()
    r.SetFileName(path)
    r.Update()
    return image_pixels(r.GetOutput())


def image_pixels(image):
    """A vtkImageData's RGB as floats in [0, 1], row 0 at the top."""
    w, h, _ = image.GetDimensions()
    pixels = vtk_to_numpy(image.GetPointData().GetScalars()).reshape(h, w, -1)
    return pixels[::-1, :, :3].astype(np.float64) / 255.0


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        values = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return values.reshape(h, w, 3)[::-1].astype(np.float64)


def srgb(c):
    return [12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055 for v in c]


def map_color(value):
    """The two-point colour map at a value, as VTK blends it (RGB space)."""
    t = min(1.0, max(0.0, (value - RANGE[0]) / (RANGE[1] - RANGE[0])))
    return [a + t * (b - a) for a, b in zip(*COLORS)]


def write_tf(work, value_range=RANGE, alpha=ALPHA):
    tf = {"colormap": {"points": [[0.0, *srgb(COLORS[0])], [1.0, *srgb(COLORS[1])]]},
          "opacity": [[0.0, alpha[0]], [1.0, alpha[1]]], "range": list(value_range), "log": False,
          "opacity_scale": 1.0}
    path = os.path.join(work, "tf.json")
    with open(path, "w") as f:
        json.dump(tf, f)
    return path


def exabricks_render(cli, plotfile, work, name, *options, field="phi", value_range=RANGE, alpha=ALPHA,
                     camera=(POSITION, FOCUS)):
    """`exabricks render` of a field (phi unless told) with the shared camera and transfer function
    (or the given camera position and focus, value range and opacity ramp; unlit unless the
    options say otherwise), read back as linear RGB clipped to [0, 1]."""
    path = os.path.join(work, name)
    scene = os.path.join(work, "termination.json")
    with open(scene, "w") as f:
        json.dump({"integration": {"termination_opacity": TERMINATION_OPACITY}}, f)
    subprocess.run([cli, "render", plotfile, "--scene", scene, "--field", field,
                    "--tf", write_tf(work, value_range, alpha),
                    "--size", "%dx%d" % (WIDTH, HEIGHT), "--position", ",".join(map(str, camera[0])),
                    "--look-at", ",".join(map(str, camera[1])), "--up", ",".join(map(str, UP)), "--fov", str(ANGLE),
                    *([] if "--shading" in options else ["--shading", "none"]), *options, "-o", path],
                   check=True, capture_output=True)
    return np.clip(read_pfm(path), 0.0, 1.0)


def new_view():
    """A render view of the checks' size on black, without the orientation axes."""
    from paraview.simple import CreateView
    view = CreateView("RenderView")
    view.ViewSize = [WIDTH, HEIGHT]
    view.OrientationAxesVisibility = 0
    view.UseColorPaletteForBackground = 0
    view.Background = [0.0, 0.0, 0.0]
    return view


def setup_view(plotfile, cell, field="phi", value_range=RANGE, alpha=ALPHA, camera=(POSITION, FOCUS)):
    """A plotfile (plt_small) through ParaView's AMReX reader at every level, its field (phi)
    shown as ExaBricks with the shared colour map and opacity ramp (or the given one) over the
    value range, and the shared camera (or the given position and focus). Returns (reader, view,
    display)."""
    from paraview.simple import AMReXBoxLibGridReader, Show
    reader = AMReXBoxLibGridReader(FileNames=[plotfile])
    reader.CellArrayStatus = [field]
    reader.Level = 10  # every level (the reader's default reads levels 0 and 1 only)
    view = new_view()
    display = Show(reader, view)
    show_exabricks(display, field, value_range, alpha, cell)
    view.CameraPosition, view.CameraFocalPoint, view.CameraViewUp = camera[0], camera[1], UP
    view.CameraViewAngle = ANGLE
    return reader, view, display


def show_exabricks(display, field, value_range, alpha, cell):
    """Shows a display as ExaBricks coloured by a cell field with the shared colour map and the
    opacity ramp over the value range, unit distance `cell`."""
    from paraview.simple import ColorBy, GetColorTransferFunction, GetOpacityTransferFunction
    display.Representation = "ExaBricks"
    ColorBy(display, ("CELLS", field))
    lut = GetColorTransferFunction(field)
    lut.ColorSpace = "RGB"
    lut.Discretize = 0
    lut.RGBPoints = [value_range[0], *COLORS[0], value_range[1], *COLORS[1]]
    lut.AutomaticRescaleRangeMode = "Never"
    pwf = GetOpacityTransferFunction(field)
    pwf.Points = [value_range[0], alpha[0], 0.5, 0.0, value_range[1], alpha[1], 0.5, 0.0]
    display.ScalarOpacityUnitDistance = cell


def show_planes(view, split=0.53):
    """Two opaque, flat green planes across the view: one between the camera and the data over
    the left of the view, one beyond the data over the right, meeting at `split` of the view's
    width across the column the data shows. Returns their sources."""
    from paraview.simple import Plane, Show
    forward = np.subtract(FOCUS, POSITION)
    distance = float(np.linalg.norm(forward))
    forward /= distance
    right = np.cross(forward, UP)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    slabs = []
    for depth, (u0, u1) in ((distance - 1.0, (-0.05, split)), (distance + 1.0, (split, 1.05))):
        half = math.tan(math.radians(ANGLE / 2)) * depth  # half the view's height at that depth
        x0, x1 = [(2 * u - 1) * half * WIDTH / HEIGHT for u in (u0, u1)]
        corner = np.asarray(POSITION) + forward * depth + right * x0 - up * 1.1 * half
        slab = Plane(Origin=list(corner), Point1=list(corner + right * (x1 - x0)),
                     Point2=list(corner + up * 2.2 * half))
        slabs.append(slab)
        plane = Show(slab, view)
        plane.Representation = "Surface"
        plane.ColorArrayName = ["POINTS", ""]
        plane.AmbientColor = plane.DiffuseColor = [0.0, 1.0, 0.0]
        plane.Ambient, plane.Diffuse, plane.Specular = 1.0, 0.0, 0.0
    return slabs


def screenshot(view, work, name):
    from paraview.simple import Render, SaveScreenshot
    path = os.path.join(work, name)
    Render(view)
    SaveScreenshot(path, view, ImageResolution=[WIDTH, HEIGHT])
    return read_png(path)


def information(display, name):
    """An information property of the representation (Model Builds, Refinement Passes, ...)."""
    display.SMProxy.UpdatePropertyInformation()
    return display.SMProxy.GetProperty(name).GetElement(0)
