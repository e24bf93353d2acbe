"""ParaView's own "Volume" representation of AMR data against "ExaBricks", with the same data,
view, camera and transfer function, in one pvbatch run:

    xvfb-run -a pvbatch paraview/compare_volume.py PLUGIN PLOTFILE OUT_DIR \\
        [--size 1024x768] [--views 10] [--spp 8] [--field phi] [--doc-width 0]

The camera looks at the blocks of the finest level from a fixed direction. For each
representation: the first still frame (after the reader has read every level; for Volume
it includes the resampling to its grid, for ExaBricks the model build and the refinement to
--spp passes), then an orbit of --views views around the data (Azimuth 360/views degrees each),
each taken as an interactive render (ParaView's render while the user drags: ExaBricks draws its
draft) and then a still render (ExaBricks refines to --spp passes); the medians over the orbit.
Writes volume.png, exabricks.png (still, first view) and exabricks-draft.png (the interactive
render of the first view) to OUT_DIR, and with --doc-width W copies of them W pixels wide
(*-doc.png), and prints the table and the settings it used."""
import argparse
import os
import statistics
import time

import paraview.simple
from paraview.simple import (AMReXBoxLibGridReader, ColorBy, CreateView, GetColorTransferFunction,
                             GetOpacityTransferFunction, LoadPlugin, Render, SaveScreenshot, Show)
from vtkmodules.vtkImagingCore import vtkImageResize
from vtkmodules.vtkIOImage import vtkPNGReader, vtkPNGWriter
from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("plugin")
parser.add_argument("plotfile")
parser.add_argument("out")
parser.add_argument("--size", default="1024x768")
parser.add_argument("--views", type=int, default=10)
parser.add_argument("--spp", type=int, default=8)
parser.add_argument("--field", default="phi")
parser.add_argument("--doc-width", type=int, default=0)
args = parser.parse_args()
width, height = map(int, args.size.lower().split("x"))
os.makedirs(args.out, exist_ok=True)
LoadPlugin(args.plugin, ns=globals())
paraview.simple._DisableFirstRenderCameraReset()

reader = AMReXBoxLibGridReader(FileNames=[os.path.abspath(args.plotfile)])
reader.CellArrayStatus = [args.field]
reader.Level = 100  # every level: the reader's default stops at level 1
start = time.perf_counter()
reader.UpdatePipeline()
read_seconds = time.perf_counter() - start
info = reader.GetDataInformation()
value_range = reader.CellData[args.field].GetRange()
bounds = info.GetBounds()

view = CreateView("RenderView")
view.ViewSize = [width, height]
view.OrientationAxesVisibility = 0
view.UseColorPaletteForBackground = 0
view.Background = [0.0, 0.0, 0.0]
display = Show(reader, view)
ColorBy(display, ("CELLS", args.field))
lut = GetColorTransferFunction(args.field)
lut.ApplyPreset("Inferno (matplotlib)", True)
lut.RescaleTransferFunction(value_range[0], value_range[1])
lut.AutomaticRescaleRangeMode = "Never"
low, high = value_range
span = high - low
opacity = GetOpacityTransferFunction(args.field)
# Transparent background (phi near its lowest value), a faint ramp towards the highest values and
# a narrow peak (a thin shell around the middle value): detail a resampled grid has to resolve.
mid = low + 0.5 * span
opacity.Points = [low, 0.0, 0.5, 0.0, low + 0.02 * span, 0.0, 0.5, 0.0, mid - 0.04 * span, 0.01, 0.5, 0.0,
                  mid, 0.4, 0.5, 0.0, mid + 0.04 * span, 0.01, 0.5, 0.0, high, 0.06, 0.5, 0.0]
opacity.RescaleTransferFunction(low, high)
extent = max(bounds[1] - bounds[0], bounds[3] - bounds[2], bounds[5] - bounds[4])
display.ScalarOpacityUnitDistance = extent / 256.0
# The camera frames the finest level's blocks (where the data has its detail).
amr = reader.GetClientSideObject().GetOutputDataObject(0)
finest = amr.GetNumberOfLevels() - 1
lower, upper = [float("inf")] * 3, [float("-inf")] * 3
for block in range(amr.GetNumberOfDataSets(finest)):
    grid = amr.GetDataSet(finest, block)
    if grid is not None:
        b = grid.GetBounds()
        lower = [min(lower[a], b[2 * a]) for a in range(3)]
        upper = [max(upper[a], b[2 * a + 1]) for a in range(3)]
center = [(lo + hi) / 2 for lo, hi in zip(lower, upper)]
size = max(hi - lo for lo, hi in zip(lower, upper))


def start_camera():
    view.CameraFocalPoint = center
    view.CameraPosition = [center[0] + 1.3 * size, center[1] - 1.9 * size, center[2] + 1.2 * size]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    view.CameraViewAngle = 30.0


def timed(call):
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


def grab(path):
    """The render window as it is (after an interactive render, which a screenshot would redo)."""
    w2i = vtkWindowToImageFilter()
    w2i.SetInput(view.GetRenderWindow())
    w2i.ReadFrontBufferOff()
    w2i.ShouldRerenderOff()
    w2i.Update()
    writer = vtkPNGWriter()
    writer.SetInputConnection(w2i.GetOutputPort())
    writer.SetFileName(path)
    writer.Write()


def information(name):
    display.SMProxy.UpdatePropertyInformation()
    return display.SMProxy.GetProperty(name).GetElement(0)


def measure(representation, name):
    display.Representation = representation
    start_camera()
    first = timed(lambda: Render(view))
    SaveScreenshot(os.path.join(args.out, name + ".png"), view, ImageResolution=[width, height])
    extra = {}
    if representation == "ExaBricks":
        extra["first passes"] = information("RefinementPasses")
        view.InteractiveRender()
        grab(os.path.join(args.out, name + "-draft.png"))
        extra["draft passes"] = information("RefinementPasses")
        Render(view)
    interactive, still = [], []
    camera = view.GetActiveCamera()
    for _ in range(args.views):
        camera.Azimuth(360.0 / args.views)
        interactive.append(timed(view.InteractiveRender))
        still.append(timed(lambda: Render(view)))
    return {"first": first, "interactive": statistics.median(interactive), "still": statistics.median(still),
            "interactive all": interactive, "still all": still, **extra}


display.SamplesPerPixel = args.spp
volume = measure("Volume", "volume")
exabricks = measure("ExaBricks", "exabricks")

cells = info.GetNumberOfCells()
print("data: %s, %d levels, %d cells in all blocks (read in %.2f s), %s range %.4g..%.4g"
      % (os.path.basename(os.path.normpath(args.plotfile)), info.GetNumberOfAMRLevels(), cells, read_seconds,
         args.field, low, high))
print("view: %dx%d, %d views in the orbit; ScalarOpacityUnitDistance %.5g" % (width, height, args.views,
                                                                            display.ScalarOpacityUnitDistance))
print("Volume: NumberOfSamples %s, ResamplingMode %s, VolumeRenderingMode %s"
      % (list(display.NumberOfSamples), display.ResamplingMode, display.VolumeRenderingMode))
print("ExaBricks: Samples Per Pixel %d, Sampling Rate %g, Device %s (in use: %s), Model Builds %d"
      % (display.SamplesPerPixel, display.SamplingRate, display.Device, information("DeviceInUse"),
         information("ModelBuilds")))
print("")
print("| | first frame | interactive render (median) | still render (median) |")
print("|---|---|---|---|")
print("| ParaView Volume | %.2f s | %.3f s | %.3f s |" % (volume["first"], volume["interactive"], volume["still"]))
print("| ExaBricks | %.2f s (%d passes) | %.3f s (draft) | %.2f s (%d passes) |"
      % (exabricks["first"], exabricks["first passes"], exabricks["interactive"], exabricks["still"], args.spp))
print("")
for name, r in (("Volume", volume), ("ExaBricks", exabricks)):
    print("%s interactive: %s" % (name, " ".join("%.3f" % t for t in r["interactive all"])))
    print("%s still: %s" % (name, " ".join("%.3f" % t for t in r["still all"])))

if args.doc_width > 0:
    for name in ("volume", "exabricks", "exabricks-draft"):
        png = vtkPNGReader()
        png.SetFileName(os.path.join(args.out, name + ".png"))
        resize = vtkImageResize()
        resize.SetInputConnection(png.GetOutputPort())
        resize.SetOutputDimensions(args.doc_width, round(args.doc_width * height / width), 1)
        resize.InterpolateOn()
        writer = vtkPNGWriter()
        writer.SetInputConnection(resize.GetOutputPort())
        writer.SetFileName(os.path.join(args.out, name + "-doc.png"))
        writer.Write()
