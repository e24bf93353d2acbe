"""The ExaBricks representation in ParaView, run by pvbatch:

    pvbatch check_paraview.py PLUGIN EXABRICKS_CLI WORK_DIR [DATA_DIR]

1. plt_small through ParaView's AMReX reader, shown as "ExaBricks" with a two-point colour map
   and opacity ramp, equals `exabricks render` of the same file, camera and transfer function
   (its linear .pfm against ParaView's 8-bit screenshot, within one 8-bit step plus rounding);
2. an opaque plane in front of the data covers it with its own colour, and one behind shows
   only through the volume: red and blue stay the volume's, green grows by at most the
   plane's.

Prints "skipped: ..." (and exits 0) where the shared sample is absent."""
import json
import math
import os
import subprocess
import sys

import numpy as np
import paraview.simple
from paraview.simple import (AMReXBoxLibGridReader, ColorBy, CreateView, GetColorTransferFunction,
                             GetOpacityTransferFunction, Hide, LoadPlugin, Plane, Render, SaveScreenshot, Show)
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOImage import vtkPNGReader

plugin, cli, work = sys.argv[1:4]
data_dir = sys.argv[4] if len(sys.argv) > 4 else os.environ.get(
    "EXABRICKS_DATA", os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data"))
plotfile = os.path.abspath(os.path.join(data_dir, "amrex", "advection_3d", "plt_small"))
if not os.path.isdir(plotfile):
    print("skipped: shared sample %s is absent (set EXABRICKS_DATA to the folder of shared samples)" % plotfile)
    sys.exit(0)
os.makedirs(work, exist_ok=True)
LoadPlugin(plugin, ns=globals())
paraview.simple._DisableFirstRenderCameraReset()  # the camera is the one set below

WIDTH, HEIGHT = 160, 120
POSITION, FOCUS, UP, ANGLE = (1.9, -1.1, 1.4), (0.5, 0.5, 0.5), (0.0, 0.0, 1.0), 30.0
RANGE = (1.0, 2.0)
COLORS = ((0.1, 0.2, 0.9), (1.0, 0.8, 0.1))  # the colour map's two ends, as VTK blends them
ALPHA = (0.0, 0.8)  # opacity per finest cell width at the ends


def read_png(path):
    r = vtkPNGReader()
    r.SetFileName(path)
    r.Update()
    image = r.GetOutput()
    w, h, _ = image.GetDimensions()
    pixels = vtk_to_numpy(image.GetPointData().GetScalars()).reshape(h, w, -1)
    return pixels[::-1, :, :3].astype(np.float64) / 255.0  # row 0 at the top


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        values = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return values.reshape(h, w, 3)[::-1].astype(np.float64)


def srgb(c):
    return [12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055 for v in c]


# The finest cell width: ParaView's opacity is per ScalarOpacityUnitDistance, exabricks' per
# finest cell; with that unit distance the two opacity functions are the same numbers.
info = json.loads(subprocess.run([cli, "info", "--json", plotfile], check=True, capture_output=True).stdout)
world, lattice = info["bounds"]["world"], info["bounds"]["lattice"]
cell = (world["upper"][0] - world["lower"][0]) / (lattice["upper"][0] - lattice["lower"][0])

reader = AMReXBoxLibGridReader(FileNames=[plotfile])
reader.CellArrayStatus = ["phi"]
reader.Level = 10  # every level (the reader's default reads levels 0 and 1 only)
view = CreateView("RenderView")
view.ViewSize = [WIDTH, HEIGHT]
view.OrientationAxesVisibility = 0
view.UseColorPaletteForBackground = 0
view.Background = [0.0, 0.0, 0.0]
display = Show(reader, view)
display.Representation = "ExaBricks"
ColorBy(display, ("CELLS", "phi"))
lut = GetColorTransferFunction("phi")
lut.ColorSpace = "RGB"
lut.Discretize = 0
lut.RGBPoints = [RANGE[0], *COLORS[0], RANGE[1], *COLORS[1]]
lut.AutomaticRescaleRangeMode = "Never"
pwf = GetOpacityTransferFunction("phi")
pwf.Points = [RANGE[0], ALPHA[0], 0.5, 0.0, RANGE[1], ALPHA[1], 0.5, 0.0]
display.ScalarOpacityUnitDistance = cell
view.CameraPosition, view.CameraFocalPoint, view.CameraViewUp = POSITION, FOCUS, UP
view.CameraViewAngle = ANGLE


def screenshot(name):
    path = os.path.join(work, name)
    Render(view)
    SaveScreenshot(path, view, ImageResolution=[WIDTH, HEIGHT])
    return read_png(path)


volume = screenshot("paraview.png")

tf = {"colormap": {"points": [[0.0, *srgb(COLORS[0])], [1.0, *srgb(COLORS[1])]]},
      "opacity": [[0.0, ALPHA[0]], [1.0, ALPHA[1]]], "range": list(RANGE), "log": False, "opacity_scale": 1.0}
tf_path = os.path.join(work, "tf.json")
with open(tf_path, "w") as f:
    json.dump(tf, f)
reference_path = os.path.join(work, "exabricks.pfm")
subprocess.run([cli, "render", plotfile, "--field", "phi", "--tf", tf_path, "--size", "%dx%d" % (WIDTH, HEIGHT),
                "--position", ",".join(map(str, POSITION)), "--look-at", ",".join(map(str, FOCUS)),
                "--up", ",".join(map(str, UP)), "--fov", str(ANGLE), "--shading", "none", "--spp", "1",
                "-o", reference_path], check=True, capture_output=True)
reference = read_pfm(reference_path)
difference = np.abs(volume - np.clip(reference, 0.0, 1.0))
shown = (reference.max(axis=-1) > 0.02).mean()
print("ParaView against exabricks render: max %.4f, mean %.5f over %dx%d pixels, %.0f%% showing data"
      % (difference.max(), difference.mean(), WIDTH, HEIGHT, 100 * shown))
failures = []
if not 0.1 < shown < 0.9:
    failures.append("the reference shows data in %.0f%% of the pixels" % (100 * shown))
if difference.max() > 1.5 / 255:
    failures.append("ParaView's picture differs from exabricks render by %.4f (bound 1.5/255)" % difference.max())

# Opaque planes across the view: one between the camera and the data over the left part of the
# view, one beyond the data over the right part, meeting across the column the data shows; flat
# green (ambient light only).
SPLIT = 0.53  # where the planes meet, as a fraction of the view's width
forward = np.subtract(FOCUS, POSITION)
distance = float(np.linalg.norm(forward))
forward /= distance
right = np.cross(forward, UP)
right /= np.linalg.norm(right)
up = np.cross(right, forward)
for depth, (u0, u1) in ((distance - 1.0, (-0.05, SPLIT)), (distance + 1.0, (SPLIT, 1.05))):
    half = math.tan(math.radians(ANGLE / 2)) * depth  # half the view's height at that depth
    x0, x1 = [(2 * u - 1) * half * WIDTH / HEIGHT for u in (u0, u1)]
    corner = np.asarray(POSITION) + forward * depth + right * x0 - up * 1.1 * half
    slab = Plane(Origin=list(corner), Point1=list(corner + right * (x1 - x0)), Point2=list(corner + up * 2.2 * half))
    plane = Show(slab, view)
    plane.Representation = "Surface"
    plane.ColorArrayName = ["POINTS", ""]
    plane.AmbientColor = plane.DiffuseColor = [0.0, 1.0, 0.0]
    plane.Ambient, plane.Diffuse, plane.Specular = 1.0, 0.0, 0.0
both = screenshot("paraview-planes.png")
Hide(reader, view)
alone = screenshot("planes.png")
Show(reader, view)
columns = np.arange(WIDTH)[None, :].repeat(HEIGHT, axis=0)
front = columns < SPLIT * WIDTH - 2
behind = columns > SPLIT * WIDTH + 2
green = (alone[..., 1] > 0.5) & (alone[..., 0] < 0.05) & (alone[..., 2] < 0.05)
dense = volume.max(axis=-1) > 0.3
in_front = front & green & dense
hidden = behind & green & dense
print("plane in front of the data: %d pixels over it; plane behind it: %d pixels under it" % (in_front.sum(), hidden.sum()))
if in_front.sum() < 50 or hidden.sum() < 50:
    failures.append("the planes do not cross the data as meant (%d, %d pixels)" % (in_front.sum(), hidden.sum()))
over = np.abs(both[in_front] - alone[in_front]).max() if in_front.any() else 0.0
print("in front: largest difference from the plane alone %.4f" % over)
if over > 1.0 / 255 + 1e-9:
    failures.append("the plane in front of the data does not cover it (difference %.4f)" % over)
rb = np.abs(both[hidden][:, [0, 2]] - volume[hidden][:, [0, 2]]).max() if hidden.any() else 0.0
gain = (both[hidden][:, 1] - volume[hidden][:, 1]) / np.maximum(alone[hidden][:, 1], 1e-6)
print("behind: red and blue differ from the volume by %.4f; green gains %.3f..%.3f of the plane's"
      % (rb, gain.min(), gain.max()))
if rb > 1.0 / 255 + 1e-9:
    failures.append("behind the data the volume's red and blue changed by %.4f" % rb)
if gain.max() > 0.9 or gain.min() < -1.0 / 255:
    failures.append("the plane behind the data is not attenuated by it (gain %.3f..%.3f)" % (gain.min(), gain.max()))

if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("passed")
