"""The peer comparisons (bench/peers) cannot drift: their exabricks command lines give every setting
that decides the picture, so that the first picture's automatic choices (a logarithmic map for
data over many decades, a transparent background value, exposure) cannot change it; the check of
those settings notices a command line that leaves one to them; two pictures are compared before a
ratio is called valid; and a dataset that cannot be compared is refused."""
import json
import math
import subprocess
import sys

import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "bench" / "peers"))
import peer_common  # noqa: E402


@pytest.fixture
def decades(cli, tmp_path):
    """A cosmology-like step over many decades with a background value: every automatic choice
    of the first picture applies to it."""
    path = tmp_path / "c.cells"
    subprocess.run([cli, "-q", "generate", "-s", "cosmic", "-n", "60000", "-o", str(path)], check=True)
    info = json.loads(subprocess.run([cli, "-q", "info", str(path), "--json"], check=True, capture_output=True,
                                     text=True).stdout)
    return path, info


def comparison_arguments(path, info, shading):
    field = info["fields"][0]
    lower, upper = info["bounds"]["world"]["lower"], info["bounds"]["world"]["upper"]
    pos, look, up, _ = peer_common.camera(lower, upper, 30.0, 25.0, 40.0)
    value_range = (field["range"]["min"], field["range"]["max"])
    return peer_common.pinned_arguments(str(path), field["name"], 64, pos, look, up, 40.0, value_range, 0.02,
                                        shading), value_range


@pytest.mark.parametrize("shading", ["smooth", "none"])
def test_the_comparisons_command_lines_pin_the_picture(cli, decades, shading):
    path, info = decades
    arguments, value_range = comparison_arguments(path, info, shading)
    assert info["fields"][0]["range"]["max"] / max(info["fields"][0]["range"]["min"], 1e-300) > 1e3
    scene = peer_common.check_pinned(cli, arguments, value_range, 0.02, shading)
    tf = scene["layers"][0]["transfer_function"]
    assert not tf["log"] and tf["opacity"] == [[0.0, 0.0], [1.0, 1.0]]
    assert math.isclose(tf["opacity_scale"], 0.02, rel_tol=1e-6)


def test_a_command_line_that_leaves_a_choice_to_the_defaults_is_noticed(cli, decades):
    path, info = decades
    arguments, value_range = comparison_arguments(path, info, "smooth")
    for flag, values in (("--linear", 0), ("--opacity", 1)):
        loose = list(arguments)
        i = loose.index(flag)
        del loose[i:i + 1 + values]
        with pytest.raises(SystemExit) as e:
            peer_common.check_pinned(cli, loose, value_range, 0.02, "smooth")
        assert "would not draw the pinned picture" in str(e.value), (flag, e.value)


def test_pictures_are_compared_before_a_ratio_is_valid():
    np = pytest.importorskip("numpy")
    rng = np.random.default_rng(3)
    y, x = np.mgrid[0:64, 0:64] / 64.0
    blob = np.exp(-((x - 0.4) ** 2 + (y - 0.5) ** 2) / 0.02)[..., None] * np.array([0.2, 0.8, 0.5])
    same = peer_common.agreement(blob, blob)
    assert same["ssim"] > 0.999 and same["mean_difference_255"] == 0 and peer_common.alike(same)
    noisy = peer_common.agreement(blob, np.clip(blob + rng.normal(0, 0.004, blob.shape), 0, 1))
    assert peer_common.alike(noisy), noisy
    filled = np.full_like(blob, 0.3)  # a filled cube where the other shows a blob
    assert not peer_common.alike(peer_common.agreement(blob, filled))
    elsewhere = np.roll(blob, 20, axis=1)
    assert not peer_common.alike(peer_common.agreement(blob, elsewhere))


def test_a_dataset_that_cannot_be_compared_is_refused(decades):
    _, info = decades
    with pytest.raises(SystemExit) as e:
        peer_common.require_comparable(info, "no_such_field", "c.cells")
    assert "has no field 'no_such_field'" in str(e.value)
    flat = json.loads(json.dumps(info))
    flat["bounds"]["lattice"]["upper"][2] = flat["bounds"]["lattice"]["lower"][2] + 1
    with pytest.raises(SystemExit) as e:
        peer_common.require_comparable(flat, info["fields"][0]["name"], "slab")
    assert "not a 3-D volume" in str(e.value)


def test_the_comparison_scripts_refuse_a_field_they_cannot_compare(cli, decades):
    path, _ = decades
    for script in ("compare_yt.py", "compare_paraview.py"):
        r = subprocess.run([sys.executable, str(ROOT / "bench" / "peers" / script), cli, str(path), "--field",
                            "no_such_field", "--out", str(path.parent / script)], capture_output=True, text=True)
        assert r.returncode != 0 and "has no field 'no_such_field'" in r.stderr, (script, r.returncode, r.stderr)
