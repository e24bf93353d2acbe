import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
CLI = os.environ.get("EXABRICKS", str(ROOT / "build" / "exabricks"))
DATA = pathlib.Path(os.environ.get("EXABRICKS_DATA", ROOT.parent / "shared" / "data"))


@pytest.fixture
def cli():
    if not os.path.exists(CLI):
        pytest.skip("the exabricks command is not built at %s (set EXABRICKS)" % CLI)
    return CLI


def shared(relative):
    path = DATA / relative
    if not path.exists():
        pytest.skip("shared sample %s is absent (set EXABRICKS_DATA to the folder of shared samples)" % path)
    return path
