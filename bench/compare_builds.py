#!/usr/bin/python3
"""Two or more builds of exabricks side by side on one input: every round renders once with each
binary in turn (--stats, median of --frames frames after a warm-up), so that all of them see the
same machine load; the medians and minima over the rounds and the ratios to the first binary are
printed. With --build, INPUT is a dataset that each binary first builds into its own model (so a
change of the brick or region build is measured with the models it makes), with --build-options.

    /usr/bin/python3 bench/compare_builds.py drop.model before/exabricks build/exabricks --rounds 5
    /usr/bin/python3 bench/compare_builds.py --build plt_drop before/exabricks build/exabricks
"""
import argparse
import json
import statistics
import subprocess
import tempfile

ap = argparse.ArgumentParser()
ap.add_argument("input")
ap.add_argument("binaries", nargs="+")
ap.add_argument("--size", default="1024x1024")
ap.add_argument("--rounds", type=int, default=5)
ap.add_argument("--frames", type=int, default=3)
ap.add_argument("--threads", type=int, default=0, help="worker threads (0: every core)")
ap.add_argument("--extra", default="", help="more render options, space separated")
ap.add_argument("--build", action="store_true", help="INPUT is a dataset each binary builds first")
ap.add_argument("--build-options", default="", help="more build options, space separated")
a = ap.parse_args()

scratch = tempfile.TemporaryDirectory()
models = {}
for i, b in enumerate(a.binaries):
    models[b] = a.input
    if a.build:
        models[b] = f"{scratch.name}/{i}.model"
        subprocess.run([b, "-q", "build", a.input, "-o", models[b]] + a.build_options.split(), check=True)
        info = subprocess.run([b, "info", models[b]], capture_output=True, text=True, check=True).stdout
        counts = [line.split()[1] for line in info.splitlines() if line.startswith(("bricks ", "regions "))]
        print(f"{b}: {counts[0]} bricks, {counts[1]} regions")

times = {b: [] for b in a.binaries}
samples = {}
for _ in range(a.rounds):
    for b in a.binaries:
        cmd = [b, "-q"] + (["--threads", str(a.threads)] if a.threads else []) + \
              ["render", models[b], "--size", a.size, "-o", "/dev/null", "--json", "--stats", "--frames",
               str(a.frames)] + a.extra.split()
        j = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
        times[b].append(j["frame_seconds"])
        samples[b] = j["samples"]
base = statistics.median(times[a.binaries[0]])
print(f"{a.input} at {a.size}, {a.rounds} rounds (each the median of {a.frames} frames)")
print(f"{'binary':40} {'median s':>9} {'min s':>7} {'M samples/s':>12} {'speed-up':>9}")
for b in a.binaries:
    t = statistics.median(times[b])
    print(f"{b:40} {t:9.3f} {min(times[b]):7.3f} {samples[b] / t / 1e6:12.1f} {base / t:9.2f}")
