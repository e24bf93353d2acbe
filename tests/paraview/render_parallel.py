"""The pictures the parallel check compares, rendered by pvbatch on however many processes
mpirun started (docs/paraview.md, "Several processes"):

    mpirun -np N pvbatch render_parallel.py PLUGIN EXABRICKS_CLI OUT_DIR PLOTFILE [PELELM]

Writes OUT_DIR/CASE.png for every case and OUT_DIR/parts.json (the Parts information of each
case and the passes of the still and interactive renders)."""
import json
import os
import sys

import paraview.simple
from paraview.simple import Hide, LoadPlugin, Outline, Render, SaveScreenshot, Show, Slice

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pv_common import HEIGHT, WIDTH, finest_cell, information, setup_view, show_planes  # noqa: E402

plugin, cli, out, plotfile = sys.argv[1:5]
pelelm = sys.argv[5] if len(sys.argv) > 5 else ""
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


reader, view, display = setup_view(plotfile, finest_cell(cli, plotfile))
shot(view, display, "volume")

# Iso-surfaces of the rendered array, lit, inside the volume.
display.IsoValues = [1.1, 1.5]
display.Shade = 1
shot(view, display, "iso")
display.IsoValues = []
display.Shade = 0

# Opaque geometry in front of and behind the data, and through it: the domain's outline, a slice
# across the column, and two planes (one between the camera and the data, one beyond it).
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

# Drafts while interacting: an interactive render after the camera turned, then a still one.
for source in slabs + [cut, box]:
    Hide(source, view)
view.CameraPosition = [1.9, -1.0, 1.5]
view.InteractiveRender()
record["draft_passes"] = information(display, "RefinementPasses")
shot(view, display, "turned")

if pelelm:
    info = json.loads(__import__("subprocess").run([cli, "info", "--json", pelelm], check=True,
                                                   capture_output=True).stdout)
    lower, upper = (info["bounds"]["world"][k] for k in ("lower", "upper"))
    centre = [(a + b) / 2 for a, b in zip(lower, upper)]
    size = sum((b - a) ** 2 for a, b in zip(lower, upper)) ** 0.5
    vorticity = [f["range"] for f in info["fields"] if f["name"] == "mag_vort"][0]
    camera = ([c + size * k for c, k in zip(centre, (1.2, -0.8, 0.9))], centre)
    _, pelelm_view, pelelm_display = setup_view(pelelm, finest_cell(cli, pelelm), "mag_vort",
                                                (vorticity["min"], vorticity["max"]), (0.0, 0.08), camera)
    shot(pelelm_view, pelelm_display, "pelelm")

with open(os.path.join(out, "parts.json"), "w") as f:
    json.dump(record, f, indent=1)
print("rendered", sorted(k for k in record if isinstance(record[k], dict)))
