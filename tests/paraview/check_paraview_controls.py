"""The ExaBricks representation's controls in ParaView, run by pvbatch:

    pvbatch check_paraview_controls.py PLUGIN EXABRICKS_CLI WORK_DIR [DATA_DIR]

plt_small shown as "ExaBricks" (the view, colour map and opacity ramp of check_paraview.py), each
ParaView screenshot against `exabricks render` of the same file, camera and settings (its linear
.pfm against the 8-bit screenshot, within BOUND):

1. Samples Per Pixel 3 equals --spp 3, and a still render holds 3 passes;
2. Sampling Rate 2 changes the image a little and equals --rate 2;
3. Iso Values [1.1] add a surface in the colour map's colour at 1.1, equal to --iso 1.1
   --iso-color (that colour); Ambient Occlusion Rays 4 darken it, equal to --ao 4;
4. Shade with Shading Analytic and Smooth equals --shading analytic and smooth; Integrator Path
   Tracing with its albedo, sun and environment equals --integrator pathtrace with the same, and
   an albedo out of range is refused (the image stays);
5. none of that, nor a new colour map or opacity function, rebuilt the model (Model Builds 1);
6. an interactive render draws a draft (Refinement Passes 0) that is close to the still image,
   the next still render refines again, and a second still render of the same view adds no pass;
7. Device cpu renders on the CPU; auto on the GPU where this build and machine have one; an
   invalid setting is refused and leaves the image as it was.

Prints "skipped: ..." (and exits 0) where the shared sample is absent."""
import os
import sys
import time

import numpy as np
import paraview.simple
from paraview.simple import GetColorTransferFunction, GetOpacityTransferFunction, LoadPlugin, Render
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pv_common import (COLORS, RANGE, ALPHA, HEIGHT, WIDTH, exabricks_render, finest_cell,  # noqa: E402
                       image_pixels, information, map_color, plotfile_or_skip, screenshot, setup_view, srgb)

BOUND = 1.5 / 255  # an 8-bit step plus rounding

plugin, cli, work = sys.argv[1:4]
plotfile = plotfile_or_skip(sys.argv[4] if len(sys.argv) > 4 else None)
os.makedirs(work, exist_ok=True)
LoadPlugin(plugin, ns=globals())
paraview.simple._DisableFirstRenderCameraReset()

reader, view, display = setup_view(plotfile, finest_cell(cli, plotfile))
failures = []


def compare(what, name, options, bound=BOUND):
    """The view's screenshot against exabricks render with the options."""
    picture = screenshot(view, work, name + ".png")
    reference = exabricks_render(cli, plotfile, work, name + ".pfm", *options)
    d = np.abs(picture - reference)
    print("%s: against exabricks render %s: max %.4f, mean %.5f" % (what, " ".join(options), d.max(), d.mean()))
    if d.max() > bound:
        failures.append("%s differs from exabricks render %s by %.4f (bound %.4f)"
                        % (what, " ".join(options), d.max(), bound))
    return picture


def expect(condition, message):
    if not condition:
        failures.append(message)


# 1. Samples per pixel.
display.SamplesPerPixel = 3
spp3 = compare("Samples Per Pixel 3", "spp3", ["--spp", "3"])
passes = information(display, "RefinementPasses")
print("Samples Per Pixel 3: the still image holds %d passes" % passes)
expect(passes == 3, "a still render with Samples Per Pixel 3 holds %d passes" % passes)

# 2. Sampling rate.
display.SamplingRate = 2.0
rate2 = compare("Sampling Rate 2", "rate2", ["--spp", "3", "--rate", "2"])
change = np.abs(rate2 - spp3)
print("Sampling Rate 2 against 1: max %.4f, mean %.5f" % (change.max(), change.mean()))
expect(0 < change.mean() < 0.01, "Sampling Rate 2 changes the image by %.5f on average (expected a little)"
       % change.mean())
display.SamplingRate = 1.0

# 3. Iso-surfaces and ambient occlusion.
ISO = 1.1
color = ",".join("%.6f" % c for c in srgb(map_color(ISO)))
display.IsoValues = [ISO]
iso = compare("Iso Values [%g]" % ISO, "iso", ["--spp", "3", "--iso", str(ISO), "--iso-color", color])
surface = np.abs(iso - spp3).max(axis=-1) > 0.05
print("the iso-surface changes %d pixels" % surface.sum())
expect(surface.sum() > 200, "the iso-surface changes only %d pixels" % surface.sum())
display.AmbientOcclusionRays = 4
ao = compare("Ambient Occlusion Rays 4", "ao", ["--spp", "3", "--iso", str(ISO), "--iso-color", color,
                                                 "--ao", "4"])
darker = (iso - ao).sum(axis=-1)
print("ambient occlusion darkens %d pixels (by %.3f at most), lightens %d"
      % ((darker > 1.5 / 255).sum(), darker.max(), (darker < -1.5 / 255).sum()))
expect((darker > 1.5 / 255).sum() > 50, "ambient occlusion darkens only %d pixels" % (darker > 1.5 / 255).sum())
display.AmbientOcclusionRays = 0
# A clip plane through the column: the half-space its normal points into is gone, volume and
# iso-surface alike.
PLANE = [0.55, 0.5, 0.5, 0.6, -0.8, 0.0]
display.ClipPlanes = PLANE
clipped = compare("Clip Planes %s" % PLANE, "clip", ["--spp", "3", "--iso", str(ISO), "--iso-color", color,
                                                    "--clip-plane", ",".join(map(str, PLANE))])
cut = (np.abs(clipped - iso).max(axis=-1) > 0.05).sum()
print("the clip plane changes %d pixels" % cut)
expect(cut > 200, "the clip plane changes only %d pixels" % cut)
display.ClipPlanes = []
display.IsoValues = []

# 4. Lighting.
display.Shade = 1
display.Shading = "analytic"
compare("Shade, Shading Analytic", "analytic", ["--spp", "3", "--shading", "analytic"])
display.Shading = "smooth"
compare("Shade, Shading Smooth", "smooth", ["--spp", "3", "--shading", "smooth"])
display.Shade = 0

# 4b. Path tracing: the same paths as the command line's (same pixels, passes and seed).
display.Integrator = "pathtrace"
display.Albedo = 0.6
display.SunIntensity = 3.0
display.SunDirection = [1.0, -0.5, -1.0]
display.Environment = [0.2, 0.25, 0.3]
traced = compare("Integrator Path Tracing", "pathtrace",
                 ["--spp", "3", "--integrator", "pathtrace", "--albedo", "0.6", "--sun", "1,-0.5,-1,3",
                  "--environment", "0.2,0.25,0.3"])
expect(np.abs(traced - spp3).mean() > 0.005, "path tracing did not change the picture")
display.SkyGradient = 1
display.Sky = [0.5, 0.7, 1.2]
display.Ground = [0.2, 0.1, 0.05]
sky = compare("Sky Gradient", "pathtrace_sky",
              ["--spp", "3", "--integrator", "pathtrace", "--albedo", "0.6", "--sun", "1,-0.5,-1,3",
               "--environment", "0.2,0.25,0.3", "--sky", "0.5,0.7,1.2", "--ground", "0.2,0.1,0.05"])
expect(np.abs(sky - traced).mean() > 0.001, "the sky gradient did not change the picture")
display.SkyGradient = 0
display.Albedo = 1.5  # refused: the setting stays 0.6
compare("Albedo 1.5 refused", "pathtrace_refused",
        ["--spp", "3", "--integrator", "pathtrace", "--albedo", "0.6", "--sun", "1,-0.5,-1,3",
         "--environment", "0.2,0.25,0.3"])
display.Albedo = 0.8
display.SunIntensity = 0.0
display.Integrator = "march"

# 5. The model was built once, whatever changed since; a new colour map and opacity function
# change the picture, not the model.
lut = GetColorTransferFunction("phi")
lut.RGBPoints = [RANGE[0], *COLORS[1], RANGE[1], *COLORS[0]]
GetOpacityTransferFunction("phi").Points = [RANGE[0], ALPHA[1], 0.5, 0.0, RANGE[1], ALPHA[0], 0.5, 0.0]
swapped = screenshot(view, work, "swapped.png")
expect(np.abs(swapped - spp3).mean() > 0.01, "a new transfer function did not change the picture")
lut.RGBPoints = [RANGE[0], *COLORS[0], RANGE[1], *COLORS[1]]
GetOpacityTransferFunction("phi").Points = [RANGE[0], ALPHA[0], 0.5, 0.0, RANGE[1], ALPHA[1], 0.5, 0.0]
builds = information(display, "ModelBuilds")
print("Model Builds after every change above: %d" % builds)
expect(builds == 1, "the model was built %d times (once expected)" % builds)

# 6. Drafts and refinement: a still render refines to 8 passes, a second one of the same view
# adds none; an interactive render after the camera moved draws a draft, the next still render
# refines the new view.
display.SamplesPerPixel = 8
start = time.perf_counter()
Render(view)
refine_seconds = time.perf_counter() - start
start = time.perf_counter()
Render(view)
again = time.perf_counter() - start
print("still render: %d passes in %.3f s; again, of the unchanged view: %.4f s"
      % (information(display, "RefinementPasses"), refine_seconds, again))
expect(again < 0.5 * refine_seconds, "a still render of an unchanged view took %.3f s (refining took %.3f s)"
       % (again, refine_seconds))
view.GetActiveCamera().Azimuth(10.0)
start = time.perf_counter()
view.InteractiveRender()
draft_seconds = time.perf_counter() - start
grab = vtkWindowToImageFilter()
grab.SetInput(view.GetRenderWindow())
grab.ReadFrontBufferOff()
grab.ShouldRerenderOff()
grab.Update()
draft = image_pixels(grab.GetOutput())
writer = vtkPNGWriter()
writer.SetInputConnection(grab.GetOutputPort())
writer.SetFileName(os.path.join(work, "draft.png"))
writer.Write()
draft_passes = information(display, "RefinementPasses")
still = screenshot(view, work, "still.png")
passes = information(display, "RefinementPasses")
d = np.abs(draft - still)
print("draft (interactive render, %.3f s, %d passes): against the still image of the same view mean %.4f, max %.3f"
      % (draft_seconds, draft_passes, d.mean(), d.max()))
print("the still render after the draft holds %d passes" % passes)
expect(draft_passes == 0, "an interactive render drew %d passes (a draft expected)" % draft_passes)
expect(draft.shape == still.shape and 0 < d.mean() < 0.03,
       "the draft differs from the still image by %.4f on average (expected 0 < d < 0.03)" % d.mean())
expect(passes == 8, "the still render after a draft holds %d passes (8 expected)" % passes)

# 7. Devices and invalid settings.
display.Device = "cpu"
Render(view)
print("Device cpu: %s" % information(display, "DeviceInUse"))
expect(information(display, "DeviceInUse") == "cpu", "Device cpu renders on %s" % information(display, "DeviceInUse"))
display.Device = "auto"
Render(view)
print("Device auto: %s" % information(display, "DeviceInUse"))
display.SamplingRate = -1.0  # refused with an error: the rate stays 1
display.SamplesPerPixel = 0  # refused: stays 8
refused = screenshot(view, work, "refused.png")
expect(np.abs(refused - still).max() == 0, "invalid settings changed the image")
expect(information(display, "ModelBuilds") == 1, "the model was rebuilt")

if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("passed")
