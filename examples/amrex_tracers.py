# %% [markdown]
# # Tracer particles in an AMReX plotfile
# AMReX codes write each particle species as a folder of the plotfile: a `Header` (the version,
# the components' names, the counts and, per level and grid, which `DATA_nnnnn` file holds the
# grid's particles and where) and `Level_L/` with the data files. This example writes such a
# species, `tracers`, into a copy of the shared sample `plt_drop` (the plotfile's own files are
# linked, not copied): tracers seeded in the drop, each carrying the value of `phi` where it sits
# and its distance from the drop's centre. exabricks finds them beside the cells as it finds any
# AMReX code's particles, and draws them with the gas, sized in pixels.

# %%
import os
import pathlib
import sys
import tempfile

import numpy as np

import exabricks as eb

here = pathlib.Path(__file__).resolve().parent
data = pathlib.Path(os.environ.get("EXABRICKS_DATA", here.parents[1] / "shared" / "data"))
source = data / "amrex" / "advection_3d" / "plt_drop"
if not source.exists():
    print("skipped: the shared sample %s is absent (set EXABRICKS_DATA)" % source)
    sys.exit(0)
out = pathlib.Path(os.environ.get("EXAMPLE_OUT", "exabricks-example"))
out.mkdir(parents=True, exist_ok=True)
count = int(os.environ.get("EXAMPLE_TRACERS", "20000"))

# %% A plotfile of the sample's own files, linked.
plotfile = pathlib.Path(tempfile.mkdtemp()) / "plt_drop"
plotfile.mkdir()
for entry in source.iterdir():
    (plotfile / entry.name).symlink_to(entry)
ds = eb.load(str(plotfile))
lo, hi = (np.array(b) for b in ds.bounds)

# %% Seeds where phi is in the upper half of its range, jittered within a 48^3 lattice's cells.
rng = np.random.default_rng(3)
n = 48
axes = [lo[a] + (np.arange(n) + 0.5) * (hi[a] - lo[a]) / n for a in range(3)]
centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
phi = np.nan_to_num(ds.sample(centres)[0], nan=-np.inf)
inside = centres[phi > 0.5 * (phi[np.isfinite(phi)].min() + phi.max())]
position = inside[rng.integers(len(inside), size=count)] + rng.uniform(-0.5, 0.5, (count, 3)) * (hi - lo) / n
value = np.nan_to_num(ds.sample(position)[0])
radius = np.linalg.norm(position - position.mean(axis=0), axis=1)

# %% The species folder in AMReX's particle format (version 2.0, double precision): one grid on
# level 0, its integer block (id, cpu per particle) and then its real block (x, y, z and the real
# components per particle).
species = plotfile / "tracers"
(species / "Level_0").mkdir(parents=True)
ints = np.stack([np.arange(1, count + 1), np.zeros(count)], axis=1).astype("<i4")
reals = np.concatenate([position, value[:, None], radius[:, None]], axis=1).astype("<f8")
with open(species / "Level_0" / "DATA_00000", "wb") as f:
    f.write(ints.tobytes())
    f.write(reals.tobytes())
header = ["Version_Two_Dot_Zero_double", "3", "2", "phi", "radius", "0", "0", str(count), str(count + 1), "0", "1",
          "0 %d 0" % count]
(species / "Header").write_text("\n".join(header) + "\n")
(species / "Level_0" / "Particle_H").write_text("(1 0\n((0,0,0) (95,95,95) (0,0,0))\n)\n")

# %% Read back as exabricks reads any plotfile's particles, and drawn with the gas.
ds = eb.load(str(plotfile))
print(ds.particle_species)
back = ds.particles("tracers")
assert np.array_equal(back["position"], position) and np.array_equal(back["phi"], value)
scene = eb.Scene(ds, width=560, height=560)
scene.particles = True
scene.particle_radius_pixels = 1.2
scene.particle_color_by = "phi"
scene.particle_color_map = eb.TransferFunction("inferno")
scene.orbit(30.0, 20.0)
scene.render()
scene.save(out / "particles-amrex.png")
print("wrote", out / "particles-amrex.png")
