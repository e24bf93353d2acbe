#!/usr/bin/env python3
"""The default path-traced picture against the ray-marched one, side by side in one run: for each
dataset, the default ray-marched frame, the default path-traced frame (denoised, passes to the
noise target of the denoised picture, tile by tile) and, unless --quick, the same target without
the denoiser. The noise of each path-traced picture is the RMS difference of two seeds' 8-bit
images / sqrt(2); with --reference N, the bias of the default picture is its low frequencies (a
5x5 box) against an N-sample undenoised render (mean and 99th percentile of the absolute
difference). Prints times, samples, noise and ratios. Not a test.

usage: bench/noise_target.py EXABRICKS [--data DIR] [--size 512] [--target 2] [--quick]
                             [--reference 2048] [--device cuda] [--work DIR]

--data is $EXABRICKS_DATA (default /work/shared/data); a generated cosmology-like step (1M cells)
is always measured; shared samples that are absent are skipped with a note. Needs numpy and PIL.
"""
import argparse
import os
import sys

import numpy as np

from pathtrace_bench import SUN, dataset, pixels, render

# name, input relative to --data (None: generated), options of both integrators, path-tracing options.
CASES = [
    ("plt_drop", "amrex/advection_3d/plt_drop", [], SUN),
    ("pelelm temp", "amrex/pelelm_3lev_3d/example_plt_3d", ["--field", "temp"], SUN),
    ("plt_eb_3d", "amrex/pele_eb_3d/plt_eb_3d", [], SUN),
    ("cosmic 1M", None, [], SUN),
]


def noise(a, b):
    return float(np.sqrt(((pixels(a) - pixels(b)) ** 2).mean()) / np.sqrt(2.0))


def box5(a):
    from numpy.lib.stride_tricks import sliding_window_view
    return sliding_window_view(a, (5, 5), axis=(0, 1)).mean(axis=(-1, -2))


def bias(image, reference):
    d = np.abs(box5(pixels(image)) - box5(pixels(reference)))
    return float(d.mean()), float(np.percentile(d, 99))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("exe")
    p.add_argument("--data", default=os.environ.get("EXABRICKS_DATA", "/work/shared/data"))
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--target", type=float, default=2.0)
    p.add_argument("--quick", action="store_true", help="skip the undenoised target")
    p.add_argument("--reference", type=int, default=0, help="samples of the undenoised reference (0: none)")
    p.add_argument("--device", help="render --device of every frame (default: the command's own)")
    p.add_argument("--work", default="/tmp/noise-target-bench")
    a = p.parse_args()
    device = ["--device", a.device] if a.device else []
    os.makedirs(a.work, exist_ok=True)
    size = ["--size", "%dx%d" % (a.size, a.size)]
    print("%-12s %8s | %8s %8s %6s %7s | %8s %8s %6s %7s | %s" % (
        "dataset", "march s", "denoised", "mean spp", "noise", "x march", "undenois", "mean spp", "noise", "x march",
        "bias mean / p99"))
    for name, rel, common, pt in CASES:
        path = dataset(a.exe, name, rel, a.data, a.work)
        if path is None:
            continue
        base = [path] + size + common + device
        w = lambda tag: os.path.join(a.work, "%s-%s.png" % (name.replace(" ", "_"), tag))
        march = render(a.exe, base, w("march"))
        m = march["frame_seconds"]
        pathtraced = base + ["--integrator", "pathtrace"] + pt
        target = ["--noise-target", str(a.target), "--spp", "1024"]
        d1 = render(a.exe, pathtraced + target + ["--seed", "1"], w("d1"))
        render(a.exe, pathtraced + target + ["--seed", "2"], w("d2"))
        row = "%-12s %8.2f | %8.2f %8.1f %6.2f %7.1f |" % (
            name, m, d1["frame_seconds"], d1["mean_samples_per_pixel"], noise(w("d1"), w("d2")), d1["frame_seconds"] / m)
        if a.quick:
            row += " %8s %8s %6s %7s |" % ("-", "-", "-", "-")
        else:
            u1 = render(a.exe, pathtraced + target + ["--denoise", "off", "--seed", "1"], w("u1"))
            render(a.exe, pathtraced + target + ["--denoise", "off", "--seed", "2"], w("u2"))
            row += " %8.2f %8.1f %6.2f %7.1f |" % (u1["frame_seconds"], u1["mean_samples_per_pixel"],
                                                  noise(w("u1"), w("u2")), u1["frame_seconds"] / m)
        if a.reference > 0:
            render(a.exe, pathtraced + ["--spp", str(a.reference), "--denoise", "off", "--seed", "7"], w("ref"))
            row += " %.2f / %.2f" % bias(w("d1"), w("ref"))
        print(row)
        sys.stdout.flush()


if __name__ == "__main__":
    main()
