"""The pictures the parallel check compares, rendered by pvbatch on however many processes
mpirun started (docs/paraview.md, "Several processes"):

    mpirun -np N pvbatch render_parallel.py PLUGIN SETTINGS_JSON OUT_DIR

SETTINGS_JSON holds what the driver learnt with `exabricks info` (which cannot run inside an MPI
job): {"plotfile", "cell", and optionally "pelelm" and "vthb": {"path", "cell", "range",
"camera"}}. Writes
OUT_DIR/CASE.png for every case and OUT_DIR/parts.json (the Parts information of each case and
the passes of the still and interactive renders). Any error ends every process (no hang)."""
import json
import os
import sys
import traceback

import paraview.simple
from paraview.simple import Hide, LoadPlugin, Outline, Render, SaveScreenshot, Show, Slice, XMLUniformGridAMRReader

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pv_common import (ALPHA, ANGLE, HEIGHT, UP, WIDTH, information, new_view, setup_view,  # noqa: E402
                       show_exabricks, show_planes)

plugin, settings, out = sys.argv[1:4]
with open(settings) as f:
    settings = json.load(f)
os.makedirs(out, exist_ok=True)
LoadPlugin(plugin, ns=globals())
paraview.simple._DisableFirstRenderCameraReset()  # the cameras are the ones set below
record = {}


def shot(view, display, name):
    view.UseFXAA = 0  # an image filter outside ExaBricks, applied to each process's image before compositing
    Render(view)
    SaveScreenshot(os.path.join(out, name + ".png"), view, ImageResolution=[WIDTH, HEIGHT])
    record[name] = {"parts": json.loads(information(display, "PartsInformation")),
                    "passes": information(display, "RefinementPasses")}


def main():
    reader, view, display = setup_view(settings["plotfile"], settings["cell"])
    shot(view, display, "volume")

    # Iso-surfaces of the rendered array, lit, inside the volume.
    display.IsoValues = [1.1, 1.5]
    display.Shade = 1
    shot(view, display, "iso")
    # The same with a clip plane through the column.
    display.ClipPlanes = [0.55, 0.5, 0.5, 0.6, -0.8, 0.0]
    shot(view, display, "clip")
    display.ClipPlanes = []
    display.IsoValues = []
    display.Shade = 0

    # Opaque geometry in front of and behind the data, and through it: the blocks' outlines, a
    # slice across the column, and two planes (one between the camera and the data, one beyond
    # it). ParaView moves these between the processes into its cuts.
    box = Outline(Input=reader)
    outline = Show(box, view)
    outline.Representation = "Surface"
    outline.ColorArrayName = ["POINTS", ""]
    outline.AmbientColor = outline.DiffuseColor = [0.9, 0.9, 0.9]
    cut = Slice(Input=reader)
    cut.SliceType.Origin = [0.5, 0.5, 0.62]
    cut.SliceType.Normal = [0.0, 0.0, 1.0]
    flat = Show(cut, view)
    flat.Representation = "Surface"
    flat.ColorArrayName = ["POINTS", ""]
    flat.AmbientColor = flat.DiffuseColor = [0.8, 0.3, 0.3]
    slabs = show_planes(view)
    shot(view, display, "geometry")
    for source in slabs + [cut, box]:
        Hide(source, view)

    # Drafts while interacting: an interactive render after the camera turned, then a still one.
    view.CameraPosition = [1.9, -1.0, 1.5]
    view.InteractiveRender()
    record["draft_passes"] = information(display, "RefinementPasses")
    shot(view, display, "turned")

    if "vthb" in settings:
        # A generated four-level hierarchy (the in situ example's data) through ParaView's XML AMR
        # reader, every level.
        v = settings["vthb"]
        xml = XMLUniformGridAMRReader(FileName=[v["path"]])
        xml.DefaultNumberOfLevels = 10
        vthb_view = new_view()
        vthb_display = Show(xml, vthb_view)
        show_exabricks(vthb_display, "density", tuple(v["range"]), ALPHA, v["cell"])
        vthb_view.CameraPosition, vthb_view.CameraFocalPoint = v["camera"]
        vthb_view.CameraViewUp, vthb_view.CameraViewAngle = UP, ANGLE
        shot(vthb_view, vthb_display, "vthb")

    if "pelelm" in settings:
        p = settings["pelelm"]
        _, pelelm_view, pelelm_display = setup_view(p["path"], p["cell"], "mag_vort", tuple(p["range"]), (0.0, 0.08),
                                                    (tuple(p["camera"][0]), tuple(p["camera"][1])))
        shot(pelelm_view, pelelm_display, "pelelm")

    with open(os.path.join(out, "parts.json"), "w") as f:
        json.dump(record, f, indent=1)
    print("rendered", sorted(k for k in record if isinstance(record[k], dict)))


try:
    main()
except Exception:
    traceback.print_exc()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(1)  # ends the MPI job (mpirun stops the other processes) instead of waiting in MPI's finalize
