"""What the peer comparisons share: exabricks' default camera, exabricks' command lines with
every setting that decides the picture pinned (checked in the scene they write), timing exabricks,
the checks that a dataset can be compared at all, and the agreement of two pictures."""
import json
import math
import os
import subprocess
import sys
import tempfile
import time

# A ratio of times is printed as valid only for pictures at least this alike (structural
# similarity of the luminance, 7x7 windows) with a mean difference at most this (in 1/255).
MIN_SSIM = 0.80
MAX_MEAN_DIFFERENCE = 6.0


def add_common_arguments(parser):
    """The arguments every comparison takes: the exabricks binary, the plotfile and the view."""
    parser.add_argument("exabricks")
    parser.add_argument("plotfile")
    parser.add_argument("--field", default="phi")
    parser.add_argument("--size", type=int, default=1024)
    parser.add_argument("--azimuth", type=float, default=30.0)
    parser.add_argument("--elevation", type=float, default=25.0)
    parser.add_argument("--fov", type=float, default=40.0)


def camera(lower, upper, azimuth, elevation, fov):
    """The camera exabricks' Camera::frame builds: the bounding sphere fills the view."""
    deg = math.pi / 180.0
    centre = [(a + b) / 2 for a, b in zip(lower, upper)]
    radius = 0.5 * math.sqrt(sum((b - a) ** 2 for a, b in zip(lower, upper)))
    d = [math.cos(elevation * deg) * math.cos(azimuth * deg),
         math.cos(elevation * deg) * math.sin(azimuth * deg), math.sin(elevation * deg)]
    distance = radius / math.sin(0.5 * fov * deg)
    position = [c + x * distance for c, x in zip(centre, d)]
    up = [0.0, 1.0, 0.0] if abs(d[2]) > 0.999 else [0.0, 0.0, 1.0]
    return position, centre, up, distance


def pinned_arguments(plot, field, size, pos, look, up, fov, value_range, opacity_scale, shading="smooth"):
    """exabricks' arguments for the peers' picture, every choice that decides it given: the camera,
    a linear map of the range through viridis, an opacity ramp from 0 to 1, the opacity scale,
    the shading and a black background; nothing left to the first picture's automatic choices
    (logarithmic mapping, a transparent background value, exposure)."""
    return [plot, "-f", field, "--size", f"{size}x{size}", "--colormap", "viridis", "--linear",
            "--opacity", "0,0,1,1", "--range", f"{value_range[0]!r},{value_range[1]!r}",
            "--opacity-scale", repr(opacity_scale), "--shading", shading, "--background", "0,0,0",
            "--position", ",".join(map(repr, pos)), "--look-at", ",".join(map(repr, look)),
            "--up", ",".join(map(repr, up)), "--fov", repr(fov)]


def check_pinned(exe, arguments, value_range, opacity_scale, shading):
    """Renders a tiny picture with `arguments` and checks, in the scene it writes, that the picture
    is the pinned one; exits with a message otherwise (a ratio of unlike pictures is never printed)."""
    with tempfile.TemporaryDirectory() as tmp:
        scene_path = os.path.join(tmp, "scene.json")
        small = list(arguments)
        small[small.index("--size") + 1] = "16x16"
        subprocess.run([exe, "-q", "render", "-o", os.path.join(tmp, "t.png"), "--write-scene", scene_path] + small,
                       check=True)
        scene = json.load(open(scene_path))
    tf = scene["layers"][0]["transfer_function"]
    problems = []
    if tf.get("log"):
        problems.append("the values are mapped logarithmically")
    if not all(math.isclose(float(x), float(v), rel_tol=1e-6, abs_tol=1e-30) for x, v in zip(tf["range"], value_range)):
        problems.append("the range is %s, not %s" % (tf["range"], list(value_range)))
    if [[float(x), float(a)] for x, a in tf.get("opacity", [])] != [[0.0, 0.0], [1.0, 1.0]]:
        problems.append("the opacity points are %s, not a ramp from 0 to 1" % tf.get("opacity", "the default's"))
    if not math.isclose(float(tf["opacity_scale"]), float(opacity_scale), rel_tol=1e-6):
        problems.append("the opacity scale is %s, not %s" % (tf["opacity_scale"], opacity_scale))
    if scene.get("shading") != shading:
        problems.append("the shading is %s, not %s" % (scene.get("shading"), shading))
    if [float(x) for x in scene["background"]] != [0.0, 0.0, 0.0]:
        problems.append("the background is %s, not black" % scene["background"])
    if problems:
        sys.exit("exabricks would not draw the pinned picture: " + "; ".join(problems))
    return scene


def dataset_info(exe, plot):
    """`exabricks info --json` of the dataset; exits with exabricks' own message when it cannot
    be read."""
    r = subprocess.run([exe, "-q", "info", plot, "--json"], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("%s cannot be compared: %s" % (plot, r.stderr.strip() or "exabricks info failed"))
    return json.loads(r.stdout)


def require_comparable(info, field, source):
    """Exits with a message unless `info` (exabricks info --json) describes a 3-D dataset with
    `field`: a peer comparison of anything else would compare unlike pictures."""
    names = [f["name"] for f in info.get("fields", [])]
    if field not in names:
        sys.exit("%s has no field '%s' (it has %s): nothing to compare" % (source, field, ", ".join(names) or "none"))
    lower, upper = info["bounds"]["lattice"]["lower"], info["bounds"]["lattice"]["upper"]
    if len(lower) != 3 or min(u - l for l, u in zip(lower, upper)) <= 1:
        sys.exit("%s is not a 3-D volume (lattice %s to %s): the peer comparisons compare volume renders"
                 % (source, lower, upper))


def agreement(a, b):
    """How alike two pictures are (arrays rows x columns x 3 in [0, 1], the same size): the mean
    absolute difference in 1/255 and the mean structural similarity of their luminance over 7x7
    windows (1: the same picture)."""
    import numpy as np
    a = np.asarray(a, dtype=np.float64)[..., :3]
    b = np.asarray(b, dtype=np.float64)[..., :3]
    if a.shape != b.shape:
        raise ValueError("pictures of different sizes: %s and %s" % (a.shape, b.shape))
    mean_difference = float(np.abs(a - b).mean() * 255.0)
    weights = np.array([0.2126, 0.7152, 0.0722])
    x, y = a @ weights, b @ weights

    def box(img, k=7):
        c = np.cumsum(np.cumsum(np.pad(img, ((1, 0), (1, 0))), axis=0), axis=1)
        return (c[k:, k:] - c[:-k, k:] - c[k:, :-k] + c[:-k, :-k]) / (k * k)

    mx, my = box(x), box(y)
    vx, vy, cxy = box(x * x) - mx * mx, box(y * y) - my * my, box(x * y) - mx * my
    c1, c2 = 0.01 ** 2, 0.03 ** 2
    ssim = ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2))
    return {"mean_difference_255": mean_difference, "ssim": float(ssim.mean())}


def alike(agree):
    return agree["ssim"] >= MIN_SSIM and agree["mean_difference_255"] <= MAX_MEAN_DIFFERENCE


def describe_agreement(agree):
    verdict = "alike" if alike(agree) else "NOT ALIKE: ratios not valid"
    return "SSIM %.3f, mean difference %.1f/255 (%s)" % (agree["ssim"], agree["mean_difference_255"], verdict)


def run_exabricks(exe, plot, field, size, pos, look, up, fov, value_range, opacity_scale, out_png, extra, frames,
                  shading="smooth"):
    common = pinned_arguments(plot, field, size, pos, look, up, fov, value_range, opacity_scale, shading) + extra
    check_pinned(exe, common, value_range, opacity_scale, shading)
    # End to end: read the plotfile, build bricks and regions, render one frame, write the PNG.
    t0 = time.perf_counter()
    subprocess.run([exe, "-q", "render", "-o", out_png] + common, check=True)
    wall = time.perf_counter() - t0
    # Frame time: median of `frames` after a warm-up, in the same process.
    stats = json.loads(subprocess.run([exe, "-q", "render", "-o", out_png, "--stats", "--json", "--frames", str(frames)]
                                      + common, check=True, capture_output=True, text=True).stdout)
    return wall, stats
