#!/usr/bin/python3
"""Renders one AMReX plotfile with exabricks and with yt at the same resolution, camera,
value range, colour map and opacity ramp; prints the times and their ratios and writes both
images side by side into one PNG. Not a test. Run with Debian's Python, which has yt:

  /usr/bin/python3 bench/peers/compare_yt.py build/exabricks /work/shared/data/amrex/advection_3d/plt_drop \\
      --size 1024 --out /tmp/peers

See bench/peers/README.md for what each renderer does differently.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_common import (add_common_arguments, agreement, alike, camera, dataset_info,  # noqa: E402
                         describe_agreement, pinned_arguments, require_comparable, run_exabricks)


def bright_level(rgb):
    """Brightness of the brightest pixels: 99.9th percentile of the per-pixel mean of r, g, b."""
    import numpy as np
    return float(np.percentile(np.asarray(rgb, dtype=np.float64).mean(axis=-1), 99.9))


def parse_arguments():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common_arguments(p)
    p.add_argument("--frames", type=int, default=3, help="exabricks frames timed (median)")
    p.add_argument("--calibration-size", type=int, default=256,
                   help="resolution at which yt's opacity is matched to exabricks' mean coverage")
    p.add_argument("--out", default="peer-comparison")
    return p.parse_args()


def describe(a):
    """The dataset as `exabricks info` describes it, and the view both renderers share: value range,
    exabricks' default opacity and camera."""
    info = dataset_info(a.exabricks, a.plotfile)
    require_comparable(info, a.field, a.plotfile)
    lower, upper = info["bounds"]["world"]["lower"], info["bounds"]["world"]["upper"]
    fr = [f for f in info["fields"] if f["name"] == a.field][0]["range"]
    value_range = (fr["min"], fr["max"])
    finest_cells = max((u - l) for l, u in zip(info["bounds"]["lattice"]["lower"], info["bounds"]["lattice"]["upper"]))
    # exabricks' default opacity: per finest cell, a ray through the whole data at full opacity
    # gathers an optical depth of about eight.
    opacity_scale = min(1.0, 8.0 / finest_cells)
    pos, look, up, distance = camera(lower, upper, a.azimuth, a.elevation, a.fov)
    return info, {"range": value_range, "opacity_scale": opacity_scale, "position": pos, "look_at": look, "up": up,
                  "distance": distance}


def render_exabricks(a, view):
    """The command line's renders: full quality, without early termination, unshaded, and the
    unshaded calibration image yt's opacity is matched to."""
    pos, look, up = view["position"], view["look_at"], view["up"]
    value_range, opacity_scale = view["range"], view["opacity_scale"]
    ex_png = os.path.join(a.out, "exabricks.png")
    ex_wall, ex = run_exabricks(a.exabricks, a.plotfile, a.field, a.size, pos, look, up, a.fov, value_range,
                                opacity_scale, ex_png, [], a.frames)
    _, ex_noet = run_exabricks(a.exabricks, a.plotfile, a.field, a.size, pos, look, up, a.fov, value_range,
                               opacity_scale, os.path.join(a.out, "exabricks-no-et.png"),
                               ["--no-early-termination"], a.frames)
    _, ex_flat = run_exabricks(a.exabricks, a.plotfile, a.field, a.size, pos, look, up, a.fov, value_range,
                               opacity_scale, os.path.join(a.out, "exabricks-unshaded.png"),
                               ["--no-early-termination"], a.frames, shading="none")
    # Mean brightness over black at the calibration size, unshaded, for matching yt's opacity.
    cal_png = os.path.join(a.out, "exabricks-calibration.png")
    subprocess.run([a.exabricks, "-q", "render", "-o", cal_png, "--no-early-termination"]
                   + pinned_arguments(a.plotfile, a.field, a.calibration_size, pos, look, up, a.fov, value_range,
                                      opacity_scale, "none"), check=True)
    return {"png": ex_png, "wall": ex_wall, "full": ex, "no_et": ex_noet, "flat": ex_flat, "calibration": cal_png,
            "flat_png": os.path.join(a.out, "exabricks-unshaded.png")}


def make_scene(ds, yfield, view, fov, resolution, alpha_scale):
    import numpy as np
    import yt

    value_range = view["range"]
    sc = yt.create_scene(ds, yfield, lens_type="perspective")
    src = sc[0]
    src.set_log(False)
    # grey_opacity: the alpha channel attenuates every colour channel (emission-absorption
    # with one opacity, as in exabricks).
    tf = yt.ColorTransferFunction(value_range, grey_opacity=True)
    # viridis over the whole range, opacity a linear ramp 0 -> 1 (times alpha_scale), the
    # emitted colour weighted the same way: emission = colour x opacity, as exabricks does.
    tf.map_to_colormap(value_range[0], value_range[1], scale=alpha_scale, colormap="viridis",
                       scale_func=lambda v, lo, hi: (v - lo) / (hi - lo))
    for ch in (tf.red, tf.green, tf.blue):
        ch.y *= alpha_scale
    src.set_transfer_function(tf)
    cam = sc.camera
    cam.resolution = (resolution, resolution)
    cam.focus = ds.arr(view["look_at"], "code_length")
    cam.set_position(ds.arr(view["position"], "code_length"), north_vector=np.array(view["up"]))
    # The perspective lens puts an image plane of size width[0] x width[1] at distance width[2].
    distance = view["distance"]
    w = 2.0 * distance * math.tan(0.5 * fov * math.pi / 180.0)
    cam.width = ds.arr([w, w, distance], "code_length")
    return sc


def brightness(img):
    import numpy as np

    # yt's image is composited over black (alpha 1 everywhere).
    return bright_level(np.clip(np.asarray(img)[..., :3], 0, 1))


def quiet(fn):
    """Runs fn with the process's stdout silenced (yt's k-d tree prints a line for every
    grid it cannot split); returns fn's result and the number of such lines."""
    sys.stdout.flush()
    saved = os.dup(1)
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 1)
        try:
            result = fn()
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
        tmp.seek(0)
        count = tmp.read().count(b"Failed to split grids")
    return result, count


def render_yt(a, view, ex_cal):
    """yt's renders: timed, then with the opacity matched to exabricks' calibration image; writes
    the image shown."""
    import numpy as np
    import matplotlib.pyplot as plt
    import yt

    yfield = ("boxlib", a.field)
    if yfield not in yt.load(a.plotfile).field_list:
        sys.exit("yt cannot read the field %s of %s: nothing to compare" % (a.field, a.plotfile))
    # Timed: the first render of a scene builds yt's brick k-d tree (vertex-centred data per
    # grid), the second reuses it. Render time does not depend on the opacity (yt integrates
    # every ray to its end).
    t0 = time.perf_counter()
    ds = yt.load(a.plotfile)
    ds.index
    t_load = time.perf_counter() - t0
    sc = make_scene(ds, yfield, view, a.fov, a.size, 8.0)
    t0 = time.perf_counter()
    _, split_messages = quiet(sc.render)
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    sc.render()
    t_second = time.perf_counter() - t0

    # yt's integrator scales opacity and emission by its own ray parameter, not per finest cell:
    # find the scale that gives the same brightness of the brightest pixels (99.9th percentile)
    # over black as exabricks' unshaded image
    # (small renders, not timed), then render the image shown.
    scale = 8.0
    t_cal = time.perf_counter()
    for _ in range(5):
        cur = brightness(quiet(make_scene(ds, yfield, view, a.fov, a.calibration_size, scale).render)[0])
        scale *= min(8.0, ex_cal / cur) if cur > 0 else 8.0
    t_cal = time.perf_counter() - t_cal
    t0 = time.perf_counter()
    im, _ = quiet(make_scene(ds, yfield, view, a.fov, a.size, scale).render)
    t_third = time.perf_counter() - t0
    yt_bright = brightness(im)

    # yt's image: colour channels as accumulated over black (they are the colour map's own sRGB
    # values), shown as they are.
    rgb = np.clip(np.asarray(im, dtype=np.float64)[..., :3], 0, 1)
    # yt's image is indexed [x, y]: transpose to rows.
    rgb = rgb.transpose(1, 0, 2)
    yt_png = os.path.join(a.out, "yt.png")
    plt.imsave(yt_png, rgb)
    return {"ds": ds, "field": yfield, "load": t_load, "first": t_first, "second": t_second, "third": t_third,
            "scale": scale, "calibration": t_cal, "bright": yt_bright, "rgb": rgb, "split_messages": split_messages}


def render_from_yt(a, view, ds, yfield):
    """exabricks in the same Python process: the loaded yt dataset handed over with from_yt. The
    times of from_yt, the first render and a frame (median); None where the module is missing."""
    try:
        import exabricks as eb
    except ImportError:
        print("  (exabricks Python module not importable: build it and add build/python to PYTHONPATH)")
        return None
    t0 = time.perf_counter()
    eds = eb.from_yt(ds, [yfield])
    t_from_yt = time.perf_counter() - t0
    scene = eb.Scene(eds, width=a.size, height=a.size)
    scene.camera = eb.Camera(view["position"], view["look_at"], view["up"], a.fov)
    scene.transfer_function = eb.TransferFunction("viridis", range=view["range"], opacity_scale=view["opacity_scale"])
    t0 = time.perf_counter()
    scene.render()
    t_eb_first = time.perf_counter() - t0
    frames = []
    for _ in range(a.frames):
        scene.ambient += 1e-6  # a new frame each time (the accumulation starts over)
        t0 = time.perf_counter()
        scene.render()
        frames.append(time.perf_counter() - t0)
    t_eb_frame = sorted(frames)[len(frames) // 2]
    scene.save(os.path.join(a.out, "exabricks-from-yt.png"))
    return t_from_yt, t_eb_first, t_eb_frame


def report(a, info, view, ex, yt_run, ex_cal, from_yt_times, agree):
    """Prints the times and their ratios, each beside the agreement of the pictures it compares;
    returns both."""
    eb_rows = []
    if from_yt_times is not None:
        t_from_yt, t_eb_first, t_eb_frame = from_yt_times
        eb_rows = [("exabricks.from_yt (yt grids -> leaf cells, bricks, regions)", t_from_yt),
                   ("exabricks.from_yt: first render in Python", t_eb_first),
                   ("exabricks.from_yt: full-quality frame in Python (median)", t_eb_frame)]
    ex_frame = ex["full"]["frame_seconds"]
    t_load, t_first, t_second = yt_run["load"], yt_run["first"], yt_run["second"]
    rows = [
        ("exabricks, full quality (shaded, early termination), frame", ex_frame),
        ("exabricks, shaded, early termination off, frame", ex["no_et"]["frame_seconds"]),
        ("exabricks, unshaded, early termination off, frame", ex["flat"]["frame_seconds"]),
        ("exabricks, load + build (plotfile read, bricks, regions)", ex["full"]["load_seconds"]),
        ("exabricks, end to end (one process: load, build, one frame, PNG)", ex["wall"]),
        ("yt, load (plotfile index)", t_load),
        ("yt, first render (brick k-d tree + render)", t_first),
        ("yt, second render (same scene)", t_second),
        ("yt, render of a new scene on the loaded data (image shown)", yt_run["third"]),
    ]
    value_range = view["range"]
    print(f"dataset {a.plotfile} ({info['cells']} leaf cells), field {a.field}, {a.size}x{a.size}, "
          f"value range [{value_range[0]:.6g}, {value_range[1]:.6g}]")
    for name, t in rows + eb_rows:
        print(f"  {name:66s} {t:8.3f} s")
    print(f"  yt opacity scale {yt_run['scale']:.4g}: brightest pixels {yt_run['bright']:.4f} (exabricks unshaded "
          f"{ex_cal:.4f}), found in {yt_run['calibration']:.1f} s")
    print(f"  yt printed 'Failed to split grids.' {yt_run['split_messages']} times while building its k-d tree")
    print("pictures: exabricks unshaded against yt (the same settings): " + describe_agreement(agree["unshaded"]))
    print("          exabricks full quality (lit) against yt: " + describe_agreement(agree["full"]))
    valid = alike(agree["unshaded"])
    print("ratios (yt / exabricks)" + ("" if valid else ", NOT VALID: the pictures differ") + ":")
    ratios = {
        "yt first render / exabricks full-quality frame": t_first / ex_frame,
        "yt second render / exabricks full-quality frame": t_second / ex_frame,
        "yt second render / exabricks frame, early termination off": t_second / ex["no_et"]["frame_seconds"],
        "yt second render / exabricks unshaded frame, early termination off": t_second / ex["flat"]["frame_seconds"],
        "yt load + first render / exabricks end to end": (t_load + t_first) / ex["wall"],
    }
    if eb_rows:
        ratios["yt first render / (exabricks.from_yt + first render)"] = t_first / (t_from_yt + t_eb_first)
        ratios["yt second render / exabricks frame through from_yt"] = t_second / t_eb_frame
    for name, r in ratios.items():
        print(f"  {name:66s} {r:8.2f}x" + ("" if valid else "  (not valid)"))
    return rows, ratios


def save_side_by_side(a, info, ex, yt_run, ex_cal, rows, ratios, agree):
    """Both images side by side in one PNG, and the figures in results.json."""
    import matplotlib.pyplot as plt
    import yt

    ex_frame = ex["full"]["frame_seconds"]
    ex_img = plt.imread(ex["png"])[..., :3]
    fig, axes = plt.subplots(1, 2, figsize=(16, 8.6), dpi=a.size / 8)
    for ax, img, title in ((axes[0], ex_img, f"exabricks: frame {ex_frame:.2f} s (basis, shaded, adaptive)"),
                           (axes[1], yt_run["rgb"], f"yt {yt.__version__}: render {yt_run['second']:.2f} s, "
                                                    f"first {yt_run['first']:.2f} s")):
        ax.imshow(img)
        ax.set_title(title, fontsize=14)
        ax.axis("off")
    fig.suptitle(f"{os.path.basename(os.path.normpath(a.plotfile))}: {info['cells']:,} leaf cells, "
                 f"{a.size}x{a.size}, same camera, range and colour map", fontsize=15)
    fig.tight_layout()
    side = os.path.join(a.out, "side-by-side.png")
    fig.savefig(side)
    json.dump({"rows": dict(rows), "ratios": ratios, "yt_opacity_scale": yt_run["scale"], "agreement": agree,
               "valid": alike(agree["unshaded"]),
               "brightness": [ex_cal, yt_run["bright"]], "yt_split_failures": yt_run["split_messages"]},
              open(os.path.join(a.out, "results.json"), "w"), indent=1)
    print(f"wrote {side}")


def main():
    a = parse_arguments()
    os.makedirs(a.out, exist_ok=True)
    info, view = describe(a)
    ex = render_exabricks(a, view)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import yt
    yt.set_log_level(40)

    ex_cal = bright_level(plt.imread(ex["calibration"])[..., :3])
    yt_run = render_yt(a, view, ex_cal)
    from_yt_times = render_from_yt(a, view, yt_run["ds"], yt_run["field"])
    agree = {"unshaded": agreement(plt.imread(ex["flat_png"])[..., :3], yt_run["rgb"]),
             "full": agreement(plt.imread(ex["png"])[..., :3], yt_run["rgb"])}
    rows, ratios = report(a, info, view, ex, yt_run, ex_cal, from_yt_times, agree)
    save_side_by_side(a, info, ex, yt_run, ex_cal, rows, ratios, agree)
    if not alike(agree["unshaded"]):
        return "the two pictures differ (%s): the ratios compare unlike work" % describe_agreement(agree["unshaded"])


if __name__ == "__main__":
    sys.exit(main())
