"""A pvpython client's picture of plt_small as ExaBricks, rendered by a render server or in
pvpython's own session (the reference):

    pvpython render_client.py PLUGIN SETTINGS_JSON OUT_PNG [PORT]

With PORT, connects to a pvserver on localhost (several processes under mpiexec) and loads the
plugin on both sides; SETTINGS_JSON as for render_parallel.py."""
import json
import os
import sys

from paraview.simple import Connect, LoadPlugin, Render, SaveScreenshot

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pv_common import HEIGHT, WIDTH, information, setup_view  # noqa: E402

plugin, settings, out = sys.argv[1:4]
with open(settings) as f:
    settings = json.load(f)
if len(sys.argv) > 4:
    Connect("localhost", int(sys.argv[4]))
    LoadPlugin(plugin, remote=True, ns=globals())  # the server renders
LoadPlugin(plugin, remote=False, ns=globals())  # the client holds the representation's proxies
import paraview.simple  # noqa: E402

paraview.simple._DisableFirstRenderCameraReset()
reader, view, display = setup_view(settings["plotfile"], settings["cell"])
view.UseFXAA = 0
Render(view)
SaveScreenshot(out, view, ImageResolution=[WIDTH, HEIGHT])
print("rendered", out, "passes", information(display, "RefinementPasses"))
