#!/usr/bin/env python3
"""The path tracer's majorant grid, side by side in one run: for each dataset, the ray-marched
frame and the path-traced frame with and without the grid (`--no-majorant-grid`: the regions'
majorants alone) at equal samples per pixel (undenoised), and, unless --no-target, the default
path-traced frame (denoised, to the noise target) with and without it. Prints the samples taken
(the marcher's reconstructions, the path tracer's tentative collisions), their ratios to the
marcher's, times (at equal samples the median of --frames after a warm-up; to the target one
frame), and how far the two path-traced pictures differ (RMS of 8-bit sRGB steps,
against the RMS difference of two seeds without the grid: equal means only noise differs).
Not a test.

usage: bench/majorants.py EXABRICKS [--data DIR] [--size 256] [--spp 8] [--frames 3]
                          [--target-size 1024] [--no-target] [--device cuda] [--work DIR]

--data is $EXABRICKS_DATA (default /work/shared/data); a generated cosmology-like step (1M cells)
is always measured; shared samples that are absent are skipped with a note. Needs numpy and PIL.
"""
import argparse
import os

import numpy as np

from pathtrace_bench import SUN, dataset, pixels, render

# name, input relative to --data (None: generated), options of both integrators.
CASES = [
    ("plt_drop", "amrex/advection_3d/plt_drop", []),
    ("pelelm temp", "amrex/pelelm_3lev_3d/example_plt_3d", ["--field", "temp"]),
    ("plt_eb_3d", "amrex/pele_eb_3d/plt_eb_3d", []),
    ("cosmic 1M", None, []),
]


def rms(a, b):
    return float(np.sqrt(((pixels(a) - pixels(b)) ** 2).mean()))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("exe")
    p.add_argument("--data", default=os.environ.get("EXABRICKS_DATA", "/work/shared/data"))
    p.add_argument("--size", type=int, default=256)
    p.add_argument("--spp", type=int, default=8)
    p.add_argument("--frames", type=int, default=3, help="timed frames at equal samples (median)")
    p.add_argument("--target-size", type=int, default=1024)
    p.add_argument("--no-target", action="store_true", help="skip the frames to the noise target")
    p.add_argument("--device", help="render --device of every frame (default: the command's own)")
    p.add_argument("--work", default="/tmp/majorant-bench")
    a = p.parse_args()
    device = ["--device", a.device] if a.device else []
    os.makedirs(a.work, exist_ok=True)
    print("At %d², %d samples per pixel, undenoised (samples: reconstructions or tentative collisions):" %
          (a.size, a.spp))
    print("%-12s %12s | %12s %7s %8s | %12s %7s %8s | %9s %8s | %s" % (
        "dataset", "march smp", "grid smp", "x march", "s", "regions smp", "x march", "s", "grid gain",
        "build s", "rms grid/regions, seeds"))
    rows = []
    for name, rel, common in CASES:
        path = dataset(a.exe, name, rel, a.data, a.work)
        if path is None:
            continue
        rows.append((name, path, common))
        size = ["--size", "%dx%d" % (a.size, a.size)]
        w = lambda tag: os.path.join(a.work, "%s-%s.png" % (name.replace(" ", "_"), tag))
        timed = ["--stats", "--frames", str(a.frames)]
        march = render(a.exe, [path] + common + device + size + timed + ["--spp", str(a.spp)], w("march"))
        pt = [path] + common + device + size + timed + SUN + ["--integrator", "pathtrace", "--spp", str(a.spp),
                                                              "--denoise", "off"]
        grid = render(a.exe, pt, w("grid"))
        regions = render(a.exe, pt + ["--no-majorant-grid"], w("regions"))
        render(a.exe, pt + ["--no-majorant-grid", "--seed", "1"], w("regions-seed1"))
        print("%-12s %12d | %12d %7.2f %8.3f | %12d %7.2f %8.3f | %9.2f %8.3f | %.2f, %.2f" % (
            name, march["samples"], grid["samples"], grid["samples"] / march["samples"], grid["frame_seconds"],
            regions["samples"], regions["samples"] / march["samples"], regions["frame_seconds"],
            regions["samples"] / grid["samples"], grid["transfer_function_update_seconds"],
            rms(w("grid"), w("regions")), rms(w("regions"), w("regions-seed1"))), flush=True)
    if a.no_target:
        return
    print("\nAt %d², the default path-traced frame (denoised, to the noise target):" % a.target_size)
    print("%-12s %8s | %8s %8s %8s | %8s %8s %8s | %s" % ("dataset", "march s", "grid s", "mean spp", "x march",
                                                          "regions", "mean spp", "x march", "regions / grid"))
    for name, path, common in rows:
        size = ["--size", "%dx%d" % (a.target_size, a.target_size)]
        w = lambda tag: os.path.join(a.work, "%s-target-%s.png" % (name.replace(" ", "_"), tag))
        march = render(a.exe, [path] + common + device + size, w("march"))
        pt = [path] + common + device + size + SUN + ["--integrator", "pathtrace"]
        grid = render(a.exe, pt, w("grid"))
        regions = render(a.exe, pt + ["--no-majorant-grid"], w("regions"))
        m, g, r = march["frame_seconds"], grid["frame_seconds"], regions["frame_seconds"]
        print("%-12s %8.2f | %8.2f %8.1f %8.1f | %8.2f %8.1f %8.1f | %.2f" % (
            name, m, g, grid["mean_samples_per_pixel"], g / m, r, regions["mean_samples_per_pixel"], r / m, r / g),
            flush=True)


if __name__ == "__main__":
    main()
