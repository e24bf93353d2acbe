#!/usr/bin/env python3
"""Renders one dataset with several renderer variants in one run and prints frame times,
samples, regions and the ratios between variants. Not a test.

usage: render_variants.py EXABRICKS INPUT [--size 512x512] [--frames 3] [--field NAME]
"""
import argparse
import json
import subprocess
import sys
import tempfile

VARIANTS = [
    # name, extra options
    ("kd traversal", ["--traversal", "kd"]),
    ("embree traversal", ["--traversal", "embree"]),
    ("hide 80%: skipping on", ["--traversal", "kd", "--opacity", "0,0,0.8,0,0.9,0.5,1,1"]),
    ("hide 80%: skipping off", ["--traversal", "kd", "--opacity", "0,0,0.8,0,0.9,0.5,1,1", "--no-skip"]),
    ("adaptive sampling", ["--traversal", "kd", "--sampling", "adaptive"]),
    ("fixed-step sampling", ["--traversal", "kd", "--sampling", "fixed"]),
]


def run(exe, data, size, frames, field, extra):
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [exe, "-q", "render"] + ([data] if data else []) + [
            "-o", f"{tmp}/out.png", "--size", size, "--stats", "--json", "--frames", str(frames),
            "--no-early-termination"] + (["-f", field] if field else []) + extra
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        return json.loads(out)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("exabricks")
    p.add_argument("input", nargs="?", default="")
    p.add_argument("--size", default="512x512")
    p.add_argument("--frames", type=int, default=3)
    p.add_argument("--field", default="")
    a = p.parse_args()
    results = {}
    print(f"{'variant':28s} {'frame s':>9s} {'samples':>12s} {'regions':>11s} {'Msamples/s':>11s} {'visible':>9s}")
    for name, extra in VARIANTS:
        r = run(a.exabricks, a.input, a.size, a.frames, a.field, extra)
        results[name] = r
        print(f"{name:28s} {r['frame_seconds']:9.3f} {r['samples']:12d} {r['regions_visited']:11d} "
              f"{r['samples_per_second'] / 1e6:11.2f} {r['visible_regions']:9d}")
    t = lambda n: results[n]["frame_seconds"]
    s = lambda n: results[n]["samples"]
    print()
    print(f"embree / kd frame time:              {t('embree traversal') / t('kd traversal'):.2f}")
    print(f"space skipping speed-up (hide 80%):  {t('hide 80%: skipping off') / t('hide 80%: skipping on'):.2f}x")
    print(f"fixed-step / adaptive samples:       {s('fixed-step sampling') / s('adaptive sampling'):.2f}x")
    print(f"fixed-step / adaptive frame time:    {t('fixed-step sampling') / t('adaptive sampling'):.2f}x")
    json.dump(results, sys.stderr, indent=1)


if __name__ == "__main__":
    main()
