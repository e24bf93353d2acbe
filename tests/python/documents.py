"""Scene documents compared as the tests of every front end compare them: numbers within float32
round-off (the library keeps single-precision values)."""
import pytest


def with_mesh_file(example):
    """The library's example scene (`exabricks keys --example`, which names no file so that it
    renders as written) with a mesh file first among its meshes, as a user's scene may have."""
    assert all("file" not in m for m in example["meshes"])
    example["meshes"].insert(0, {"file": "triangle.ply", "color": [0.25, 0.5, 0.75]})
    return example


def holds(got, want, where="scene", same_keys=False):
    """Every key of `want` is in `got` with an equal value; with `same_keys`, `got` has no others."""
    if isinstance(want, dict):
        assert isinstance(got, dict), (where, got)
        if same_keys:
            assert sorted(got) == sorted(want), (where, sorted(want), sorted(got))
        for k in want:
            assert k in got, (where + "." + k, "missing")
            holds(got[k], want[k], where + "." + k, same_keys)
    elif isinstance(want, list):
        assert isinstance(got, list) and len(got) == len(want), (where, got, want)
        for i, (x, y) in enumerate(zip(got, want)):
            holds(x, y, "%s[%d]" % (where, i), same_keys)
    elif isinstance(want, float) or isinstance(got, float):
        assert got == pytest.approx(want, rel=1e-6, abs=1e-9), (where, got, want)
    else:
        assert got == want, (where, got, want)


def assert_same(a, b, where="scene"):
    """Equal documents: the same keys and values."""
    holds(b, a, where, same_keys=True)
