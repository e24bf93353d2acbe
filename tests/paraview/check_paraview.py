"""The ExaBricks representation in ParaView, run by pvbatch:

    pvbatch check_paraview.py PLUGIN EXABRICKS_CLI WORK_DIR [DATA_DIR]

1. plt_small through ParaView's AMReX reader, shown as "ExaBricks" with a two-point colour map
   and opacity ramp, equals `exabricks render --spp 8` of the same file, camera and transfer
   function (its linear .pfm against ParaView's 8-bit screenshot, within one 8-bit step plus
   rounding): a still render refines to the default 8 samples per pixel;
2. an opaque plane in front of the data covers it with its own colour, and one behind shows
   only through the volume: red and blue stay the volume's, green grows by at most the
   plane's;
3. the same data written by ParaView's AMR writer (.vthb) and read back by its XML AMR
   reader gives the same picture, and `exabricks render` of that file equals its render of
   the plotfile;
4. the three-level PeleLM plotfile's mag_vort (every level covers the domain; a 0.016 world) equals
   `exabricks render` within the same bound.

Prints "skipped: ..." (and exits 0) where the shared sample is absent."""
import json
import os
import subprocess
import sys

import numpy as np
import paraview.simple
from paraview.simple import Hide, LoadPlugin, Show, XMLUniformGridAMRReader, XMLUniformGridAMRWriter

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pv_common import (ALPHA, HEIGHT, RANGE, WIDTH, exabricks_render, finest_cell,  # noqa: E402
                       plotfile_or_skip, screenshot, setup_view, show_exabricks, show_planes)

plugin, cli, work = sys.argv[1:4]
plotfile = plotfile_or_skip(sys.argv[4] if len(sys.argv) > 4 else None)
os.makedirs(work, exist_ok=True)
LoadPlugin(plugin, ns=globals())
paraview.simple._DisableFirstRenderCameraReset()  # the camera is the one set below

reader, view, display = setup_view(plotfile, finest_cell(cli, plotfile))
volume = screenshot(view, work, "paraview.png")
# The representation's default: 8 samples per pixel, unlit.
reference = exabricks_render(cli, plotfile, work, "exabricks.pfm", "--spp", "8")
difference = np.abs(volume - reference)
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
slabs = show_planes(view, SPLIT)
both = screenshot(view, work, "paraview-planes.png")
Hide(reader, view)
alone = screenshot(view, work, "planes.png")
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

# 3. The same data written by ParaView's own AMR writer and read back by its XML AMR reader (all
# levels: it reads one by default): the same picture; and exabricks render of that file equals its
# render of the plotfile.
vthb = os.path.join(work, "plt_small.vthb")
# Inline base64 (valid XML): Debian 12's current expat refuses raw appended data in VTK 9.2's reader.
XMLUniformGridAMRWriter(Input=reader, FileName=vthb, DataMode="Binary").UpdatePipeline()
xml = XMLUniformGridAMRReader(FileName=[vthb])
xml.DefaultNumberOfLevels = 10
Hide(reader, view)
for source in slabs:
    Hide(source, view)
show_exabricks(Show(xml, view), "phi", RANGE, ALPHA, display.ScalarOpacityUnitDistance)
from_xml = screenshot(view, work, "paraview-vthb.png")
difference = np.abs(from_xml - reference)
print("ParaView's own .vthb through its XML AMR reader: max %.4f, mean %.5f" % (difference.max(), difference.mean()))
if difference.max() > 1.5 / 255:
    failures.append("ParaView's picture of its own .vthb differs from exabricks render by %.4f" % difference.max())
written = exabricks_render(cli, vthb, work, "exabricks-vthb.pfm", "--spp", "8")
if np.abs(written - reference).max() > 0:
    failures.append("exabricks render of ParaView's .vthb differs from its render of the plotfile by %.4f"
                    % np.abs(written - reference).max())
Hide(xml, view)

# 4. Three levels that each cover the whole domain (ParaView blanks the covered cells), a small
# world (0.016 on a side) and a field other than phi: the same bound.
pelelm = os.path.join(os.path.dirname(os.path.dirname(plotfile)),
                      "pelelm_3lev_3d", "example_plt_3d")
if os.path.isdir(pelelm):
    Hide(reader, view)
    info = json.loads(subprocess.run([cli, "info", "--json", pelelm], check=True, capture_output=True).stdout)
    lower, upper = (np.asarray(info["bounds"]["world"][k]) for k in ("lower", "upper"))
    vorticity = [f["range"] for f in info["fields"] if f["name"] == "mag_vort"][0]
    value_range = (vorticity["min"], vorticity["max"])
    centre = (lower + upper) / 2
    camera = (tuple(centre + np.linalg.norm(upper - lower) * np.array([1.2, -0.8, 0.9])), tuple(centre))
    alpha = (0.0, 0.08)  # per finest cell: the flame shows through the hot gas
    _, pelelm_view, _ = setup_view(pelelm, finest_cell(cli, pelelm), "mag_vort", value_range, alpha, camera)
    pelelm_image = screenshot(pelelm_view, work, "paraview-pelelm.png")
    pelelm_reference = exabricks_render(cli, pelelm, work, "exabricks-pelelm.pfm", "--spp", "8", field="mag_vort",
                                        value_range=value_range, alpha=alpha, camera=camera)
    difference = np.abs(pelelm_image - pelelm_reference)
    shown = (pelelm_reference.max(axis=-1) > 0.02).mean()
    print("three-level PeleLM plotfile, mag_vort: max %.4f, mean %.5f, %.0f%% showing data"
          % (difference.max(), difference.mean(), 100 * shown))
    if not 0.1 < shown < 0.9:
        failures.append("the PeleLM reference shows data in %.0f%% of the pixels" % (100 * shown))
    if difference.max() > 1.5 / 255:
        failures.append("ParaView's picture of the PeleLM plotfile differs from exabricks render by %.4f"
                        " (bound 1.5/255)" % difference.max())
else:
    print("the three-level PeleLM sample is absent (%s): that part is not checked" % pelelm)

if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("passed")
