"""The Python module against independent truth: brute-force reconstruction, the command line on
the same data, yt's own grids, and the C++ error messages."""
import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import exabricks as eb
from conftest import shared


def two_level_cells(seed=1):
    """An 8^3 block of width-2 cells with one corner refined into width-1 cells; values from a
    smooth function plus noise."""
    rng = np.random.default_rng(seed)
    corners, levels = [], []
    for z in range(0, 16, 2):
        for y in range(0, 16, 2):
            for x in range(0, 16, 2):
                if x < 6 and y < 6 and z < 6:
                    for dz in (0, 1):
                        for dy in (0, 1):
                            for dx in (0, 1):
                                corners.append((x + dx, y + dy, z + dz))
                                levels.append(0)
                else:
                    corners.append((x, y, z))
                    levels.append(1)
    corners = np.array(corners, dtype=np.int32)
    levels = np.array(levels, dtype=np.int32)
    centres = corners + 0.5 * (1 << levels)[:, None]
    values = (np.sin(centres[:, 0] / 3) + centres[:, 1] / 16 + rng.normal(0, 0.05, len(levels))).astype(np.float32)
    return corners, levels, values


def brute_force(corners, levels, values, p):
    """B(p) = sum H v / sum H over every cell, H the product of hats of radius w about the centre."""
    w = (1 << levels).astype(np.float64)
    c = corners + 0.5 * w[:, None]
    h = np.prod(np.clip(1.0 - np.abs(c - p) / w[:, None], 0.0, None), axis=1)
    s = h.sum()
    return np.nan if s == 0 else float((h * values).sum() / s)


def test_from_cells_samples_equal_the_brute_force_basis_sum():
    corners, levels, values = two_level_cells()
    origin, spacing = np.array([-2.0, 5.0, 1.0]), np.array([0.5, 0.25, 2.0])
    ds = eb.from_cells(corners, levels, {"f": values}, origin=origin, spacing=spacing)
    assert ds.cells == len(levels) and ds.fields == ["f"]
    rng = np.random.default_rng(3)
    lattice = rng.uniform(-1.0, 17.0, size=(400, 3))
    got, grad = ds.sample(origin + spacing * lattice)
    want = np.array([brute_force(corners, levels, values.astype(np.float64), p) for p in lattice])
    assert np.array_equal(np.isnan(got), np.isnan(want))
    ok = ~np.isnan(want)
    assert ok.sum() > 300
    np.testing.assert_allclose(got[ok], want[ok], rtol=1e-9, atol=1e-9)
    # Gradients per world unit against central differences of the brute force.
    for p, g in zip(lattice[ok][:40], grad[ok][:40]):
        for a in range(3):
            e = np.zeros(3)
            e[a] = 1e-4
            fp, fm = brute_force(corners, levels, values, p + e), brute_force(corners, levels, values, p - e)
            if not (np.isnan(fp) or np.isnan(fm)):
                assert abs((fp - fm) / 2e-4 / spacing[a] - g[a]) < 2e-3 * (1 + abs(g[a]))


def grids_of(corners, levels, values):
    """The same data as yt-style grids: one coarse grid over everything, one fine grid."""
    coarse = np.zeros((8, 8, 8))
    fine = np.zeros((6, 6, 6))
    for (x, y, z), l, v in zip(corners, levels, values):
        if l == 1:
            coarse[x // 2, y // 2, z // 2] = v
        else:
            fine[x, y, z] = v
    return [
        {"left_edge": [0.0, 0.0, 0.0], "right_edge": [16.0, 16.0, 16.0], "level": 0, "dimensions": [8, 8, 8],
         "density": coarse},
        {"left_edge": [0.0, 0.0, 0.0], "right_edge": [6.0, 6.0, 6.0], "level": 1, "dimensions": [6, 6, 6],
         "density": fine},
    ]


def test_version_is_the_command_lines(cli):
    out = subprocess.run([cli, "--version"], check=True, capture_output=True, text=True).stdout.split()
    assert out == ["exabricks", eb.__version__]


def test_from_grids_equals_from_cells():
    corners, levels, values = two_level_cells()
    a = eb.from_cells(corners, levels, {"density": values})
    b = eb.from_grids(grids_of(corners, levels, values))
    assert a.cells == b.cells
    # Grids are built from their boxes and cells by their own bricks: the same reconstruction,
    # summed over the bricks in another order.
    pts = np.random.default_rng(5).uniform(0, 16, size=(300, 3))
    np.testing.assert_allclose(a.sample(pts)[0], b.sample(pts)[0], rtol=1e-6, atol=1e-7)
    sa, sb = eb.Scene(a, width=48, height=40), eb.Scene(b, width=48, height=40)
    ra, rb = np.asarray(sa.render(), dtype=np.float64), np.asarray(sb.render(), dtype=np.float64)
    scale = 255.0 if ra.max() > 1.5 else 1.0
    assert np.abs(ra - rb).max() <= scale / 255


def test_from_yt_stream_dataset_equals_from_grids():
    yt = pytest.importorskip("yt", reason="yt is not installed (Debian: python3-yt)")
    corners, levels, values = two_level_cells()
    grids = grids_of(corners, levels, values)
    stream = yt.load_amr_grids([dict(g) for g in grids], [8, 8, 8], bbox=np.array([[0, 16], [0, 16], [0, 16]]))
    a = eb.from_yt(stream, [("stream", "density")])
    b = eb.from_grids(grids)
    assert a.cells == b.cells == len(levels)
    pts = np.random.default_rng(2).uniform(0, 16, size=(200, 3))
    np.testing.assert_array_equal(a.sample(pts)[0], b.sample(pts)[0])


def test_from_yt_on_an_amrex_plotfile_equals_the_command_line(cli, tmp_path):
    yt = pytest.importorskip("yt", reason="yt is not installed (Debian: python3-yt)")
    path = shared("amrex/advection_3d/plt_small")
    yt.set_log_level(50)
    ds = yt.load(str(path))
    a = eb.from_yt(ds, [("boxlib", "phi")])
    b = eb.load(path)
    assert a.cells == b.cells == 1036288
    info = b.info()
    assert [l["cells"] for l in a.info()["levels"]] == [l["cells"] for l in info["levels"]]
    lo, hi = np.array(b.bounds[0]), np.array(b.bounds[1])
    np.testing.assert_allclose(a.bounds, b.bounds, rtol=1e-12)
    pts = lo + (hi - lo) * np.random.default_rng(1).uniform(0, 1, size=(500, 3))
    np.testing.assert_allclose(a.sample(pts)[0], b.sample(pts)[0], rtol=1e-6)
    # The same picture as the command line, which wrote it from the same file.
    out = tmp_path / "cli.png"
    subprocess.run([cli, "render", str(path), "-o", str(out), "--size", "96x64"], check=True)
    s = eb.Scene(a, width=96, height=64)
    img = s.render()
    t = eb.Scene(b, width=96, height=64)
    t.save(tmp_path / "py.png")
    assert (tmp_path / "py.png").read_bytes() == out.read_bytes()
    assert np.max(np.abs(img - t.render())) < 2e-3


def test_info_is_the_command_lines_dictionary(cli, tmp_path):
    corners, levels, values = two_level_cells()
    subprocess.run([cli, "generate", "-s", "shells", "-n", "5000", "-o", str(tmp_path / "s.cells")], check=True)
    ds = eb.load(tmp_path / "s.cells")
    want = json.loads(subprocess.run([cli, "info", str(tmp_path / "s.cells"), "--json"], check=True,
                                     capture_output=True, text=True).stdout)
    got = ds.info()
    for d in (want, got):
        d.pop("build_seconds")
    assert got == want


def test_save_and_png_write_the_last_render(cli, tmp_path):
    # render(spp=8) then save(): the eight passes, not a new one-pass render; a change of the scene
    # renders again at the same size and samples; a size given renders that frame.
    subprocess.run([cli, "generate", "-s", "blobs", "-n", "8000", "-o", str(tmp_path / "b.cells")], check=True)
    s = eb.Scene(eb.load(tmp_path / "b.cells"), width=40, height=30)
    assert s.spp == 1
    s.render(spp=8)
    eight = s.image().copy()
    seconds = s.stats()["seconds"]
    s.save(tmp_path / "a.png")
    assert s.stats()["passes"] == 8 and s.stats()["seconds"] == seconds  # nothing rendered again
    assert np.array_equal(s.image(), eight)
    assert s.png()[:8] == b"\x89PNG\r\n\x1a\n" and s.stats()["passes"] == 8
    s.ambient += 0.05
    s.save(tmp_path / "b.png")
    assert s.stats()["passes"] == 8 and s.image().shape == (30, 40, 4)
    s.save(tmp_path / "c.png", 20, 10)
    assert s.image().shape == (10, 20, 4) and s.stats()["passes"] == 1


def test_a_path_traced_render_to_a_noise_target_equals_the_command_line(cli, tmp_path):
    # The command line's default path tracing (denoised, to a noise of 2/255) written as a scene;
    # Python reads it and renders the same picture, each tile stopping where the command line's
    # did, and turning the denoiser off gives another.
    subprocess.run([cli, "generate", "-s", "blobs", "-n", "8000", "-o", str(tmp_path / "b.cells")], check=True)
    run = subprocess.run([cli, "render", str(tmp_path / "b.cells"), "-o", str(tmp_path / "cli.png"), "--size", "48x32",
                          "--integrator", "pathtrace", "--write-scene", str(tmp_path / "s.json"), "--json"],
                         check=True, capture_output=True, text=True)
    measured = json.loads(run.stdout)
    assert measured["noise_target"] == 2 and measured["mean_samples_per_pixel"] < measured["samples_per_pixel"]
    s = eb.Scene.from_json(eb.load(tmp_path / "b.cells"), tmp_path / "s.json")
    assert s.noise_target == 2 and s.spp == 1024 and s.denoise and measured["denoised"]
    s.render()
    s.save(tmp_path / "py.png")
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    s.denoise = False
    s.render()
    s.save(tmp_path / "raw.png")
    assert (tmp_path / "raw.png").read_bytes() != (tmp_path / "cli.png").read_bytes()


def test_render_and_save_equal_the_command_line(cli, tmp_path):
    subprocess.run([cli, "generate", "-s", "blobs", "-n", "8000", "-o", str(tmp_path / "b.cells")], check=True)
    subprocess.run([cli, "render", str(tmp_path / "b.cells"), "-o", str(tmp_path / "cli.png"), "--size", "64x48",
                    "--colormap", "magma", "--iso", "0.4", "--spp", "2", "--write-scene", str(tmp_path / "s.json")],
                   check=True)
    ds = eb.load(tmp_path / "b.cells")
    s = eb.Scene(ds, width=64, height=48, spp=2, iso_values=[0.4])
    s.transfer_function.colormap = "magma"  # the defaults adapted to the data, as --colormap keeps them
    img = s.render()
    assert img.shape == (48, 64, 4) and img.dtype == np.float32
    s.save(tmp_path / "py.png")
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    # A scene written by the command line, read in Python, and one written in Python, read by it.
    t = eb.Scene.from_json(ds, (tmp_path / "s.json").read_text())
    t.save(tmp_path / "from_cli_scene.png")
    assert (tmp_path / "from_cli_scene.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    s.save_json(tmp_path / "py.json")
    subprocess.run([cli, "render", str(tmp_path / "b.cells"), "--scene", str(tmp_path / "py.json"),
                    "-o", str(tmp_path / "cli2.png")], check=True)
    assert (tmp_path / "cli2.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    assert s._repr_png_()[:8] == b"\x89PNG\r\n\x1a\n"


def test_publication_output_equals_the_command_line(cli, tmp_path, monkeypatch):
    """16-bit PNG and OpenEXR from Python are the command line's files byte for byte, and a save
    without a path is named after the dataset, the field and the size."""
    subprocess.run([cli, "generate", "-s", "blobs", "-n", "8000", "-o", str(tmp_path / "b.cells")], check=True)
    for name, extra in (("p16.png", ["--bits", "16", "--alpha"]), ("p.exr", ["--alpha"])):
        subprocess.run([cli, "render", str(tmp_path / "b.cells"), "-o", str(tmp_path / ("cli-" + name)),
                        "--size", "64x48", "--spp", "2", "--write-scene", str(tmp_path / "s.json")] + extra,
                       check=True)
        s = eb.Scene.from_json(eb.load(tmp_path / "b.cells"), (tmp_path / "s.json").read_text())
        written = s.save(tmp_path / name, bits=16 if name.endswith(".png") else 8)
        assert (tmp_path / name).read_bytes() == (tmp_path / ("cli-" + name)).read_bytes(), name
        assert written == str(tmp_path / name)
    monkeypatch.chdir(tmp_path)
    s = eb.Scene(eb.load(tmp_path / "b.cells"), width=32, height=24)
    assert s.save() == "b-scalar-32x24.png"
    assert (tmp_path / "b-scalar-32x24.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(Exception, match="unknown image format"):
        s.save(tmp_path / "x.gif")
    # normalize: the brightest channel reaches 1 (yt's save), the picture's proportions kept.
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    from mpi_checks import read_pfm  # the tests' reader of float images (standard library only)
    plain = np.asarray(read_pfm(s.save(tmp_path / "plain.pfm"))[2])
    bright = np.asarray(read_pfm(s.save(tmp_path / "bright.pfm", normalize=True))[2])
    assert plain.max() < 0.99 and abs(bright.max() - 1.0) < 1e-6
    np.testing.assert_allclose(bright, plain / plain.max(), rtol=1e-5, atol=1e-6)


def test_progressive_passes_equal_one_render():
    ds = eb.load()
    s = eb.Scene(ds, width=40, height=30)
    whole = s.render(spp=4)
    s.ambient = 0.31  # a change the renderer needs no rebuild for still starts the passes over
    assert s.render_progressive(spp=4, passes=1) == 1
    s.ambient = 0.3
    for n in range(1, 5):
        assert s.render_progressive(spp=4, passes=n) == n
    np.testing.assert_array_equal(s.image(), whole)
    assert s.stats()["passes"] == 4


def test_meshes_clipping_and_pick():
    ds = eb.load()
    s = eb.Scene(ds, width=48, height=48)
    (lo, hi) = ds.bounds
    z = lo[2] + 10.0
    verts = np.array([[lo[0] - 10, lo[1] - 10, z], [hi[0] + 10, lo[1] - 10, z], [hi[0] + 10, hi[1] + 10, z],
                      [lo[0] - 10, hi[1] + 10, z]], dtype=np.float32)
    mesh = s.add_mesh(verts, np.array([[0, 1, 2], [0, 2, 3]]), color=(0.2, 0.6, 0.3))
    assert mesh.triangle_count == 2
    hit = s.pick((48.0, 48.0, 200.0), (0.0, 0.0, -1.0))
    assert hit["kind"] == "mesh" and abs(hit["position"][2] - z) < 1e-3
    s.add_clip_plane((48, 48, 48), (1, 0, 0))
    s.ao_rays = 2
    assert s.render().shape == (48, 48, 4)



def test_a_depth_limit_ends_the_rays_like_a_clip_plane():
    ds = eb.load()
    (lo, hi) = ds.bounds
    centre = 0.5 * (np.asarray(lo) + np.asarray(hi))
    s = eb.Scene(ds, width=40, height=30, shading="none", jitter=False)
    s.camera = eb.Camera(centre + np.array([0.0, 0.0, 200.0]), centre, (0, 1, 0), orthographic=True,
                         ortho_height=1.2 * float(np.max(np.asarray(hi) - np.asarray(lo))))
    whole = s.render()
    depth = 200.0  # the plane through the centre, across the view
    limit = np.full((30, 40), depth, dtype=np.float32)
    limit[:, :10] = np.inf  # no limit in the left quarter
    limited = s.render(depth_limit=limit)
    s.add_clip_plane(centre, (0, 0, -1))
    clipped = s.render()
    assert np.abs(limited[:, 10:] - clipped[:, 10:]).max() < 1e-6
    np.testing.assert_array_equal(limited[:, :10], whole[:, :10])
    assert np.abs(limited - whole).max() > 0.05
    # The same along the view direction (a z-buffer's depth), float64 converted.
    s.clip_planes = []
    np.testing.assert_array_equal(s.render(depth_limit=limit.astype(np.float64), depth_limit_planar=True), limited)
    # Progressive passes start over when the limit changes.
    assert s.render_progressive(spp=2, passes=2, depth_limit=limit) == 2
    assert s.render_progressive(spp=2, passes=2, depth_limit=limit + 1) == 2
    assert s.render_progressive(spp=2, passes=1, depth_limit=limit) == 1
    with pytest.raises(ValueError, match=r"depth_limit must be an \(H, W\) = \(30, 40\) array like the image, not \(40, 30\)"):
        s.render(depth_limit=limit.T)
    limit[3, 7] = np.nan
    with pytest.raises(ValueError, match=r"depth limit of pixel \(7, 3\) is nan"):
        s.render(depth_limit=limit)


def test_errors_arrive_with_the_libraries_messages(cli, tmp_path):
    ds = eb.load()
    with pytest.raises(ValueError, match="unknown field 'nope'"):
        ds.sample([[1, 2, 3]], field="nope")
    s = eb.Scene(ds, width=16, height=16)
    s.field = "nope"
    with pytest.raises(ValueError, match="unknown field 'nope'"):
        s.render()
    # The same message as the command line's.
    r = subprocess.run([cli, "sample", "-f", "nope"], input="1 2 3\n", capture_output=True, text=True)
    assert "unknown field 'nope'" in r.stderr
    with pytest.raises(ValueError, match="integer"):
        eb.from_cells(np.zeros((2, 3)), np.zeros(2, dtype=np.int32), {"f": np.zeros(2)})
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        eb.from_cells(np.zeros((2, 2), dtype=np.int32), np.zeros(2, dtype=np.int32), {"f": np.zeros(2)})
    with pytest.raises(ValueError, match="one value per cell"):
        eb.from_cells(np.zeros((2, 3), dtype=np.int32), np.zeros(2, dtype=np.int32), {"f": np.zeros(3)})
    with pytest.raises(ValueError, match="not aligned"):  # a width-2 cell at an odd corner
        eb.from_cells(np.array([[1, 0, 0]], dtype=np.int32), np.array([1], dtype=np.int32), {"f": np.ones(1)})
    with pytest.raises(ValueError, match="finite"):
        eb.from_cells(np.array([[0, 0, 0]], dtype=np.int32), np.array([0], dtype=np.int32), {"f": np.array([np.nan])})
    with pytest.raises(ValueError, match="no such file"):
        eb.load(tmp_path / "missing.cells")
    with pytest.raises(ValueError, match="power-of-two"):
        eb.from_grids([{"left_edge": [0, 0, 0], "right_edge": [3, 3, 3], "level": 0, "dimensions": [1, 1, 1],
                        "f": np.ones((1, 1, 1))},
                       {"left_edge": [0, 0, 0], "right_edge": [1, 1, 1], "level": 1, "dimensions": [1, 1, 1],
                        "f": np.ones((1, 1, 1))}])


def test_a_renderer_keeps_its_dataset_alive():
    corners, levels, values = two_level_cells()
    ds = eb.from_cells(corners, levels, values)
    s = eb.Scene(ds, width=32, height=32)
    first = s.render()
    del ds
    import gc
    gc.collect()
    s.dataset = None  # even the Python reference
    gc.collect()
    np.testing.assert_array_equal(s._renderer.image(), first)
    s.rate = 2.0
    s.render()


def test_rendering_releases_the_gil_and_ctrl_c_cancels():
    ds = eb.load()
    s = eb.Scene(ds, width=1024, height=1024, rate=8.0, early_termination=False)
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(1)
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.time()
    with pytest.raises(KeyboardInterrupt):
        s.render(spp=64)
    elapsed = time.time() - start
    stop.set()
    t.join()
    assert elapsed < 5.0, "cancelled within tiles, not after the frame"
    assert len(ticks) > 20, "another Python thread ran while rendering"
    # The scene still renders afterwards.
    assert s.render(width=16, height=16, spp=1).shape == (16, 16, 4)


def test_transfer_functions_cameras_and_files(tmp_path):
    tf = eb.TransferFunction("inferno", opacity=[(0, 0), (1, 0.5)], range=(0.1, 10), log=True, opacity_scale=0.5)
    assert eb.TransferFunction.from_dict(tf.to_dict()).to_dict() == tf.to_dict()
    # A dictionary without an opacity scale means the library's default, "auto", as a file does.
    assert eb.TransferFunction.from_dict({"colormap": "magma"}).opacity_scale == "auto"
    (tmp_path / "preset.json").write_text(json.dumps([{"Name": "two", "RGBPoints": [0, 0, 0, 1, 5, 1, 0, 0]}]))
    p = eb.TransferFunction.from_file(tmp_path / "preset.json")
    assert p.range is None and p.opacity_scale == "auto"  # rescaled to the data, as ParaView applies it
    assert eb.TransferFunction.from_file(tmp_path / "preset.json", preset_range=True).range == (0.0, 5.0)
    assert "viridis" in eb.colormap_names()
    c = eb.Camera.frame(((0, 0, 0), (1, 1, 1)), 0.0, 0.0, 40.0)
    assert c.position[1] == pytest.approx(0.5) and c.position[0] > 1.0


def test_yt_camera_converts():
    yt = pytest.importorskip("yt", reason="yt is not installed (Debian: python3-yt)")
    corners, levels, values = two_level_cells()
    stream = yt.load_amr_grids(grids_of(corners, levels, values), [8, 8, 8],
                               bbox=np.array([[0, 16], [0, 16], [0, 16]]))
    sc = yt.create_scene(stream, ("stream", "density"))
    cam = eb.Camera.from_yt(sc.camera)
    # A yt ColorTransferFunction: its colours and alpha over its x bounds (log10 of the value).
    ctf = yt.ColorTransferFunction((-1.0, 1.0))
    ctf.add_layers(3, w=0.02, colormap="viridis")
    tf = eb.TransferFunction.from_yt(ctf)
    assert tf.log and tf.range == pytest.approx((0.1, 10.0))
    assert max(a for _, a in tf.opacity) == pytest.approx(1.0)
    assert tf.colormap[0][0] == 0.0 and tf.colormap[-1][0] == 1.0
    assert np.allclose(cam.look_at, sc.camera.focus.d)
    ds = eb.from_yt(stream, [("stream", "density")])
    s = eb.Scene(ds, width=24, height=24)
    s.camera = cam
    assert s.render()[..., 3].max() > 0
    s.transfer_function = eb.TransferFunction.from_yt(ctf, log=False)
    s.render()


def png_size(data):
    """(width, height) of PNG bytes, from their header."""
    assert data[:4] == b"\x89PNG"
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def test_drafts_are_the_views_sized_to_the_budget_at_a_lower_rate():
    s = eb.Scene(eb.load(), width=128, height=96)
    r = s._renderer
    assert r.draft_divisor == 4  # the view's first draft: a quarter of the resolution
    draft = s.render_draft(budget=1e-9)
    assert draft.shape == (24, 32, 4)
    assert r.draft_divisor == 16  # far over a tiny budget: as coarse as drafts go
    # One sample per pixel at half the frame's rate, as a render of that size and rate draws it.
    assert draft[..., 3].max() > 0
    np.testing.assert_array_equal(draft, s.render(32, 24, spp=1, rate=s.rate * 0.5))
    assert not np.array_equal(draft, s.render(32, 24, spp=1))
    draft = s.render_draft(budget=1e-9)
    assert draft.shape == (6, 8, 4)
    np.testing.assert_array_equal(draft, s.render(8, 6, spp=1, rate=s.rate * 0.5))
    s.render_draft(budget=60.0)
    assert r.draft_divisor == 1  # far under a large budget: the next one is full size
    draft = s.render_draft(budget=60.0)
    assert draft.shape == (96, 128, 4)
    np.testing.assert_array_equal(draft, s.render(spp=1, rate=s.rate * 0.5))
    assert png_size(r.draft_png()) == (128, 96)
    # Each next divisor follows the view's rule, hysteresis included: at a budget near the time
    # a draft took, the divisor stays.
    frame = s._frame_json(128, 96, s.spp, s.rate)
    seconds = None
    for budget in (1e-4, 1e-3, 0.0, None, None, 1.0, None):
        budget = seconds if budget is None else budget
        image, divisor, seconds = r.render_draft(frame, budget)
        assert 1 <= divisor <= 16
        assert image.shape == (96 // divisor, 128 // divisor, 4)
        expected = eb._core.next_draft_divisor(divisor, 128, 96, image.shape[0] * image.shape[1], seconds,
                                               budget or 0.035, 16)
        assert r.draft_divisor == expected
    with pytest.raises(Exception, match="budget"):
        s.render_draft(budget=-1.0)


def test_widget_previews_are_the_views_drafts_then_it_refines():
    pytest.importorskip("ipywidgets", reason="ipywidgets is not installed (Debian: python3-ipywidgets)")
    from exabricks.widget import SceneWidget
    s = eb.Scene(eb.load())
    drafts = []
    render_draft = s.render_draft

    def recording(*args, **kwargs):
        draft = render_draft(*args, **kwargs)
        drafts.append(draft.copy())
        return draft

    s.render_draft = recording
    w = SceneWidget(s, 128, 96, budget=1e-9, passes=3)
    # The view's first draft (a quarter), far over its budget: the next is as coarse as drafts go.
    assert [d.shape for d in drafts] == [(24, 32, 4)]
    assert w.preview == 16
    img = w.wait()
    assert img.shape == (96, 128, 4)
    assert w.image.value[:4] == b"\x89PNG"
    assert s.stats()["passes"] == 3
    w.azimuth.value = 120.0
    assert drafts[-1].shape == (6, 8, 4)
    assert png_size(s._renderer.draft_png()) == (8, 6)
    assert w.wait().shape == (96, 128, 4)
    assert s.stats()["passes"] == 3
    np.testing.assert_array_equal(drafts[-1], s.render(8, 6, spp=1, rate=s.rate * 0.5))
    # A large budget: the drafts grow back to the full resolution.
    w.budget = 60.0
    w.azimuth.value = 130.0
    assert drafts[-1].shape == (6, 8, 4) and w.preview == 1
    w.azimuth.value = 140.0
    assert drafts[-1].shape == (96, 128, 4)
    w.wait()
    np.testing.assert_array_equal(drafts[-1], s.render(128, 96, spp=1, rate=s.rate * 0.5))
    w.close()


@pytest.mark.parametrize("script", [
    # A widget refining in its background thread when the interpreter exits.
    "import exabricks as eb\ns = eb.Scene(eb.load())\nw = s.widget(width=512, height=512, passes=64)\n",
    # Any daemon thread rendering when the interpreter exits.
    "import threading, time, exabricks as eb\ns = eb.Scene(eb.load(), width=1024, height=1024)\n"
    "threading.Thread(target=lambda: s.render(spp=64), daemon=True).start()\ntime.sleep(0.3)\n",
])
def test_leaving_the_interpreter_while_rendering_exits_cleanly(script):
    if "widget" in script:
        pytest.importorskip("ipywidgets", reason="ipywidgets is not installed (Debian: python3-ipywidgets)")
    for _ in range(3):
        r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, (r.returncode, r.stderr)
        assert "terminate" not in r.stderr


def test_from_yt_without_fields_takes_the_mesh_field_the_command_line_would():
    yt = pytest.importorskip("yt", reason="yt is not installed (Debian: python3-yt)")
    yt.set_log_level(50)
    # Particles beside the grid: yt lists the particle fields first.
    rng = np.random.default_rng(3)
    n = 50
    data = {"density": (rng.uniform(0.5, 1.5, (8, 8, 8)), "g/cm**3"),
            "particle_position_x": (rng.uniform(0, 1, n), "cm"), "particle_position_y": (rng.uniform(0, 1, n), "cm"),
            "particle_position_z": (rng.uniform(0, 1, n), "cm"), "particle_mass": (np.ones(n), "g")}
    stream = yt.load_uniform_grid(data, (8, 8, 8), length_unit="cm", bbox=np.array([[0.0, 1.0]] * 3))
    assert stream.field_list[0][0] in stream.particle_types  # what the first field used to be
    ds = eb.from_yt(stream)
    assert ds.fields == ["density"] and ds.cells == 512
    # An AMReX plotfile with many fields: the one the command line takes by default.
    path = shared("amrex/pelelm_3lev_3d/example_plt_3d")
    plotfile = yt.load(str(path))
    ds = eb.from_yt(plotfile)
    assert ds.fields == [eb.load(path).default_field] == ["density"]


def test_the_device_path_renders_like_the_cpu():
    ds = eb.load()
    cpu = eb.Scene(ds, width=64, height=48, device="cpu")
    cpu.iso_values = [0.5]
    portable = eb.Scene(ds, width=64, height=48, device="portable")
    portable.iso_values = [0.5]
    a, b = cpu.render(spp=2), portable.render(spp=2)
    assert cpu.device == "cpu" and portable.device == "portable"
    assert np.abs(a - b).max() < 2e-3
    info = ds.info()["device"]
    if info["gpus"] == 0:
        with pytest.raises(Exception, match="the cuda device cannot be used"):
            eb.Scene(ds, device="cuda")
        assert eb.Scene(ds, width=16, height=16).render() is not None  # "auto" falls back to the CPU
