"""exabricks.Series: a tiny series made with `exabricks generate --steps`, its steps and range,
frames equal to `exabricks movie`'s for the same scene, and movie() writing its output."""
import os
import shutil
import subprocess

import numpy as np
import pytest

exabricks = pytest.importorskip("exabricks")

LOOK = ["--size", "64x48", "--linear", "--opacity", "0,0,1,0.6", "--frame-all", "--azimuth", "40"]


@pytest.fixture(scope="module")
def series_dir(tmp_path_factory):
    from conftest import CLI
    if not os.path.exists(CLI):
        pytest.skip("the exabricks command is not built at %s (set EXABRICKS)" % CLI)
    d = tmp_path_factory.mktemp("series")
    subprocess.run([CLI, "-q", "generate", "-n", "20000", "--steps", "3", "-o", str(d / "moving" / "blobs.cells")],
                   check=True)
    subprocess.run([CLI, "-q", "movie", str(d / "moving"), "-o", str(d / "frames")] + LOOK, check=True)
    return d


def srgb8(linear):
    """Linear values (composited over black) as 8-bit sRGB, as the PNG files hold them."""
    c = np.clip(linear, 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.round(s * 255.0)


def test_steps_names_and_range(series_dir):
    s = exabricks.Series(series_dir / "moving")
    assert len(s) == 3
    assert s.names == ["blobs_0000.cells", "blobs_0001.cells", "blobs_0002.cells"]
    assert exabricks.Series(str(series_dir / "moving" / "blobs_*.cells")).steps == s.steps
    lo, hi = s.range()
    field = s.dataset(0).default_field
    values = [exabricks.Series(p).range(field) for p in s.steps]
    assert lo == min(v[0] for v in values) and hi == max(v[1] for v in values)
    assert lo < hi


def test_frames_equal_the_movie_command(series_dir):
    s = exabricks.Series(series_dir / "moving")
    scene_file = series_dir / "frames" / "scene.json"
    for k in range(3):
        image = s.render(k, scene_file)
        assert image.shape == (48, 64, 4) and image.dtype == np.float32
        frame = exabricks.read_png(series_dir / "frames" / ("frame_%05d.png" % k))
        assert np.abs(srgb8(image[..., :3]) - srgb8(frame[..., :3])).max() <= 1.0, k
    assert s.stats()["steps_loaded"] == 3


def test_render_with_a_scene_object_and_global_range(series_dir):
    s = exabricks.Series(series_dir / "moving")
    scene = s.scene(0, width=32, height=24)
    a = s.render("blobs_0002.cells", scene, range="global")
    b = s.render(2, scene, range="per-step")
    assert a.shape == (24, 32, 4) and b.shape == (24, 32, 4)
    assert a[..., 3].max() > 0
    with pytest.raises(IndexError):
        s.render(3, scene)
    with pytest.raises(KeyError):
        s.render("nothing", scene)


def test_movie_writes_its_output(series_dir, tmp_path):
    s = exabricks.Series(series_dir / "moving")
    scene = s.scene(0, width=32, height=24)
    folder = s.movie(tmp_path / "frames_only", scene, frames_per_step=2)
    assert sorted(os.listdir(folder)) == ["frame_%05d.png" % i for i in range(6)]
    spread = s.movie(tmp_path / "spread", scene, frames=4)
    assert len(os.listdir(spread)) == 4
    out = tmp_path / "movie.mp4"
    if shutil.which("ffmpeg"):
        assert s.movie(out, scene, fps=6) == str(out)
        assert out.stat().st_size > 0
    else:
        with pytest.warns(UserWarning, match="ffmpeg"):
            assert s.movie(out, scene, fps=6) == str(out) + ".frames"
        assert len(os.listdir(str(out) + ".frames")) == 3
    with pytest.raises(ValueError, match="write .mp4"):
        s.movie(tmp_path / "movie.avi", scene)


def test_bad_input_names_the_file(tmp_path):
    with pytest.raises(Exception, match="nothing_"):
        exabricks.Series(str(tmp_path / "nothing_*.cells"))


def test_frames_carry_the_legends_as_the_movie_command_draws_them(series_dir, tmp_path):
    from conftest import CLI
    subprocess.run([CLI, "-q", "movie", str(series_dir / "moving"), "-o", str(tmp_path / "frames"), "--colorbar",
                    "--annotate"] + LOOK, check=True)
    s = exabricks.Series(series_dir / "moving")
    scene_file = tmp_path / "frames" / "scene.json"
    plain = s.render(1, series_dir / "frames" / "scene.json")
    for k in range(3):
        image = s.render(k, scene_file)
        frame = exabricks.read_png(tmp_path / "frames" / ("frame_%05d.png" % k))
        assert np.abs(srgb8(image[..., :3]) - srgb8(frame[..., :3])).max() <= 1.0, k
    assert np.abs(srgb8(s.render(1, scene_file)[..., :3]) - srgb8(plain[..., :3])).max() > 100  # they show
    written = s.write_frames(tmp_path / "py_frames", scene_file)
    for k, path in enumerate(written):
        assert open(path, "rb").read() == open(tmp_path / "frames" / ("frame_%05d.png" % k), "rb").read(), k
