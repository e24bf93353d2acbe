#!/usr/bin/python3
"""MPI rendering on one machine: for 1..N processes, image-parallel and data-parallel, the frame
time, the compositing time, and per process the cells held and the peak memory, beside the
performance model of docs/distributed.md (bytes each process sends per frame; cells each holds).

    /usr/bin/python3 bench/mpi_bench.py build/exabricks INPUT --size 1024x1024 --max-processes 4
"""
import argparse
import json
import os
import subprocess
import tempfile

ap = argparse.ArgumentParser()
ap.add_argument("exabricks")
ap.add_argument("input")
ap.add_argument("--size", default="1024x1024")
ap.add_argument("--max-processes", type=int, default=4)
ap.add_argument("--modes", default="image,data")
ap.add_argument("--extra", default="", help="more render options, space separated")
a = ap.parse_args()

env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_btl_vader_single_copy_mechanism="none")
w, h = map(int, a.size.split("x"))
pixels = w * h
out = tempfile.mkdtemp()
print(f"input {a.input}, {a.size}; one thread per process (2 cores: more than 2 processes share them)")
print(f"{'mode':6} {'N':>2} {'frame s':>8} {'comp. s':>8} {'wait s':>7} {'cells/proc (max)':>17} {'peak MB/proc (max)':>19} "
      f"{'model: MB sent/proc':>20}")
for mode in a.modes.split(","):
    for n in range(1, a.max_processes + 1):
        cmd = ["mpirun", "--oversubscribe", "--bind-to", "none", "-np", str(n), a.exabricks, "-q", "--threads", "1" if n > 1 else "2",
               "render", a.input, "--size", a.size, "-o", os.path.join(out, "b.png"), "--json",
               "--distribute", mode] + a.extra.split()
        r = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if r.returncode != 0:
            print(mode, n, "failed:", r.stderr.strip()[-400:])
            continue
        j = json.loads(r.stdout)
        ranks = j.get("ranks", [])
        cells = max((x["resident_cells"] for x in ranks), default=0)
        rss = max((x["peak_rss_bytes"] for x in ranks), default=0) / 1e6
        # The model: image-parallel reduces 20 B/pixel from every process (binomial tree: each
        # sends its sums once); data-parallel direct send: 20 B/pixel x (N-1)/N in the exchange
        # plus 20 B/pixel / N to the root, per pass.
        spp = j.get("samples_per_pixel", 1)
        if n == 1:
            sent = 0.0
        elif mode == "image":
            sent = 20 * pixels
        else:
            sent = spp * 20 * pixels * ((n - 1) / n + 1 / n)
        print(f"{mode:6} {n:>2} {j['frame_seconds']:8.3f} {j.get('composite_seconds', 0):8.3f} "
              f"{j.get('composite_wait_seconds', 0):7.3f} {cells:17d} "
              f"{rss:19.1f} {sent / 1e6:20.1f}")
