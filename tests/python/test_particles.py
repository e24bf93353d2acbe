"""Particles through Python: Dataset.particle_species and Dataset.particles against an AMReX
plotfile written here with numpy (independent of the C++ test's writer), the shared Enzo output
against h5py's reading of the same file, and from_yt against the native reader."""
import os

import numpy as np
import pytest

import exabricks
from conftest import shared

ENZO = "particles/enzo_moving7_3d/DD0010/moving7_0010"


def write_plotfile(root, counts, single):
    """A 4^3 plotfile over [0, 2]^3 with one field and a species "tracers": two level-0 grids of
    the given particle counts, real components mass and temp, integer component tag."""
    os.makedirs(root / "Level_0")
    (root / "Header").write_text(
        "HyperCLaw-V1.1\n1\nrho\n3\n0\n0\n0 0 0\n2 2 2\n\n((0,0,0) (3,3,3) (0,0,0))\n0\n0.5 0.5 0.5\n0\n0\n"
        "0 1 0\n0\n0 2\n0 2\n0 2\nLevel_0/Cell\n")
    (root / "Level_0" / "Cell_H").write_text(
        "1\n0\n1\n0\n(1 0\n((0,0,0) (3,3,3) (0,0,0))\n)\n1\nFabOnDisk: Cell_D_00000 0\n")
    (root / "Level_0" / "Cell_D_00000").write_bytes(
        b"FAB ((8, (64 11 52 0 1 12 0 1023)),(8, (8 7 6 5 4 3 2 1)))((0,0,0) (3,3,3) (0,0,0)) 1\n"
        + np.linspace(1, 2, 64).astype("<f8").tobytes())
    species = root / "tracers"
    os.makedirs(species / "Level_0")
    rng = np.random.default_rng(5)
    real = np.float32 if single else np.float64
    expected = {"position": [], "mass": [], "temp": [], "id": [], "cpu": [], "tag": []}
    table, data, start = [], b"", 0
    for n in counts:
        ints = np.zeros((n, 3), np.int32)
        ints[:, 0] = np.arange(start, start + n) + 1
        ints[:, 1] = 3
        ints[:, 2] = rng.integers(-5, 5, n)
        reals = np.zeros((n, 5), real)
        reals[:, :3] = rng.uniform(0, 2, (n, 3))
        reals[:, 3:] = rng.uniform(-1, 1, (n, 2))
        table.append("0 %d %d" % (n, len(data)) if n else "-1 0 0")
        data += ints.tobytes() + reals.tobytes()
        expected["position"].append(reals[:, :3].astype(np.float64))
        expected["mass"].append(reals[:, 3].astype(np.float64))
        expected["temp"].append(reals[:, 4].astype(np.float64))
        expected["id"].append(ints[:, 0])
        expected["cpu"].append(ints[:, 1])
        expected["tag"].append(ints[:, 2])
        start += n
    (species / "Level_0" / "DATA_00000").write_bytes(data)
    version = "Version_Two_Dot_Zero_" + ("single" if single else "double")
    (species / "Header").write_text("%s\n3\n2\nmass\ntemp\n1\ntag\n0\n%d\n%d\n0\n%d\n%s\n" % (
        version, sum(counts), sum(counts) + 1, len(counts), "\n".join(table)))
    return {k: np.concatenate(v) for k, v in expected.items()}


@pytest.mark.parametrize("single", [False, True])
def test_amrex_particles_arrive_exactly(tmp_path, single):
    root = tmp_path / "plt"
    expected = write_plotfile(root, [7, 0, 5], single)
    ds = exabricks.load(str(root))
    (info,) = ds.particle_species
    assert info == {"name": "tracers", "count": 12, "attributes": ["id", "cpu", "tag", "mass", "temp"],
                    "precision": "single" if single else "double"}
    p = ds.particles("tracers")
    assert p["position"].shape == (12, 3) and p["position"].dtype == np.float64
    for key, value in expected.items():
        assert np.array_equal(p[key], value), key
    assert p["id"].dtype == np.int64 and p["mass"].dtype == np.float64
    assert list(ds.particles()) == ["tracers"]
    with pytest.raises(Exception, match="no particle species 'gas'"):
        ds.particles("gas")


def test_datasets_without_particles_have_none():
    ds = exabricks.load()
    assert ds.particle_species == [] and ds.particles() == {}
    with pytest.raises(ValueError, match="holds no particles"):
        ds.particles("dark_matter")


def test_shared_enzo_particles_equal_h5py():
    h5py = pytest.importorskip("h5py")
    path = shared(ENZO)
    ds = exabricks.load(str(path))
    assert [(s["name"], s["count"]) for s in ds.particle_species] == [("dark_matter", 9233)]
    p = ds.particles("dark_matter")
    with h5py.File(str(path) + ".cpu0000", "r") as f:
        groups = [f[g] for g in sorted(f) if "particle_position_x" in f[g]]
        position = np.concatenate([np.stack([g["particle_position_" + a][:] for a in "xyz"], 1) for g in groups])
        index = np.concatenate([g["particle_index"][:] for g in groups])
        mass = np.concatenate([g["particle_mass"][:] for g in groups])
    assert np.array_equal(p["position"], position)
    assert np.array_equal(p["index"], index)
    assert np.array_equal(p["mass"], mass.astype(np.float64))


def test_from_yt_particles_equal_the_native_reader():
    yt = pytest.importorskip("yt")
    path = shared(ENZO)
    ds = yt.load(str(path))
    made = exabricks.from_yt(ds)
    species = made.particle_species
    assert [s["count"] for s in species] == [9233]
    (name,) = [s["name"] for s in species]
    theirs = made.particles(name)
    ours = exabricks.load(str(path)).particles("dark_matter")
    order, mine = np.argsort(theirs["index"]), np.argsort(ours["index"])
    assert np.allclose(theirs["position"][order], ours["position"][mine], rtol=0, atol=1e-12)


def test_python_renders_particles_as_the_command_line_does(tmp_path, cli):
    import subprocess
    from PIL import Image
    path = shared(ENZO)
    ds = exabricks.load(str(path))
    s = exabricks.Scene(ds, particles=True, particle_radius=0.006, particle_color_by="mass")
    s.particle_color_map = exabricks.TransferFunction("viridis", log=True)
    with_particles = s.render(96, 96)
    s.particles = False
    without = s.render(96, 96)
    assert np.abs(with_particles - without).max() > 0.1  # the spheres show
    s.particles = True
    s.save_json(tmp_path / "scene.json")
    assert '"color_by": "mass"' in (tmp_path / "scene.json").read_text()
    out = tmp_path / "cli.png"
    subprocess.run([cli, "-q", "render", "--scene", str(tmp_path / "scene.json"), "--size", "96x96", "-o", str(out)],
                   check=True)
    s.render(96, 96)
    s.save(tmp_path / "py.png")
    a = np.asarray(Image.open(out).convert("RGBA")).astype(float)
    b = np.asarray(Image.open(tmp_path / "py.png").convert("RGBA")).astype(float)
    assert np.abs(a - b).mean() <= 0.5 and (np.abs(a - b) <= 2).mean() >= 0.999
    again = exabricks.Scene.from_json(ds, str(tmp_path / "scene.json"))
    assert again.particles and again.particle_color_by == "mass" and again.particle_radius == pytest.approx(0.006)
    with pytest.raises(Exception, match="no particle attribute 'nope'"):
        s.particle_color_by = "nope"
        s.render(32, 32)


def test_from_yt_particles_render(tmp_path):
    yt = pytest.importorskip("yt")
    ds = exabricks.from_yt(yt.load(str(shared(ENZO))))
    s = exabricks.Scene(ds, particles=True, particle_radius=0.006)
    assert np.abs(s.render(64, 64)[..., 3]).max() > 0.5
