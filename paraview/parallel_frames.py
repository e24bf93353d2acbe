"""Time per frame and memory per process of the ExaBricks representation on N processes:

    mpiexec -np N pvbatch paraview/parallel_frames.py PLUGIN PLOTFILE [--size WxH] [--field NAME]

Opens an AMReX plotfile at every level, shows it as ExaBricks (Samples Per Pixel 8) and times
the first still frame (redistribution, bricks and regions, 8 passes, compositing), three still
frames of turned views (8 passes each) and three interactive renders (drafts); prints one JSON
object with the medians and the Parts information (cells and bytes per process)."""
import argparse
import json
import statistics
import time

import paraview.simple
from paraview.simple import (AMReXBoxLibGridReader, ColorBy, CreateView, GetColorTransferFunction,
                             GetOpacityTransferFunction, LoadPlugin, Render, Show)

parser = argparse.ArgumentParser()
parser.add_argument("plugin")
parser.add_argument("plotfile")
parser.add_argument("--size", default="1024x768")
parser.add_argument("--field", default="phi")
args = parser.parse_args()
width, height = (int(v) for v in args.size.split("x"))
LoadPlugin(args.plugin, ns=globals())
paraview.simple._DisableFirstRenderCameraReset()
reader = AMReXBoxLibGridReader(FileNames=[args.plotfile])
reader.CellArrayStatus = [args.field]
reader.Level = 10
view = CreateView("RenderView")
view.ViewSize = [width, height]
view.OrientationAxesVisibility = 0
view.UseFXAA = 0
display = Show(reader, view)
display.Representation = "ExaBricks"
ColorBy(display, ("CELLS", args.field))
reader.UpdatePipeline()
low, high = reader.CellData[args.field].GetRange()
lut = GetColorTransferFunction(args.field)
lut.ApplyPreset("Inferno (matplotlib)", True)
lut.RescaleTransferFunction(low, high)
GetOpacityTransferFunction(args.field).Points = [low, 0.0, 0.5, 0.0, high, 0.3, 0.5, 0.0]
display.ScalarOpacityUnitDistance = (reader.GetDataInformation().GetBounds()[1] -
                                     reader.GetDataInformation().GetBounds()[0]) / 256
view.CameraPosition, view.CameraFocalPoint, view.CameraViewUp = [2.0, -1.2, 1.5], [0.5, 0.5, 0.5], [0, 0, 1]
view.CameraViewAngle = 30


def timed(render):
    start = time.perf_counter()
    render()
    return time.perf_counter() - start


first = timed(lambda: Render(view))
still, draft = [], []
for k in range(3):
    view.CameraPosition = [2.0 - 0.2 * (k + 1), -1.2 + 0.25 * (k + 1), 1.5]
    draft.append(timed(view.InteractiveRender))
    still.append(timed(lambda: Render(view)))
display.SMProxy.UpdatePropertyInformation()
parts = json.loads(display.SMProxy.GetProperty("PartsInformation").GetElement(0))
print(json.dumps({"processes": len(parts), "size": [width, height], "first_frame_s": round(first, 3),
                  "still_frame_s": round(statistics.median(still), 3),
                  "draft_s": round(statistics.median(draft), 3),
                  "cells_per_process": [p["cells"] for p in parts],
                  "bytes_per_process": [p["bytes"] for p in parts]}))
