#!/usr/bin/python3
"""Renders the same scenes with two builds of exabricks and compares the images: for every
variant (each shading mode, the march's measurement switches, sampling and reconstruction,
surfaces with ambient occlusion, meshes, clipping, debug views, several layers) it says whether
the PNG and the float image (PFM) are byte-identical, else the largest difference per channel.
For changes that must not move a pixel, or must move them only by round-off. Not a test.

    /usr/bin/python3 bench/compare_images.py before/exabricks build/exabricks [--data /work/shared/data]
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("before")
ap.add_argument("after")
ap.add_argument("--data", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data"),
                help="folder of the shared samples (amrex/...); variants on them are left out without it")
ap.add_argument("--size", default="160x120")
a = ap.parse_args()

tmp = tempfile.TemporaryDirectory()
quad = os.path.join(tmp.name, "quad.obj")
with open(quad, "w") as f:
    f.write("v 10 10 30\nv 86 10 60\nv 86 86 60\nv 10 86 30\nf 1 2 3\nf 1 3 4\n")
drop = os.path.join(a.data, "amrex", "advection_3d", "plt_drop")
pele = os.path.join(a.data, "amrex", "pelelm_3lev_3d", "example_plt_3d")
variants = [
    ("default", []), ("analytic", ["--shading", "analytic"]), ("central", ["--shading", "central"]),
    ("unshaded", ["--shading", "none"]), ("scalar lanes", ["--scalar"]),
    ("scalar lanes, central", ["--scalar", "--shading", "central"]), ("one batch per segment", ["--no-join-segments"]),
    ("eager gradients", ["--no-lazy-gradients", "--shading", "analytic"]), ("fixed steps", ["--sampling", "fixed"]),
    ("cell location", ["--reconstruction", "cells"]), ("embree traversal", ["--traversal", "embree"]),
    ("no skipping, no termination", ["--no-skip", "--no-early-termination"]),
    ("iso, volume AO", ["--iso", "0.3,0.6", "--ao", "4", "--ao-volume"]),
    ("iso by field, surfaces only", ["--iso", "0.5", "--iso-color-field", "scalar", "--no-volume", "--ao", "2"]),
    ("mesh, AO, clip plane", ["--mesh", quad, "--ao", "3", "--clip-plane", "48,48,48,1,0,0"]),
    ("clip box with meshes", ["--clip-box", "10,10,10,70,80,60", "--mesh", quad, "--clip-meshes"]),
    ("debug level", ["--debug", "level"]), ("debug brick", ["--debug", "brick"]),
    ("debug region", ["--debug", "region"]), ("debug steps", ["--debug", "steps"]),
    ("4 spp, rate 2", ["--spp", "4", "--rate", "2"]), ("ortho, directional light", ["--ortho", "--light", "1,0.5,0.2"]),
    ("two layers", ["--layer", "radius=plasma"]),
]
if os.path.isdir(drop):
    variants += [("plt_drop", [drop]), ("plt_drop analytic", [drop, "--shading", "analytic"])]
if os.path.isdir(pele):
    variants += [("pelelm two layers", [pele, "-f", "temp", "--layer", "density=plasma"]),
                 ("pelelm iso by field", [pele, "-f", "temp", "--iso", "1000", "--iso-color-field", "density", "--ao",
                                          "2"])]


def pfm(path):
    with open(path, "rb") as f:
        data = f.read()
    head = data.split(b"\n", 3)
    return np.frombuffer(head[3], dtype="<f4" if float(head[2]) < 0 else ">f4")


changed = 0
for name, extra in variants:
    out = {}
    for tag, exe in (("before", a.before), ("after", a.after)):
        png, flt = os.path.join(tmp.name, tag + ".png"), os.path.join(tmp.name, tag + ".pfm")
        subprocess.run([exe, "-q", "render", "--size", a.size] + extra + ["-o", png, "--float", flt], check=True)
        out[tag] = (open(png, "rb").read(), open(flt, "rb").read())
    same_png, same_pfm = out["before"][0] == out["after"][0], out["before"][1] == out["after"][1]
    if same_png and same_pfm:
        print(f"{name:32} identical")
        continue
    changed += 1
    with open(os.path.join(tmp.name, "b.pfm"), "wb") as f:
        f.write(out["before"][1])
    with open(os.path.join(tmp.name, "a.pfm"), "wb") as f:
        f.write(out["after"][1])
    diff = float(np.abs(pfm(os.path.join(tmp.name, "b.pfm")) - pfm(os.path.join(tmp.name, "a.pfm"))).max())
    print(f"{name:32} float image differs by {diff:.3g} at most; PNG {'identical' if same_png else 'differs'}")
print(f"{len(variants) - changed} of {len(variants)} variants identical")
sys.exit(0)
