#!/usr/bin/env python3
"""Regenerate docs/images/pathtrace-compare.png: plt_drop, the PeleLM plotfile (temp) and a
generated cosmology-like density, each ray-marched (top row) and path-traced (bottom row) from
the same camera, over the same ground plane; the path tracer as it draws by default (denoised, to
its noise target). Prints every command and its time. Not a test.

usage: pathtrace_figure.py EXABRICKS [--data DIR] [--work DIR] [-o OUT]

--data is $EXABRICKS_DATA (default /work/shared/data); --work holds the floor meshes, the
generated cosmic.cells and the six panels (default /tmp/pathtrace-figure). Needs PIL.
"""
import argparse
import os
import shlex
import subprocess
import sys
import time

from PIL import Image, ImageDraw, ImageFont

SIZE = "320x320"
BACKGROUND = "0.72,0.78,0.86"
# One light rig for all three: a sun from the upper left behind the camera (elevation ~40 deg)
# and a sky gradient (blue zenith, grey horizon, dark ground).
LIGHTS = ["--sun", "-0.75,0.5,-0.7,5", "--environment", "0.3,0.33,0.38",
          "--sky", "0.12,0.2,0.45", "--ground", "0.1,0.1,0.1"]

# name, input (relative to --data or absolute), floor quad x0,y0,x1,y1,z, floor colour,
# camera, transfer function and other options shared by both integrators, path-tracing options.
DATASETS = [
    dict(name="plt_drop", label="plt_drop (phi)",
         input="{data}/amrex/advection_3d/plt_drop",
         floor=(-3, -3, 4, 4, 0.0), floor_color="0.55,0.55,0.55",
         camera=["--look-at", "0.55,0.74,0.33", "--position", "1.65,1.375,1.219"],
         common=["--colormap", "cool-to-warm", "--opacity-scale", "0.15"],
         pathtrace=["--albedo", "0.95"]),
    dict(name="pelelm", label="PeleLM (temp)",
         input="{data}/amrex/pelelm_3lev_3d/example_plt_3d",
         floor=(-0.05, -0.05, 0.066, 0.066, -0.0002), floor_color="0.55,0.55,0.55",
         camera=["--look-at", "0.008,0.006,0.005", "--position", "0.0455,0.02765,0.03"],
         common=["-f", "temp", "--colormap", "inferno", "--range", "298,1580",
                 "--opacity", "0,0,0.25,0,0.5,1,0.75,0,1,0.05", "--opacity-scale", "0.5"],
         pathtrace=["--albedo", "0.9"]),
    dict(name="cosmic", label="cosmic (density, log)",
         input="{work}/cosmic.cells",
         floor=(-800, -800, 1100, 1100, -2), floor_color="0.55,0.55,0.55",
         camera=["--look-at", "150,170,105", "--position", "717.5,497.7,563.9"],
         common=["--colormap", "plasma", "--opacity-scale", "0.25"],
         pathtrace=["--albedo", "0.9"]),
]


def run(cmd):
    print("$ " + " ".join(shlex.quote(c) for c in cmd), flush=True)
    t = time.time()
    subprocess.run(cmd, check=True, stderr=subprocess.DEVNULL)
    dt = time.time() - t
    print(f"  {dt:.1f} s", flush=True)
    return dt


def write_floor(path, x0, y0, x1, y1, z):
    """A two-triangle quad in the plane z, world coordinates."""
    with open(path, "w") as f:
        f.write(f"v {x0} {y0} {z}\nv {x1} {y0} {z}\nv {x1} {y1} {z}\nv {x0} {y1} {z}\n"
                "f 1 2 3\nf 1 3 4\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("exabricks")
    ap.add_argument("--data", default=os.environ.get("EXABRICKS_DATA", "/work/shared/data"))
    ap.add_argument("--work", default="/tmp/pathtrace-figure")
    ap.add_argument("--only", help="render only this dataset (no figure)")
    ap.add_argument("-o", "--output", default=os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "docs", "images",
        "pathtrace-compare.png"))
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    cosmic = os.path.join(a.work, "cosmic.cells")
    if not os.path.exists(os.path.join(a.work, "cosmic.density.scalars")):
        run([a.exabricks, "generate", "-s", "cosmic", "-n", "400000", "-o", cosmic])

    panels = []
    for d in DATASETS:
        if a.only and d["name"] != a.only:
            continue
        floor = os.path.join(a.work, f"floor-{d['name']}.obj")
        write_floor(floor, *d["floor"])
        base = [a.exabricks, "render", d["input"].format(data=a.data, work=a.work),
                "--size", SIZE, "--background", BACKGROUND] + d["camera"] + d["common"] + \
            ["--mesh", floor, "--mesh-color", d["floor_color"]]
        march = os.path.join(a.work, f"{d['name']}-march.png")
        trace = os.path.join(a.work, f"{d['name']}-pathtrace.png")
        run(base + ["-o", march])
        run(base + ["--integrator", "pathtrace"] + d["pathtrace"] +
            LIGHTS + ["-o", trace])
        panels.append((d["label"], march, trace))
    if a.only:
        return

    w, h = (int(v) for v in SIZE.split("x"))
    fig = Image.new("RGB", (w * len(panels), h * 2), "white")
    draw = ImageDraw.Draw(fig)
    try:
        font = ImageFont.truetype("DejaVuSans.ttf", 13)
    except OSError:
        font = ImageFont.load_default()
    for col, (label, march, trace) in enumerate(panels):
        for row, path in enumerate((march, trace)):
            fig.paste(Image.open(path).convert("RGB"), (col * w, row * h))
            text = f"{label}: " + ("ray-marched" if row == 0 else "path-traced")
            draw.text((col * w + 7, row * h + 5), text, fill=(20, 20, 30), font=font)
    fig.save(a.output, optimize=True)
    print(f"wrote {a.output} ({os.path.getsize(a.output) // 1024} KiB)")


if __name__ == "__main__":
    main()
