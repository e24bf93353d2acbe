#!/usr/bin/env python3
"""Frame time of each rendering effect on one dataset, in one run: volume alone, iso-surface
alone, volume + iso-surface, + mesh, + ambient occlusion (2 rays), and the same with a clipping
plane. Prints a table and the cost of each effect relative to the volume
alone. Not a test.

usage: effects.py EXABRICKS [INPUT] [--size 1024x1024] [--frames 3] [--iso VALUE]

The mesh is a UV sphere of about 20k triangles beside the data plus a floor below it, written
to a temporary OBJ file; the iso-value defaults to 60 % of the field's range.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile


def info(exe, data):
    out = subprocess.run([exe, "-q", "info"] + ([data] if data else []) + ["--json"], check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)


def write_mesh(path, lo, hi):
    """A floor below the world box and a sphere beside it (world coordinates)."""
    size = [h - l for l, h in zip(lo, hi)]
    ext = max(size)
    verts, faces = [], []
    z = lo[2] - 0.02 * ext
    for x, y in ((lo[0] - ext, lo[1] - ext), (hi[0] + ext, lo[1] - ext), (hi[0] + ext, hi[1] + ext),
                 (lo[0] - ext, hi[1] + ext)):
        verts.append((x, y, z))
    faces.append((1, 2, 3, 4))
    c = (hi[0] + 0.05 * ext, (lo[1] + hi[1]) / 2, lo[2] + 0.2 * ext)
    r = 0.18 * ext
    n_lat, n_lon = 70, 140
    base = len(verts)
    for i in range(n_lat + 1):
        th = math.pi * i / n_lat
        for j in range(n_lon):
            ph = 2 * math.pi * j / n_lon
            verts.append((c[0] + r * math.sin(th) * math.cos(ph), c[1] + r * math.sin(th) * math.sin(ph),
                          c[2] + r * math.cos(th)))
    for i in range(n_lat):
        for j in range(n_lon):
            a = base + i * n_lon + j + 1
            b = base + i * n_lon + (j + 1) % n_lon + 1
            faces.append((a, b, b + n_lon, a + n_lon))
    with open(path, "w") as f:
        for v in verts:
            f.write("v %.6g %.6g %.6g\n" % v)
        for fc in faces:
            f.write("f " + " ".join(str(i) for i in fc) + "\n")
    return 2 + 2 * n_lat * n_lon


def run(exe, data, size, frames, extra):
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [exe, "-q", "render"] + ([data] if data else []) + [
            "-o", os.path.join(tmp, "out.png"), "--size", size, "--stats", "--json", "--frames",
            str(frames)] + extra
        return json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("exabricks")
    p.add_argument("input", nargs="?", default="")
    p.add_argument("--size", default="1024x1024")
    p.add_argument("--frames", type=int, default=3)
    p.add_argument("--iso", type=float, default=None)
    a = p.parse_args()
    meta = info(a.exabricks, a.input)
    names = [f["name"] for f in meta["fields"]]
    field = meta["fields"][names.index("scalar") if "scalar" in names else 0]
    lo_v, hi_v = field["range"]["min"], field["range"]["max"]
    iso = a.iso if a.iso is not None else lo_v + 0.6 * (hi_v - lo_v)
    wb = meta["bounds"]["world"]
    lo, hi = wb["lower"], wb["upper"]
    centre = [(l + h) / 2 for l, h in zip(lo, hi)]
    with tempfile.TemporaryDirectory() as tmp:
        mesh = os.path.join(tmp, "mesh.obj")
        tris = write_mesh(mesh, lo, hi)
        iso_opt = ["--iso", "%.9g" % iso]
        clip = ["--clip-plane", ",".join("%.9g" % v for v in centre + [1, 1, 0])]
        cases = [
            ("volume", []),
            ("iso-surface", ["--no-volume"] + iso_opt),
            ("volume + iso", iso_opt),
            ("volume + iso + mesh", iso_opt + ["--mesh", mesh]),
            ("volume + iso + mesh + AO 2", iso_opt + ["--mesh", mesh, "--ao", "2"]),
            ("... + clipping plane", iso_opt + ["--mesh", mesh, "--ao", "2"] + clip),
        ]
        print(f"dataset {a.input or '(default)'}: {meta['cells']} cells; iso {iso:.6g}; mesh {tris} triangles; "
              f"{a.size}, median of {a.frames} frames")
        print(f"{'case':30s} {'frame s':>9s} {'vs volume':>10s} {'samples':>12s} {'iso samples':>12s} "
              f"{'surface hits':>13s} {'AO rays':>10s}")
        results = {}
        for name, extra in cases:
            r = run(a.exabricks, a.input, a.size, a.frames, extra)
            results[name] = r
            print(f"{name:30s} {r['frame_seconds']:9.3f} {r['frame_seconds'] / results['volume']['frame_seconds']:9.2f}x "
                  f"{r['samples']:12d} {r['iso_samples']:12d} {r['surface_hits']:13d} {r['ao_rays']:10d}")
        json.dump(results, sys.stderr, indent=1)


if __name__ == "__main__":
    main()
