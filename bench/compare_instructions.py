#!/usr/bin/python3
"""Two or more builds (or models) of exabricks side by side by instructions executed per frame:
each renders the same view once under valgrind's callgrind, counting only inside the frame
(renderPass), and the counts, samples and ratios to the first are printed. Instruction counts are
exact and repeatable, so they separate changes of a few percent on a machine whose timings vary
more than that; they are not times (cache misses and mispredicted branches cost no instructions),
so confirm a change with compare_builds.py. A frame at 256^2 takes about half a minute per run.

Each variant is BINARY or BINARY:MODEL (a model of its own; otherwise INPUT):

    /usr/bin/python3 bench/compare_instructions.py drop.model before/exabricks build/exabricks
    /usr/bin/python3 bench/compare_instructions.py drop.model build/exabricks build/exabricks:other.model
"""
import argparse
import os
import re
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor

ap = argparse.ArgumentParser()
ap.add_argument("input")
ap.add_argument("variants", nargs="+")
ap.add_argument("--size", default="256x256")
ap.add_argument("--extra", default="", help="more render options, space separated")
ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="runs at once")
a = ap.parse_args()

scratch = tempfile.TemporaryDirectory()


def run(i_variant):
    i, variant = i_variant
    binary, _, model = variant.partition(":")
    out = f"{scratch.name}/{i}.callgrind"
    cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", "--toggle-collect=*renderPass*",
           binary, "--threads", "1", "render", model or a.input, "--size", a.size, "--frames", "1", "--stats",
           "-o", f"{scratch.name}/{i}.png"] + a.extra.split()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"{variant}: exit {p.returncode}\n{p.stderr[-2000:]}")
    collected = re.search(r"Collected : (\d+)", p.stderr)
    samples = re.search(r"^samples\s+(\d+)", p.stdout + p.stderr, re.M)
    if not collected or not samples:
        raise SystemExit(f"{variant}: no instruction count or sample count in its output")
    # --stats renders a warm-up frame and the timed one: half the count is one frame.
    return int(collected.group(1)) // 2, int(samples.group(1))


with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
    results = list(pool.map(run, enumerate(a.variants)))

print(f"{a.input} at {a.size}, one thread, instructions in one frame (callgrind)")
print(f"{'variant':<48} {'instructions':>14} {'samples':>10} {'per sample':>10} {'ratio':>7}")
base = results[0][0]
for v, (ins, samples) in zip(a.variants, results):
    print(f"{v[-48:]:<48} {ins:>14,} {samples:>10,} {ins / max(samples, 1):>10.1f} {ins / base:>7.3f}")
