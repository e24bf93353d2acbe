#!/usr/bin/python3
"""Renders one AMReX plotfile with exabricks and with ParaView (pvbatch, AMR volume
representation) at the same resolution, camera, value range, colour map and opacity ramp;
prints the times and their ratios and writes both images side by side into one PNG. Not a
test. Run with Debian's Python; it starts ParaView's pvbatch under a virtual X server with
Mesa's llvmpipe software OpenGL (packages paraview, python3-paraview, xvfb):

  /usr/bin/python3 bench/peers/compare_paraview.py build/exabricks /work/shared/data/amrex/advection_3d/plt_drop \\
      --size 1024 --out /tmp/peers-pv

The same file is the script pvbatch runs (given one JSON file of settings). See
bench/peers/README.md for what each renderer does differently.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_common import (add_common_arguments, agreement, alike, camera, dataset_info,  # noqa: E402
                         describe_agreement, require_comparable, run_exabricks)


# ---------------------------------------------------------------------------------------------
# The ParaView side: runs inside pvbatch.

def paraview_worker(cfg_path):
    cfg = json.load(open(cfg_path))
    from paraview.simple import (AMReXBoxLibGridReader, CreateView, Show, Render, SaveScreenshot,
                                 GetColorTransferFunction, GetOpacityTransferFunction)
    import paraview
    result = {"paraview_version": paraview.__version__ if hasattr(paraview, "__version__") else None}

    # Load: the reader's metadata, then every level of the one field, as a vtkOverlappingAMR.
    t0 = time.perf_counter()
    reader = AMReXBoxLibGridReader(FileNames=[cfg["plotfile"]])
    reader.UpdatePipelineInformation()
    levels = int(reader.GetPropertyValue("NumLevels"))
    reader.Level = levels  # the finest level to read (0 is the coarsest)
    reader.CellArrayStatus = [cfg["field"]]
    reader.UpdatePipeline()
    result["load_seconds"] = time.perf_counter() - t0
    info = reader.GetDataInformation()
    result["reader"] = {"levels_read": levels + 1, "blocks": int(reader.GetPropertyValue("NumBlocks")),
                        "cells": int(info.GetNumberOfCells()), "type": info.GetDataSetTypeAsString()}

    size = cfg["size"]
    view = CreateView("RenderView")
    view.ViewSize = [size, size]
    view.OrientationAxesVisibility = 0
    if hasattr(view, "UseColorPaletteForBackground"):
        view.UseColorPaletteForBackground = 0
    view.Background = [0.0, 0.0, 0.0]
    view.CameraPosition = cfg["position"]
    view.CameraFocalPoint = cfg["look_at"]
    view.CameraViewUp = cfg["up"]
    view.CameraViewAngle = cfg["fov"]  # VTK's view angle is the vertical one, as exabricks'
    view.CameraParallelProjection = 0

    rep = Show(reader, view)
    rep.SetRepresentationType("Volume")
    rep.ColorArrayName = ["CELLS", cfg["field"]]
    lo, hi = cfg["range"]
    lut = GetColorTransferFunction(cfg["field"])
    lut.ApplyPreset("Viridis (matplotlib)", True)
    lut.RescaleTransferFunction(lo, hi)
    lut.AutomaticRescaleRangeMode = "Never"
    pwf = GetOpacityTransferFunction(cfg["field"])
    # exabricks' ramp: opacity 0 at the lowest value to opacity_scale per finest cell width at
    # the highest; VTK corrects the opacity for its step from ScalarOpacityUnitDistance.
    pwf.Points = [lo, 0.0, 0.5, 0.0, hi, cfg["opacity_scale"], 0.5, 0.0]
    rep.LookupTable = lut
    rep.ScalarOpacityFunction = pwf
    rep.ScalarOpacityUnitDistance = cfg["finest_width"]
    if cfg.get("samples"):
        rep.NumberOfSamples = cfg["samples"]
    result["representation"] = {p: str(rep.GetPropertyValue(p)) for p in (
        "VolumeRenderingMode", "ResamplingMode", "NumberOfSamples", "Shade", "ScalarOpacityUnitDistance")}

    def timed_render():
        t = time.perf_counter()
        Render(view)
        return time.perf_counter() - t

    renders = {}
    for shade in (0, 1):
        rep.Shade = shade
        first = timed_render()  # warm-up: for the very first, the resampling to a uniform grid
        times = [timed_render() for _ in range(cfg["frames"])]
        renders["shaded" if shade else "unshaded"] = {"first": first, "times": times,
                                                       "median": statistics.median(times)}
        png = os.path.join(cfg["out"], "paraview-shaded.png" if shade else "paraview.png")
        SaveScreenshot(png, view, ImageResolution=[size, size], OverrideColorPalette="BlackBackground")
    result["renders"] = renders

    # What VTK ended up using, where the objects can be reached.
    try:
        window = view.GetRenderWindow()
        caps = window.ReportCapabilities()
        result["opengl"] = [l.strip() for l in caps.splitlines() if "renderer" in l.lower() or "version" in l.lower()][:3]
    except Exception as e:  # noqa: BLE001
        result["opengl"] = [f"unavailable: {e}"]
    json.dump(result, open(os.path.join(cfg["out"], "paraview.json"), "w"), indent=1)


# ---------------------------------------------------------------------------------------------
# The driver: Debian's Python.

def parse_arguments():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common_arguments(p)
    p.add_argument("--frames", type=int, default=3, help="frames timed (median), after a warm-up")
    p.add_argument("--samples", default="",
                   help="ParaView's resampling grid NXxNYxNZ (default: the representation's own default)")
    p.add_argument("--pvbatch", default="pvbatch")
    p.add_argument("--out", default="peer-comparison-paraview")
    return p.parse_args()


def describe(a):
    """The dataset as `exabricks info` describes it, and the view both renderers share: value range,
    finest cell width, exabricks' default opacity and camera."""
    info = dataset_info(a.exabricks, a.plotfile)
    require_comparable(info, a.field, a.plotfile)
    lower, upper = info["bounds"]["world"]["lower"], info["bounds"]["world"]["upper"]
    fr = [f for f in info["fields"] if f["name"] == a.field][0]["range"]
    value_range = (fr["min"], fr["max"])
    finest_cells = max((u - l) for l, u in zip(info["bounds"]["lattice"]["lower"], info["bounds"]["lattice"]["upper"]))
    finest_width = max(u - l for l, u in zip(lower, upper)) / finest_cells
    opacity_scale = min(1.0, 8.0 / finest_cells)  # exabricks' default, as in compare_yt.py
    pos, look, up, _ = camera(lower, upper, a.azimuth, a.elevation, a.fov)
    return info, {"range": value_range, "finest_width": finest_width, "opacity_scale": opacity_scale,
                  "position": pos, "look_at": look, "up": up}


def render_paraview(a, view):
    """Runs pvbatch on this file under a virtual X server; returns the results it wrote and the
    process's wall time."""
    cfg = {"plotfile": os.path.abspath(a.plotfile), "field": a.field, "size": a.size, "position": view["position"],
           "look_at": view["look_at"], "up": view["up"], "fov": a.fov, "range": list(view["range"]),
           "opacity_scale": view["opacity_scale"], "finest_width": view["finest_width"], "frames": a.frames,
           "out": os.path.abspath(a.out), "samples": [int(v) for v in a.samples.split("x")] if a.samples else None}
    cfg_path = os.path.join(a.out, "paraview-settings.json")
    json.dump(cfg, open(cfg_path, "w"), indent=1)
    env = dict(os.environ, GALLIUM_DRIVER="llvmpipe", LP_NUM_THREADS="2")
    side = max(1280, a.size + 256)
    cmd = ["xvfb-run", "-a", "-s", f"-screen 0 {side}x{side}x24", a.pvbatch, os.path.abspath(__file__),
           "--paraview-worker", cfg_path]
    pv_json = os.path.join(a.out, "paraview.json")
    if os.path.exists(pv_json):
        os.remove(pv_json)
    t0 = time.perf_counter()
    # pvbatch may exit non-zero while tearing down its X window (GLXBadContext) after it has
    # written its results; what counts is that the results file exists.
    rc = subprocess.run(cmd, env=env).returncode
    pv_wall = time.perf_counter() - t0
    if not os.path.exists(pv_json):
        sys.exit(f"pvbatch failed (exit status {rc}) before writing {pv_json}")
    pv = json.load(open(pv_json))
    pv["pvbatch_exit_status"] = rc
    return pv, pv_wall


def report(a, info, view, ex_wall, ex, ex_flat, pv, pv_wall, agree):
    """Prints the times and their ratios, beside the agreement of the pictures; returns both."""
    ex_frame, ex_flat_frame = ex["frame_seconds"], ex_flat["frame_seconds"]
    pr = pv["renders"]
    rows = [
        ("exabricks, full quality (shaded, early termination), frame", ex_frame),
        ("exabricks, unshaded, early termination off, frame", ex_flat_frame),
        ("exabricks, load + build (plotfile read, bricks, regions)", ex["load_seconds"]),
        ("exabricks, end to end (one process: load, build, one frame, PNG)", ex_wall),
        ("ParaView, load (reader: all levels, one field)", pv["load_seconds"]),
        ("ParaView, first render (resampling + render), unshaded", pr["unshaded"]["first"]),
        ("ParaView, render, unshaded (median)", pr["unshaded"]["median"]),
        ("ParaView, first render after switching shading on", pr["shaded"]["first"]),
        ("ParaView, render, shaded (median)", pr["shaded"]["median"]),
        ("ParaView, whole pvbatch process (X server, start, load, all renders, PNGs)", pv_wall),
    ]
    value_range = view["range"]
    print(f"dataset {a.plotfile} ({info['cells']} leaf cells), field {a.field}, {a.size}x{a.size}, "
          f"value range [{value_range[0]:.6g}, {value_range[1]:.6g}]")
    print("ParaView:", json.dumps({k: pv[k] for k in ("reader", "representation", "opengl")}))
    for name, t in rows:
        print(f"  {name:76s} {t:8.3f} s")
    ratios = {
        "ParaView shaded render / exabricks full-quality frame": pr["shaded"]["median"] / ex_frame,
        "ParaView unshaded render / exabricks unshaded frame (no early termination)":
            pr["unshaded"]["median"] / ex_flat_frame,
        "ParaView first render / exabricks full-quality frame": pr["unshaded"]["first"] / ex_frame,
        "ParaView load / exabricks load + build": pv["load_seconds"] / ex["load_seconds"],
        "ParaView load + first render / exabricks end to end":
            (pv["load_seconds"] + pr["unshaded"]["first"]) / ex_wall,
    }
    print("pictures: exabricks unshaded against ParaView unshaded: " + describe_agreement(agree["unshaded"]))
    print("          exabricks full quality against ParaView shaded: " + describe_agreement(agree["shaded"]))
    valid = alike(agree["unshaded"]) and alike(agree["shaded"])
    print("ratios (ParaView / exabricks)" + ("" if valid else ", NOT VALID: the pictures differ") + ":")
    for name, r in ratios.items():
        print(f"  {name:76s} {r:8.2f}x" + ("" if valid else "  (not valid)"))
    return rows, ratios


def save_side_by_side(a, info, ex_png, ex_frame, pv, rows, ratios, agree):
    """One PNG: exabricks (full quality) | ParaView (shaded); and the figures in results.json."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ex_img = plt.imread(ex_png)[..., :3]
    pv_img = plt.imread(os.path.join(a.out, "paraview-shaded.png"))[..., :3]
    fig, axes = plt.subplots(1, 2, figsize=(12, 6.6), dpi=100)
    samples = pv["representation"]["NumberOfSamples"]
    for ax, img, title in ((axes[0], ex_img, f"exabricks: frame {ex_frame:.2f} s (basis, shaded, adaptive)"),
                           (axes[1], pv_img, f"ParaView {pv.get('paraview_version') or ''}: render "
                                             f"{pv['renders']['shaded']['median']:.2f} s (resampled {samples}, shaded)")):
        ax.imshow(img)
        ax.set_title(title, fontsize=10)
        ax.axis("off")
    fig.suptitle(f"{os.path.basename(os.path.normpath(a.plotfile))}: {info['cells']:,} leaf cells, "
                 f"{a.size}x{a.size}, same camera, range and colour map", fontsize=12)
    fig.tight_layout()
    out_side = os.path.join(a.out, "side-by-side.png")
    fig.savefig(out_side)
    json.dump({"rows": dict(rows), "ratios": ratios, "paraview": pv, "agreement": agree,
               "valid": alike(agree["unshaded"]) and alike(agree["shaded"])}, open(os.path.join(a.out, "results.json"), "w"),
              indent=1)
    print(f"wrote {out_side}")


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--paraview-worker":
        return paraview_worker(sys.argv[2])
    a = parse_arguments()
    os.makedirs(a.out, exist_ok=True)
    print("uptime:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    info, view = describe(a)
    pos, look, up, value_range = view["position"], view["look_at"], view["up"], view["range"]

    # --- exabricks ---
    ex_png = os.path.join(a.out, "exabricks.png")
    ex_wall, ex = run_exabricks(a.exabricks, a.plotfile, a.field, a.size, pos, look, up, a.fov, value_range,
                                view["opacity_scale"], ex_png, [], a.frames)
    _, ex_flat = run_exabricks(a.exabricks, a.plotfile, a.field, a.size, pos, look, up, a.fov, value_range,
                               view["opacity_scale"], os.path.join(a.out, "exabricks-unshaded.png"),
                               ["--no-early-termination"], a.frames, shading="none")

    # --- ParaView ---
    pv, pv_wall = render_paraview(a, view)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    agree = {"unshaded": agreement(plt.imread(os.path.join(a.out, "exabricks-unshaded.png"))[..., :3],
                                   plt.imread(os.path.join(a.out, "paraview.png"))[..., :3]),
             "shaded": agreement(plt.imread(ex_png)[..., :3],
                                 plt.imread(os.path.join(a.out, "paraview-shaded.png"))[..., :3])}
    rows, ratios = report(a, info, view, ex_wall, ex, ex_flat, pv, pv_wall, agree)
    save_side_by_side(a, info, ex_png, ex["frame_seconds"], pv, rows, ratios, agree)
    if not (alike(agree["unshaded"]) and alike(agree["shaded"])):
        return "the two pictures differ: the ratios compare unlike work"

if __name__ == "__main__":
    sys.exit(main())
