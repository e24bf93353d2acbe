# %% [markdown]
# # Particles with the gas
# A cosmology-like generated step (`exabricks generate -s cosmic`) with dark matter placed where
# its gas is and stars in its densest knots, handed to exabricks as arrays
# (`Dataset.add_particles`) and drawn with the gas in one picture: the spheres hide the gas behind
# them and are dimmed by the gas in front of them. A file's own particles (AMReX plotfiles, Enzo
# outputs) need no such step: `eb.load(path)` finds them and `Scene(ds, particles=True)` draws them.

# %%
import os
import pathlib
import subprocess
import tempfile

import numpy as np

import exabricks as eb

out = pathlib.Path(os.environ.get("EXAMPLE_OUT", "exabricks-example"))
out.mkdir(parents=True, exist_ok=True)
exe = os.environ.get("EXABRICKS", "exabricks")
cells = int(os.environ.get("EXAMPLE_CELLS", "1000000"))

# %% The gas: a generated step (in a temporary folder).
tmp = tempfile.mkdtemp()
path = os.path.join(tmp, "cosmic.cells")
subprocess.run([exe, "-q", "generate", "-s", "cosmic", "-n", str(cells), "-o", path], check=True)
ds = eb.load(path)

# %% Where the gas is: its density sampled on a grid of 64^3 points.
rng = np.random.default_rng(7)
lo, hi = (np.array(b) for b in ds.bounds)
n = 64
axes = [lo[a] + (np.arange(n) + 0.5) * (hi[a] - lo[a]) / n for a in range(3)]
centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
density = np.nan_to_num(ds.sample(centres)[0]).clip(min=0.0)
cell = (hi - lo) / n

# %% Dark matter follows the gas; stars sit in the densest 0.2 % of it.
dm = centres[rng.choice(len(centres), 40000, p=density / density.sum())] + rng.uniform(-0.5, 0.5, (40000, 3)) * cell
dense = np.argsort(density)[-len(density) // 500:]
stars = centres[rng.choice(dense, 1500)] + rng.uniform(-0.5, 0.5, (1500, 3)) * cell
ds.add_particles("dark_matter", dm, kind=np.zeros(len(dm)), size=np.full(len(dm), 0.2))
ds.add_particles("stars", stars, kind=np.ones(len(stars)), size=np.ones(len(stars)))
print(ds.particle_species)

# %% One picture: the gas, dark matter in blue, stars in warm colours and larger.
scene = eb.Scene(ds, width=560, height=560)
scene.particles = True
scene.particle_radius = float(np.linalg.norm(hi - lo)) / 400
scene.particle_radius_by = "size"
scene.particle_color_by = "kind"
scene.particle_color_map = eb.TransferFunction("cool-to-warm", range=(0.0, 1.0))
scene.orbit(35.0, 20.0)
scene.render()
scene.save(out / "particles-cosmic.png")
print("wrote", out / "particles-cosmic.png")
