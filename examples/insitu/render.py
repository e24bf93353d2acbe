"""The Catalyst script of the in situ example (blobs.cpp): every step's AMR data ("input") drawn
with the ExaBricks representation into OUT/step_NNNN.png, and every EVERY-th step written as
OUT/step_NNNN.vthb (ParaView's XML AMR format, which `exabricks render` and ParaView read).

Environment: EXABRICKS_PV_PLUGIN (the plugin's ExaBricks.so, required), EXABRICKS_INSITU_OUT
(the folder, set by the simulation from --out), EXABRICKS_INSITU_VIEW (optional: a JSON file
with any of "size", "position", "focus", "up", "angle", "range", "colors", "alpha", "unit",
"samples", "every"), EXABRICKS_CLI (optional: the exabricks command line, used without a display).

Without a display ParaView's render view cannot draw (this ParaView draws through X): the script
says so once and goes on with every step. It still writes the data, and draws each step with
exabricks' own renderer, which needs no display: the step written as .vthb and rendered by `exabricks
render` with the same camera, colour map and opacity (the same picture as the representation's,
within its bounds). Where no exabricks command line is found, the steps are not drawn."""
import ctypes
import ctypes.util
import json
import os
import shutil
import subprocess

import paraview.simple
from paraview.simple import (ColorBy, CreateView, GetColorTransferFunction, GetOpacityTransferFunction, LoadPlugin,
                             Render, SaveScreenshot, Show, TrivialProducer, XMLUniformGridAMRWriter)
from vtkmodules.vtkParallelCore import vtkMultiProcessController

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



def display_problem():
    """Why ParaView's render view cannot draw here, or None: its X render window needs an X
    server it can open (EGL and OSMesa builds need none)."""
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the render window's factory)
    from vtkmodules.vtkRenderingCore import vtkRenderWindow
    if "XOpenGL" not in vtkRenderWindow().GetClassName():
        return None
    if not os.environ.get("DISPLAY"):
        return "no X display (DISPLAY is not set)"
    try:
        x11 = ctypes.CDLL(ctypes.util.find_library("X11") or "libX11.so.6")
        x11.XOpenDisplay.restype = ctypes.c_void_p
        x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
        x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
        handle = x11.XOpenDisplay(None)
    except OSError:
        return None  # ParaView will say what is wrong
    if not handle:
        return "the X display %s cannot be opened" % os.environ["DISPLAY"]
    x11.XCloseDisplay(handle)
    return None


def exabricks_cli():
    """The exabricks command line: EXABRICKS_CLI, else on PATH, else beside the plugin (its build
    folder, or the bin folder of its prefix)."""
    found = os.environ.get("EXABRICKS_CLI") or shutil.which("exabricks")
    if found:
        return found
    root = os.path.dirname(os.path.abspath(os.environ["EXABRICKS_PV_PLUGIN"]))
    for parts in (("..",) * 4 + ("exabricks",), ("..",) * 4 + ("bin", "exabricks")):
        path = os.path.normpath(os.path.join(root, *parts))
        if os.access(path, os.X_OK):
            return path
    return None


controller = vtkMultiProcessController.GetGlobalController()
rank = controller.GetLocalProcessId() if controller else 0
problem = display_problem()
cli = exabricks_cli() if problem else None
if problem and rank == 0:
    if cli:
        print("render.py: %s, so ParaView's render view cannot draw; drawing each step with %s render from the "
              "data instead" % (problem, cli), flush=True)
    else:
        print("render.py: %s, so ParaView's render view cannot draw and no exabricks command line was found "
              "(set EXABRICKS_CLI): the steps are not drawn; the data is written every %d steps"
              % (problem, view_settings["every"]), flush=True)

# The simulation's channel.
producer = TrivialProducer(registrationName="input")


def srgb(c):
    return [12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055 for v in c]


def draw_without_display(vthb, png):
    """`exabricks render` of the data at `vthb` into `png` (first process): the view's camera, the
    two-point colour map and opacity ramp (opacity per unit distance: exabricks' per finest cell
    when the unit is the finest cell, as here), rays ended at the representation's 1 - 0.5/255,
    the 8-bit image of ParaView's linear colours."""
    import numpy as np
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOImage import vtkPNGWriter

    low, high = view_settings["range"]
    base = png[:-len(".png")]
    tf = {"colormap": {"points": [[0.0, *srgb(view_settings["colors"][0])], [1.0, *srgb(view_settings["colors"][1])]]},
          "opacity": [[0.0, view_settings["alpha"][0]], [1.0, view_settings["alpha"][1]]], "range": [low, high],
          "log": False, "opacity_scale": 1.0}
    with open(base + ".tf.json", "w") as f:
        json.dump(tf, f)
    with open(base + ".scene.json", "w") as f:
        json.dump({"integration": {"termination_opacity": 1.0 - 0.5 / 255.0}}, f)
    width, height = view_settings["size"]
    # The command line on its own, not as a process of this MPI job (it would join the job).
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "PMI_", "MPI_LOCALRANK"))}
    subprocess.run([cli, "-q", "render", vthb, "--scene", base + ".scene.json", "--field", "density",
                    "--tf", base + ".tf.json", "--size", "%dx%d" % (width, height), "--shading", "none",
                    "--position", ",".join(map(str, view_settings["position"])),
                    "--look-at", ",".join(map(str, view_settings["focus"])),
                    "--up", ",".join(map(str, view_settings["up"])), "--fov", str(view_settings["angle"]),
                    "--spp", str(view_settings["samples"]), "-o", base + ".pfm"], check=True, capture_output=True,
                   env=env)
    with open(base + ".pfm", "rb") as f:
        f.readline()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        rgb = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4").reshape(h, w, 3)  # bottom row first
    pixels = np.ascontiguousarray((np.clip(rgb, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8).reshape(-1, 3))
    image = vtkImageData()
    image.SetDimensions(w, h, 1)
    image.GetPointData().SetScalars(numpy_to_vtk(pixels))
    writer = vtkPNGWriter()
    writer.SetFileName(png)
    writer.SetInputData(image)
    writer.Write()
    for suffix in (".tf.json", ".scene.json", ".pfm"):
        os.remove(base + suffix)


def write_step(name, time):
    # Inline base64 (valid XML: Debian 12's current expat refuses raw appended data).
    XMLUniformGridAMRWriter(Input=producer, FileName=name + ".vthb", DataMode="Binary").UpdatePipeline(time)


def catalyst_execute_without_display(info):
    name = os.path.join(out, "step_%04d" % info.timestep)
    kept = info.timestep % view_settings["every"] == 0
    if not cli:
        if kept:
            write_step(name, info.time)
        return
    data = name if kept else os.path.join(out, "scratch_%04d" % info.timestep)
    write_step(data, info.time)
    if controller:
        controller.Barrier()  # every process's blocks are on disk
    if rank == 0:
        try:
            draw_without_display(data + ".vthb", name + ".png")
        finally:
            if not kept:
                os.remove(data + ".vthb")
                shutil.rmtree(data, ignore_errors=True)


def show_in_view():
    """ParaView's render view with the ExaBricks representation of the input."""
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
    return view


def catalyst_execute_in_view(info):
    name = os.path.join(out, "step_%04d" % info.timestep)
    Render(view)
    SaveScreenshot(name + ".png", view, ImageResolution=view_settings["size"])
    if info.timestep % view_settings["every"] == 0:
        write_step(name, info.time)


if problem:
    catalyst_execute = catalyst_execute_without_display
else:
    view = show_in_view()
    catalyst_execute = catalyst_execute_in_view
