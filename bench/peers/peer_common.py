"""What the peer comparisons share: exabricks' default camera, and timing exabricks itself."""
import json
import math
import subprocess
import time


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


def run_exabricks(exe, plot, field, size, pos, look, up, fov, value_range, opacity_scale, out_png, extra, frames):
    common = [plot, "-f", field, "--size", f"{size}x{size}", "--colormap", "viridis",
              "--position", ",".join(map(repr, pos)), "--look-at", ",".join(map(repr, look)),
              "--up", ",".join(map(repr, up)), "--fov", repr(fov),
              "--range", f"{value_range[0]!r},{value_range[1]!r}", "--opacity-scale", repr(opacity_scale),
              "--background", "0,0,0"] + extra
    # End to end: read the plotfile, build bricks and regions, render one frame, write the PNG.
    t0 = time.perf_counter()
    subprocess.run([exe, "-q", "render", "-o", out_png] + common, check=True)
    wall = time.perf_counter() - t0
    # Frame time: median of `frames` after a warm-up, in the same process.
    stats = json.loads(subprocess.run([exe, "-q", "render", "-o", out_png, "--stats", "--json", "--frames", str(frames)]
                                      + common, check=True, capture_output=True, text=True).stdout)
    return wall, stats
