# %% [markdown]
# # Particles with the gas
# A cosmology-like generated step (`exabricks generate -s cosmic`): its gas, and beside it the
# dark matter placed where the gas's mass is and stars in the haloes (`NAME.particles`, written by
# `generate`), drawn in one picture: the spheres hide the gas behind them and are dimmed by the gas
# in front of them. `eb.load` finds a file's particles (AMReX plotfiles, Enzo outputs, FLASH
# files, native datasets); `Dataset.add_particles` gives any dataset particles from arrays.

# %%
import math
import os
import pathlib
import subprocess
import tempfile

import exabricks as eb

out = pathlib.Path(os.environ.get("EXAMPLE_OUT", "exabricks-example"))
out.mkdir(parents=True, exist_ok=True)
exe = os.environ.get("EXABRICKS", "exabricks")
cells = int(os.environ.get("EXAMPLE_CELLS", "1000000"))

# %% The step: cells/25 dark-matter particles and cells/625 stars come with it.
tmp = tempfile.mkdtemp()
path = os.path.join(tmp, "cosmic.cells")
subprocess.run([exe, "-q", "generate", "-s", "cosmic", "-n", str(cells), "-o", path], check=True)
ds = eb.load(path)
print(ds.particle_species)
stars = ds.particles("star")
print("%d stars, masses %.3g to %.3g" % (len(stars["position"]), stars["mass"].min(), stars["mass"].max()))

# %% One picture: the gas kept faint, dark matter in blue, stars in red and larger (radius by
# the cube root of the mass).
scene = eb.Scene(ds, width=560, height=560)
scene.transfer_function.opacity_scale = 0.03
scene.particles = True
scene.particle_radius = math.dist(*ds.bounds) / 240  # of the domain's diagonal
scene.particle_radius_by = "mass"
scene.particle_color_by = "type"
scene.particle_color_map = eb.TransferFunction("cool-to-warm", range=(1.0, 2.0))
scene.orbit(35.0, 20.0)
scene.render()
scene.save(out / "particles-cosmic.png")
print("wrote", out / "particles-cosmic.png")
