#!/usr/bin/python3
"""Movie of a generated time series: total time with and without loading the next step while one
renders (prefetch) and with and without reusing bricks and regions when the hierarchy is
unchanged; the four variants alternate in every round, and the medians and ratios are printed.

    exabricks generate -n 1000000 --steps 24 --regrid 4 -o series/blobs.cells
    /usr/bin/python3 bench/movie_bench.py build/exabricks series --size 512x512 --rounds 2
"""
import argparse
import json
import shutil
import statistics
import subprocess
import tempfile

ap = argparse.ArgumentParser()
ap.add_argument("exabricks")
ap.add_argument("series")
ap.add_argument("--size", default="512x512")
ap.add_argument("--rounds", type=int, default=2)
a = ap.parse_args()

variants = {"prefetch + reuse": [], "reuse only": ["--no-prefetch"], "prefetch only": ["--no-reuse"],
            "neither": ["--no-prefetch", "--no-reuse"]}
results = {k: [] for k in variants}
for r in range(a.rounds):
    for name, flags in variants.items():
        out = tempfile.mkdtemp()
        p = subprocess.run([a.exabricks, "-q", "movie", a.series, "-o", out, "--size", a.size, "--json"] + flags,
                           capture_output=True, text=True, check=True)
        shutil.rmtree(out)
        results[name].append(json.loads(p.stdout))
base = statistics.median(j["seconds"] for j in results["neither"])
print("%-18s %9s %9s %9s %9s %7s %7s" % ("variant", "total s", "render s", "load s", "waited s", "reused", "ratio"))
for name, runs in results.items():
    med = lambda k: statistics.median(j[k] for j in runs)  # noqa: E731
    total = med("seconds")
    print("%-18s %9.2f %9.2f %9.2f %9.2f %7d %7.3f" % (name, total, med("render_seconds"), med("load_seconds"),
                                                        med("load_wait_seconds"), runs[0]["steps_reused"],
                                                        base / total))
