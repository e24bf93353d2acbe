# %% [markdown]
# # exabricks from Python
# A notebook in script form (cells start with `# %%`; Jupyter opens it with jupytext, and it runs
# top to bottom as a script): load data, render, change the transfer function and iso-surfaces,
# sample, and hand numpy data and yt datasets to exabricks.

# %%
import os
import pathlib

import numpy as np

import exabricks as eb

out = pathlib.Path(os.environ.get("EXAMPLE_OUT", "exabricks-example"))
out.mkdir(parents=True, exist_ok=True)

# %% The embedded default dataset (any path the command line reads works the same).
ds = eb.load()
print(ds)
print({k: ds.info()[k] for k in ("cells", "bricks", "regions")})

# %% A scene: render to a numpy array (linear RGB, premultiplied alpha) and save a PNG.
scene = eb.Scene(ds, width=320, height=240)
scene.transfer_function = eb.TransferFunction("inferno", opacity=[(0.0, 0.0), (0.3, 0.0), (1.0, 0.8)])
scene.background = (0.0, 0.0, 0.0)
image = scene.render()
print(image.shape, image.dtype, "mean alpha %.3f" % image[..., 3].mean())
scene.save(out / "volume.png")

# %% Iso-surfaces coloured by a second field, a clip plane; only the iso set is rebuilt.
scene.iso_values = [0.5]
scene.iso_color_field = "radius"
scene.add_clip_plane(point=(48, 48, 48), normal=(1, 0, 0))
scene.save(out / "iso.png")
print(scene.stats()["iso_regions"], "regions may hold the iso-surface")

# %% Progressive refinement: each pass adds one sample per pixel.
for n in (1, 2, 4, 8):
    scene.render_progressive(spp=8, passes=n)
print("passes:", scene.stats()["passes"])

# %% Sampling: values and gradients per world unit at world positions.
values, gradients = ds.sample([[48.0, 48.0, 48.0], [10.0, 20.0, 30.0]])
print(values, gradients)

# %% Your own arrays: leaf cells (corners in finest-lattice units, levels) and fields.
corners = np.array([[x, y, z] for z in range(0, 8, 2) for y in range(0, 8, 2) for x in range(0, 8, 2)], dtype=np.int32)
levels = np.ones(len(corners), dtype=np.int32)
density = np.exp(-np.sum((corners + 1.0 - 4.0) ** 2, axis=1) / 8.0).astype(np.float32)
small = eb.from_cells(corners, levels, {"density": density}, origin=(-1.0, -1.0, -1.0), spacing=(0.25, 0.25, 0.25))
eb.Scene(small, width=160, height=160).save(out / "cells.png")

# %% yt: any dataset yt loads renders in one line.
try:
    import yt
except ImportError:
    yt = None
if yt is not None:
    yt.set_log_level(50)
    grids = [{"left_edge": [0.0, 0.0, 0.0], "right_edge": [1.0, 1.0, 1.0], "level": 0, "dimensions": [8, 8, 8],
              "density": np.random.default_rng(1).random((8, 8, 8))}]
    stream = yt.load_amr_grids(grids, [8, 8, 8])
    eb.Scene(eb.from_yt(stream, [("stream", "density")]), width=160, height=160).save(out / "yt.png")
print("wrote", sorted(p.name for p in out.glob("*.png")))
