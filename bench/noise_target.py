#!/usr/bin/env python3
"""Path tracing to a noise target against a fixed sample count, side by side in one run: for each
dataset, the default ray-marched frame, the default path-traced frame (passes to the noise
target, tile by tile) and a path-traced frame that spends the same mean samples per pixel on every
pixel. The noise of each path-traced picture is measured as the RMS difference of two seeds'
8-bit images / sqrt(2). Prints times, samples, noise and ratios. Not a test.

usage: bench/noise_target.py EXABRICKS [--data DIR] [--size 512] [--target 2] [--work DIR]

--data is $EXABRICKS_DATA (default /work/shared/data); a generated cosmology-like step (1M cells)
is always measured; shared samples that are absent are skipped with a note. Needs numpy and PIL.
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np
from PIL import Image

# name, input relative to --data (None: generated), options of both integrators, path-tracing options.
CASES = [
    ("plt_drop", "amrex/advection_3d/plt_drop", [], ["--sun", "-0.75,0.5,-0.7,5", "--bounces", "4"]),
    ("pelelm temp", "amrex/pelelm_3lev_3d/example_plt_3d", ["--field", "temp"], ["--sun", "-0.75,0.5,-0.7,5", "--bounces", "4"]),
    ("cosmic 1M", None, [], ["--sun", "-0.75,0.5,-0.7,5", "--bounces", "4"]),
]


def render(exe, args, out):
    run = subprocess.run([exe, "render"] + args + ["-o", out, "--json"], capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit("failed: %s\n%s" % (" ".join(args), run.stderr))
    return json.loads(run.stdout)


def pixels(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(float)


def noise(a, b):
    return float(np.sqrt(((pixels(a) - pixels(b)) ** 2).mean()) / np.sqrt(2.0))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("exe")
    p.add_argument("--data", default=os.environ.get("EXABRICKS_DATA", "/work/shared/data"))
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--target", type=float, default=2.0)
    p.add_argument("--work", default="/tmp/noise-target-bench")
    a = p.parse_args()
    os.makedirs(a.work, exist_ok=True)
    size = ["--size", "%dx%d" % (a.size, a.size)]
    print("%-12s %9s %9s %9s %8s %8s %9s %8s %8s" % ("dataset", "march s", "target s", "mean spp", "noise",
                                                      "x march", "fixed s", "noise", "x march"))
    for name, rel, common, pt in CASES:
        if rel is None:
            path = os.path.join(a.work, "cosmic.cells")
            if not os.path.exists(path):
                subprocess.run([a.exe, "-q", "generate", "-s", "cosmic", "-n", "1000000", "-o", path], check=True)
        else:
            path = os.path.join(a.data, rel)
            if not os.path.exists(path):
                print("%-12s skipped: %s is absent" % (name, path))
                continue
        base = [path] + size + common
        w = lambda tag: os.path.join(a.work, "%s-%s.png" % (name.replace(" ", "_"), tag))
        march = render(a.exe, base, w("march"))
        pathtraced = base + ["--integrator", "pathtrace"] + pt
        t1 = render(a.exe, pathtraced + ["--noise-target", str(a.target), "--spp", "1024", "--seed", "1"], w("t1"))
        render(a.exe, pathtraced + ["--noise-target", str(a.target), "--spp", "1024", "--seed", "2"], w("t2"))
        spp = max(1, int(round(t1["mean_samples_per_pixel"])))
        f1 = render(a.exe, pathtraced + ["--spp", str(spp), "--seed", "1"], w("f1"))
        render(a.exe, pathtraced + ["--spp", str(spp), "--seed", "2"], w("f2"))
        m = march["frame_seconds"]
        print("%-12s %9.2f %9.2f %9.1f %8.2f %8.1f %9.2f %8.2f %8.1f" % (
            name, m, t1["frame_seconds"], t1["mean_samples_per_pixel"], noise(w("t1"), w("t2")),
            t1["frame_seconds"] / m, f1["frame_seconds"], noise(w("f1"), w("f2")), f1["frame_seconds"] / m))
        sys.stdout.flush()


if __name__ == "__main__":
    main()
