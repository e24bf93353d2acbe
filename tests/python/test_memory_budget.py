"""exabricks.load(..., memory_budget=...): a step larger than the budget is held in parts; its
first picture's choices, its picture, its samples and its info equal the whole step's."""

import re
import subprocess

import numpy as np
import pytest

import exabricks


@pytest.fixture(scope="module")
def step(tmp_path_factory):
    from conftest import CLI
    import os
    if not os.path.exists(CLI):
        pytest.skip("the exabricks command is not built at %s (set EXABRICKS)" % CLI)
    path = tmp_path_factory.mktemp("budget") / "c.cells"
    subprocess.run([CLI, "-q", "generate", "-s", "cosmic", "-n", "700000", "-o", str(path)], check=True)
    return str(path)


def in_parts(path):
    """The step held whole, and in a few parts: the budget comes down from 64 MiB above the
    smallest that works (which the error of a budget too small names) until the step no longer
    fits whole."""
    whole = exabricks.load(path)
    with pytest.raises(Exception, match="the smallest budget that works is") as refused:
        exabricks.load(path, memory_budget="1M")
    smallest = int(re.search(r"the smallest budget that works is .*?\(--memory-budget (\d+)M\)",
                             str(refused.value)).group(1))
    for extra in range(64, -1, -8):
        parted = exabricks.load(path, memory_budget="%dM" % (smallest + extra))
        if parted.memory is not None:
            return whole, parted
    pytest.fail("no budget above %dM held the step in parts" % smallest)


def test_a_step_in_parts_draws_the_whole_steps_picture(step):
    whole, parted = in_parts(step)
    assert parted.memory is not None and parted.memory["parts"] > 1, parted.memory
    assert whole.memory is None
    assert parted.cells == whole.cells and parted.bounds == whole.bounds and parted.fields == whole.fields
    a, b = exabricks.Scene(whole), exabricks.Scene(parted)
    # The defaults count every part: the same transfer function and notes.
    assert a.transfer_function.to_dict() == b.transfer_function.to_dict()
    assert a.notes == b.notes
    b.camera = a.camera
    one, parts = a.render(96, 80), b.render(96, 80)
    d = np.abs(one - parts) * 255
    assert d.mean() <= 0.5 and (d <= 2).mean() >= 0.999, (d.mean(), d.max())
    assert b.stats()["parts"] == parted.memory["parts"]
    # NAME.cells holds no coarse levels: drafts come from every cell merged into cubes, without
    # reading a part.
    read = b.stats()["parts_read"]
    draft = b.render_draft(96, 80)
    assert draft.shape[2] == 4 and draft[..., 3].max() > 0
    assert b.stats()["drafts"] == "every cell merged" and b.stats()["parts_read"] == read


def test_a_step_in_parts_samples_and_describes_the_whole_step(step):
    whole, parted = in_parts(step)
    points = np.random.RandomState(4).uniform(-0.05, 1.05, (2000, 3)) * np.array(whole.bounds[1])
    va, ga = whole.sample(points)
    vb, gb = parted.sample(points)
    # The same cells in each part's own bricks: equal up to the order of the float sums.
    assert np.array_equal(np.isnan(va), np.isnan(vb))
    ok = ~np.isnan(va)
    assert np.allclose(va[ok], vb[ok], rtol=1e-5, atol=0) and np.allclose(ga[ok], gb[ok], rtol=1e-4, atol=1e-9)
    a, b = whole.info(), parted.info()
    assert a["cells"] == b["cells"] and a["fields"] == b["fields"] and a["bounds"] == b["bounds"]
    assert [(l["level"], l["cells"]) for l in a["levels"]] == [(l["level"], l["cells"]) for l in b["levels"]]
    assert b["memory"]["parts"] > 1


def test_bad_budgets_are_refused(step):
    for bad in ("lots", "0", "-2G"):
        with pytest.raises(Exception, match="not a size"):
            exabricks.load(step, memory_budget=bad)


def test_a_plotfile_in_parts_drafts_from_its_coarse_levels():
    # An AMReX plotfile reads its coarse levels alone: under a budget that holds them beside the
    # parts, drafts come from them without reading a part, and the render from every level equals
    # the whole step's.
    import os
    from pathlib import Path
    data = Path(os.environ.get("EXABRICKS_DATA", Path(__file__).resolve().parents[3] / "shared" / "data"))
    drop = data / "amrex" / "advection_3d" / "plt_drop"
    if not drop.exists():
        pytest.skip("shared sample %s is absent (set EXABRICKS_DATA to the folder of shared samples)" % drop)
    with pytest.raises(Exception, match="with the coarse levels a Scene holds for drafts") as refused:
        exabricks.load(drop, memory_budget="1M")
    text = str(refused.value)
    smallest = int(text.split("the smallest budget that works is")[1].split("(--memory-budget ")[1].split("M)")[0])
    whole_budget = int(text.split("held whole: --memory-budget ")[1].split("M)")[0])
    parted = exabricks.load(drop, memory_budget="%dM" % (smallest + (whole_budget - smallest) * 2 // 5))
    assert parted.memory is not None and parted.memory["parts"] > 1, parted.memory
    whole = exabricks.load(drop)
    a, b = exabricks.Scene(whole), exabricks.Scene(parted)
    assert a.transfer_function.to_dict() == b.transfer_function.to_dict()
    b.camera = a.camera
    read = b.stats().get("parts_read", 0)
    draft = b.render_draft(96, 80)
    assert draft.shape[2] == 4 and draft[..., 3].max() > 0
    assert b.stats()["drafts"] == "coarse levels" and b.stats()["parts_read"] == read
    one, parts = a.render(96, 80), b.render(96, 80)
    d = np.abs(one - parts) * 255
    assert d.mean() <= 0.5 and (d <= 2).mean() >= 0.999, (d.mean(), d.max())
