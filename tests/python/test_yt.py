"""Datasets and scenes converted from yt against yt itself: the units yt reports, and the exposure
of yt's own volume rendering of the same scene."""
import numpy as np
import pytest

import exabricks as eb
from conftest import shared


def import_yt():
    yt = pytest.importorskip("yt", reason="yt is not installed (Debian: python3-yt)")
    yt.set_log_level(50)
    return yt


def test_from_cells_and_from_grids_carry_units():
    corners = np.array([[0, 0, 0], [1, 0, 0]])
    levels = np.array([0, 0])
    ds = eb.from_cells(corners, levels, {"rho": [1.0, 2.0], "T": [3.0, 4.0]}, units={"rho": "g/cm**3"})
    assert ds.units == {"rho": "g/cm**3", "T": ""}
    assert ds.field_units("rho") == "g/cm**3" and ds.field_units("T") == ""
    assert ds.field_label("rho") == "rho [g/cm**3]" and ds.field_label("T") == "T"
    assert [f["units"] for f in ds.info()["fields"]] == ["g/cm**3", ""]
    grid = {"left_edge": [0, 0, 0], "right_edge": [2, 2, 2], "level": 0, "dimensions": [2, 2, 2],
            "a": np.ones((2, 2, 2)), "b": np.zeros((2, 2, 2))}
    assert eb.from_grids([grid], units=["K", "cm/s"]).units == {"a": "K", "b": "cm/s"}
    with pytest.raises(ValueError, match="not among the fields"):
        eb.from_cells(corners, levels, {"rho": [1.0, 2.0]}, units={"nope": "K"})
    with pytest.raises(ValueError, match="1 units given for 2 fields"):
        eb.from_grids([grid], units=["K"])
    with pytest.raises(ValueError, match="unknown field 'nope'"):
        ds.field_units("nope")


def test_from_yt_carries_the_units_yt_reports():
    yt = import_yt()
    data = {"density": (np.full((4, 4, 4), 2.0), "g/cm**3"), "mach": (np.ones((4, 4, 4)), "dimensionless")}
    stream = yt.load_uniform_grid(data, (4, 4, 4), length_unit="cm", bbox=np.array([[0.0, 1.0]] * 3))
    ds = eb.from_yt(stream, [("stream", "density"), ("stream", "mach")])
    assert ds.units == {"density": "g/cm**3", "mach": ""}
    assert ds.field_label() == "density [g/cm**3]"
    # An AMReX plotfile: yt knows the density's units (in code units), not those of volFrac.
    plotfile = yt.load(str(shared("amrex/pele_eb_3d/plt_eb_3d")))
    ds = eb.from_yt(plotfile, [("boxlib", "density"), ("boxlib", "volFrac")])
    grid = plotfile.index.grids[0]
    assert ds.units["density"] == str(grid[("boxlib", "density")].units) == "code_mass/code_length**3"
    assert ds.units["volFrac"] == ""
    assert [f["units"] for f in ds.info()["fields"]] == ["code_mass/code_length**3", ""]


def exposure(image, mask):
    """Mean and 99th percentile of pixel alpha and brightness (mean of R, G, B) over `mask`."""
    brightness = image[..., :3].mean(axis=-1)
    return {"alpha": (image[..., 3][mask].mean(), np.percentile(image[..., 3][mask], 99)),
            "brightness": (brightness[mask].mean(), np.percentile(brightness[mask], 99))}


def yt_render(sc):
    """yt's image as exabricks lays it out: (H, W, 4), row 0 at the top."""
    return np.asarray(sc.render(), dtype=np.float64).swapaxes(0, 1)


def test_a_yt_scene_renders_with_the_exposure_of_yt():
    yt = import_yt()
    ds = yt.load(str(shared("amrex/advection_3d/plt_small")))
    field = ("boxlib", "phi")
    sc = yt.create_scene(ds, field)  # plane-parallel
    source = sc[0]
    source.log_field = False
    # Gaussian layers of increasing alpha; grey opacity, so that yt's image has an alpha channel
    # and integrates emission and absorption as exabricks does.
    ctf = yt.ColorTransferFunction((0.99, 2.0), grey_opacity=True)
    ctf.add_layers(4, w=0.002, colormap="viridis", alpha=[1.0, 2.0, 4.0, 8.0])
    source.transfer_function = ctf
    cam = sc.camera
    cam.resolution = (128, 128)
    cam.set_width(ds.arr([1.6, 1.6, 1.6], "code_length"))
    cam.set_position(ds.arr([2.2, 1.4, 1.7], "code_length"), north_vector=[0, 0, 1])
    cam.set_focus(ds.arr([0.5, 0.5, 0.5], "code_length"))
    want = yt_render(sc)

    scene = eb.Scene.from_yt(sc)
    assert scene.shading == "none" and scene.spp == 8 and scene.camera.orthographic
    assert (scene.width, scene.height) == (128, 128)
    got = scene.render(spp=4)
    mask = (want[..., 3] > 0.01 * want[..., 3].max()) | (got[..., 3] > 0.01 * got[..., 3].max())
    assert 0.2 < mask.mean() < 0.9
    # The same picture: the camera and the data agree pixel by pixel.
    assert np.corrcoef(want[..., 3][mask], got[..., 3][mask])[0, 1] > 0.95
    yt_exposure, eb_exposure = exposure(want, mask), exposure(got, mask)
    for key in ("alpha", "brightness"):
        for w, g in zip(yt_exposure[key], eb_exposure[key]):
            assert g == pytest.approx(w, rel=0.15), (key, yt_exposure, eb_exposure)

    # Without the camera and the dataset the opacity is not yt's: the dataset's default scale
    # makes this scene far more opaque than yt shows it.
    scene.transfer_function = eb.TransferFunction.from_yt(ctf, log=False)
    uncalibrated = exposure(scene.render(spp=4), mask)["alpha"][0]
    assert uncalibrated > 1.3 * yt_exposure["alpha"][0]


def test_yt_default_scene_renders_with_the_exposure_of_yt():
    yt = import_yt()
    ds = yt.load(str(shared("amrex/advection_3d/plt_small")))
    # yt's defaults: a logged field, ten layers of nipy_spectral, opacity per colour channel (its
    # image has no alpha); here through a perspective lens.
    sc = yt.create_scene(ds, ("boxlib", "phi"), lens_type="perspective")
    sc.camera.resolution = (128, 128)
    want = yt_render(sc)
    scene = eb.Scene.from_yt(sc)
    assert not scene.camera.orthographic and scene.transfer_function.log
    got = scene.render(spp=4)
    brightness = lambda img: img[..., :3].mean(axis=-1)
    mask = (brightness(want) > 0.01 * brightness(want).max()) | (brightness(got) > 0.01 * brightness(got).max())
    assert np.corrcoef(brightness(want)[mask], brightness(got)[mask])[0, 1] > 0.9
    # yt absorbs each colour channel by its own emission, exabricks by the opacity: where the
    # optical depth is small they agree; here within 25 %.
    for w, g in zip(exposure(want, mask)["brightness"], exposure(got, mask)["brightness"]):
        assert g == pytest.approx(w, rel=0.25), (exposure(want, mask), exposure(got, mask))


def test_a_scene_made_from_yt_renders_in_the_command_line(tmp_path, cli):
    """A scene converted from yt and saved names what the command line reads: the output's path,
    the file's field name (Enzo's Density, not yt's density) and a range in the file's units (code
    units, not g/cm^3); the command line's picture equals the Python one, and reading the file
    back with the yt dataset gives yt's names and units again."""
    import json
    import subprocess

    import enzo_output
    from PIL import Image

    yt = import_yt()
    pytest.importorskip("h5py", reason="h5py is not installed (Debian: python3-h5py)")
    parameter_file = enzo_output.write(tmp_path / "DD0003")
    ds = yt.load(parameter_file)
    scene = eb.Scene.from_yt(yt.create_scene(ds, ("gas", "density")))
    scene.width, scene.height, scene.spp = 64, 48, 2
    yt_range = scene.transfer_function.range
    path = tmp_path / "s.json"
    scene.save_json(path)
    d = json.loads(path.read_text())
    assert d["input"] == parameter_file
    assert d["layers"][0]["field"] == "Density"
    lo, hi = d["layers"][0]["transfer_function"]["range"]
    assert lo == pytest.approx(yt_range[0] / enzo_output.DENSITY_UNITS, rel=1e-5)
    assert hi == pytest.approx(yt_range[1] / enzo_output.DENSITY_UNITS, rel=1e-5)

    subprocess.run([cli, "-q", "render", "--scene", str(path), "-o", str(tmp_path / "cli.png")], check=True)
    scene.save(str(tmp_path / "py.png"))
    a = np.asarray(Image.open(tmp_path / "cli.png"), dtype=np.float64)
    b = np.asarray(Image.open(tmp_path / "py.png"), dtype=np.float64)
    assert a.shape == b.shape and a[..., :3].max() > 50
    assert np.abs(a - b).mean() < 0.5 and np.abs(a - b).max() <= 2

    again = eb.Scene.from_json(scene.dataset, path)
    assert again.field == "density"
    assert again.transfer_function.range == pytest.approx(yt_range, rel=1e-5)

    # A dataset made beforehand from the same output (its default field, the file's Density in code
    # units) serves yt's scene of ("gas", "density"): the same picture, the range in its units.
    made = eb.from_yt(ds)
    reused = eb.Scene.from_yt(yt.create_scene(ds, ("gas", "density")), dataset=made)
    assert reused.dataset is made and reused.field == "Density"
    assert list(reused.transfer_function.range) == pytest.approx(
        [v / enzo_output.DENSITY_UNITS for v in yt_range], rel=1e-5)
    reused.width, reused.height, reused.spp = 64, 48, 2
    reused.save(str(tmp_path / "reused.png"))
    c = np.asarray(Image.open(tmp_path / "reused.png"), dtype=np.float64)
    assert np.abs(c - b).mean() < 0.5 and np.abs(c - b).max() <= 2
    with pytest.raises(ValueError, match="does not hold"):
        eb.Scene.from_yt(yt.create_scene(ds, ("gas", "number_density")), dataset=made)

    # A field yt derives has no field of the file behind it: the file names no input, and says why.
    derived = eb.Scene.from_yt(yt.create_scene(ds, ("gas", "number_density")))
    with pytest.warns(UserWarning, match="yt derives 'number_density'"):
        text = derived.to_json()
    assert "input" not in json.loads(text)
