"""What the path-tracing benchmarks share: the lights they render with, one `exabricks render` run
with its JSON, a PNG's pixels, and the datasets (shared samples, or a generated cosmology-like
step)."""
import json
import os
import subprocess
import sys

import numpy as np
from PIL import Image

# The sun and bounces of every path-traced frame the benchmarks time.
SUN = ["--sun", "-0.75,0.5,-0.7,5", "--bounces", "4"]


def render(exe, args, out):
    """`exabricks render ARGS -o OUT --json`: its JSON, or exit naming the command that failed."""
    run = subprocess.run([exe, "render"] + args + ["-o", out, "--json"], capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit("failed: %s\n%s" % (" ".join(args), run.stderr))
    return json.loads(run.stdout)


def pixels(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(float)


def dataset(exe, name, rel, data, work):
    """The input of a case: `rel` under `data`, or (rel None) a 1M-cell cosmic step generated once
    under `work`; None, with a note, where a shared sample is absent."""
    if rel is None:
        path = os.path.join(work, "cosmic.cells")
        if not os.path.exists(path):
            subprocess.run([exe, "-q", "generate", "-s", "cosmic", "-n", "1000000", "-o", path], check=True)
        return path
    path = os.path.join(data, rel)
    if not os.path.exists(path):
        print("%-12s skipped: %s is absent" % (name, path))
        return None
    return path
