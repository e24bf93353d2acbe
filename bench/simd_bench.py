#!/usr/bin/python3
"""Sampling variants side by side: the scalar reference loop, and SIMD batches with each
instruction set the CPU has, with and without lazy gradients. Every round runs each variant once
(in one process per variant: --stats times --frames frames after a warm-up); the medians over the
rounds and the ratios to the scalar loop are printed. The two best instruction sets also run with
one batch per region segment (--no-join-segments) instead of batches filled from consecutive
segments.

    /usr/bin/python3 bench/simd_bench.py build/exabricks drop.model --size 1024x1024 --rounds 3
"""
import argparse
import json
import statistics
import subprocess

ap = argparse.ArgumentParser()
ap.add_argument("exabricks")
ap.add_argument("input")
ap.add_argument("--size", default="1024x1024")
ap.add_argument("--rounds", type=int, default=3)
ap.add_argument("--frames", type=int, default=3)
ap.add_argument("--extra", default="", help="more render options, space separated")
a = ap.parse_args()

targets = subprocess.run([a.exabricks, "--simd", "?", "render", "-o", "/dev/null"], capture_output=True,
                         text=True).stderr
targets = targets[targets.index("(") + 1: targets.rindex(")")].split(", ")
variants = {"scalar loop": ["--scalar"]}
for t in targets:
    variants[f"batches {t}"] = ["--simd", t]
variants[f"batches {targets[0]}, eager gradients"] = ["--simd", targets[0], "--no-lazy-gradients"]
for t in targets[:2]:
    variants[f"batches {t}, one per segment"] = ["--simd", t, "--no-join-segments"]
times = {k: [] for k in variants}
samples = {}
for r in range(a.rounds):
    for name, flags in variants.items():
        cmd = [a.exabricks, "-q"] + flags[:0] + ([flags[0], flags[1]] if flags[0] == "--simd" else []) + \
              ["render", a.input, "--size", a.size, "-o", "/dev/null", "--json", "--stats", "--frames",
               str(a.frames)] + [f for f in flags if f in ("--scalar", "--no-lazy-gradients", "--no-join-segments")] + a.extra.split()
        j = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
        times[name].append(j["frame_seconds"])
        samples[name] = j["samples"]
base = statistics.median(times["scalar loop"])
print(f"{a.input} at {a.size}, median of {a.rounds} rounds (each the median of {a.frames} frames)")
print(f"{'variant':36} {'frame s':>8} {'M samples/s':>12} {'speed-up':>9}")
for name in variants:
    t = statistics.median(times[name])
    print(f"{name:36} {t:8.3f} {samples[name] / t / 1e6:12.1f} {base / t:9.2f}")
