"""The Catalyst script of the in situ example (blobs.cpp): every step's AMR data ("input") drawn
with the ExaBricks representation into OUT/step_NNNN.png, and every EVERY-th step written as
OUT/step_NNNN.vthb (ParaView's XML AMR format, which `exabricks render` and ParaView read).

Environment: EXABRICKS_PV_PLUGIN (the plugin's ExaBricks.so, required), EXABRICKS_INSITU_OUT
(the folder, set by the simulation from --out), EXABRICKS_INSITU_VIEW (optional: a JSON file
with any of "size", "position", "focus", "up", "angle", "range", "colors", "alpha", "unit",
"samples", "every")."""
import json
import os

import paraview.simple
from paraview.simple import (ColorBy, CreateView, GetColorTransferFunction, GetOpacityTransferFunction, LoadPlugin,
                             Render, SaveScreenshot, Show, TrivialProducer, XMLUniformGridAMRWriter)

view_settings = {
    "size": [480, 360], "position": [1.75, -0.85, 1.3], "focus": [0.5, 0.5, 0.5], "up": [0, 0, 1], "angle": 30.0,
    "range": [0.0, 1.0], "colors": [[0.1, 0.2, 0.9], [1.0, 0.8, 0.1]], "alpha": [0.0, 0.3],
    "unit": 1.0 / 256, "samples": 8, "every": 5,
}
if os.environ.get("EXABRICKS_INSITU_VIEW"):
    with open(os.environ["EXABRICKS_INSITU_VIEW"]) as f:
        view_settings.update(json.load(f))
out = os.environ.get("EXABRICKS_INSITU_OUT", ".")
os.makedirs(out, exist_ok=True)
LoadPlugin(os.environ["EXABRICKS_PV_PLUGIN"], ns=globals())
paraview.simple._DisableFirstRenderCameraReset()  # the camera is the one set below

# The simulation's channel.
producer = TrivialProducer(registrationName="input")
view = CreateView("RenderView")
view.ViewSize = view_settings["size"]
view.OrientationAxesVisibility = 0
view.UseColorPaletteForBackground = 0
view.Background = [0.0, 0.0, 0.0]
view.UseFXAA = 0
view.CameraPosition = view_settings["position"]
view.CameraFocalPoint = view_settings["focus"]
view.CameraViewUp = view_settings["up"]
view.CameraViewAngle = view_settings["angle"]
display = Show(producer, view)
display.Representation = "ExaBricks"
ColorBy(display, ("CELLS", "density"))
low, high = view_settings["range"]
lut = GetColorTransferFunction("density")
lut.ColorSpace = "RGB"
lut.Discretize = 0
lut.RGBPoints = [low, *view_settings["colors"][0], high, *view_settings["colors"][1]]
lut.AutomaticRescaleRangeMode = "Never"
opacity = GetOpacityTransferFunction("density")
opacity.Points = [low, view_settings["alpha"][0], 0.5, 0.0, high, view_settings["alpha"][1], 0.5, 0.0]
display.ScalarOpacityUnitDistance = view_settings["unit"]
display.SamplesPerPixel = view_settings["samples"]


def catalyst_execute(info):
    name = os.path.join(out, "step_%04d" % info.timestep)
    Render(view)
    SaveScreenshot(name + ".png", view, ImageResolution=view_settings["size"])
    if info.timestep % view_settings["every"] == 0:
        # Inline base64 (valid XML: Debian 12's current expat refuses raw appended data).
        XMLUniformGridAMRWriter(Input=producer, FileName=name + ".vthb", DataMode="Binary").UpdatePipeline(info.time)
