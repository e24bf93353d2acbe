"""Starts `exabricks view` on a free loopback port and talks to it over HTTP."""
import http.client
import json
import os
import pathlib
import signal
import struct
import subprocess
import sys
import time
import urllib.parse

import pytest

# The tests compare scene documents as the Python tests do (tests/python/documents.py).
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "python"))
from documents import with_mesh_file  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
CLI = os.environ.get("EXABRICKS", str(ROOT / "build" / "exabricks"))
ARTIFACTS = pathlib.Path(os.environ.get("EXABRICKS_ARTIFACTS", ROOT / "build" / "test-artifacts"))


class Viewer:
    """A running viewer: its process, address and token, with helpers for the API."""

    def __init__(self, args, tmp_path):
        if not os.path.exists(CLI):
            pytest.skip("the exabricks command is not built at %s (set EXABRICKS)" % CLI)
        self.stderr_path = tmp_path / "viewer.stderr"
        self.stderr = open(self.stderr_path, "w")
        self.proc = subprocess.Popen([CLI, "view", "--port", "0"] + list(args), stdout=subprocess.PIPE,
                                     stderr=self.stderr, text=True)
        line = self.proc.stdout.readline().strip()
        if not line.startswith("http://"):
            self.proc.kill()
            raise AssertionError("the viewer printed no address: %r\n%s" % (line, self.stderr_path.read_text()))
        self.url = line
        parsed = urllib.parse.urlparse(line)
        self.host, self.port = parsed.hostname, parsed.port
        self.token = urllib.parse.parse_qs(parsed.query)["token"][0]

    def request(self, method, path, body=None, token=True, headers=None, timeout=30):
        conn = http.client.HTTPConnection(self.host, self.port, timeout=timeout)
        h = dict(headers or {})
        if token is True:
            h["X-Exabricks-Token"] = self.token
        elif token:
            h["X-Exabricks-Token"] = token
        if isinstance(body, (dict, list)):
            body = json.dumps(body)
            h["Content-Type"] = "application/json"
        conn.request(method, path, body=body, headers=h)
        r = conn.getresponse()
        data = r.read()
        conn.close()
        return r.status, data, dict(r.getheaders())

    def json(self, method, path, body=None, expect=200):
        status, data, _ = self.request(method, path, body)
        assert status == expect, (status, data[:500])
        return json.loads(data)

    def info(self):
        return self.json("GET", "/api/info")

    def render(self, scene, interactive=False):
        return self.json("POST", "/api/render", {"scene": scene, "interactive": interactive})["request"]

    def stream(self, timeout=120):
        """Yields (header, jpeg bytes) of the frame stream."""
        conn = http.client.HTTPConnection(self.host, self.port, timeout=timeout)
        conn.request("GET", "/api/stream", headers={"X-Exabricks-Token": self.token})
        r = conn.getresponse()
        assert r.status == 200, r.status
        try:
            while True:
                n = struct.unpack("<I", r.read(4))[0]
                header = json.loads(r.read(n))
                m = struct.unpack("<I", r.read(4))[0]
                image = r.read(m)
                yield header, image
        finally:
            conn.close()

    def wait_final(self, request, timeout=120):
        """Frames up to the final one of `request` (asserts none is older than it once it began)."""
        frames = []
        deadline = time.time() + timeout
        for header, image in self.stream(timeout):
            assert time.time() < deadline, "no final frame within %s s" % timeout
            if header.get("keepalive"):
                continue
            assert "error" not in header, header
            frames.append(header)
            if header["request"] == request and header["final"]:
                return frames, image

    def alive(self):
        status, _, _ = self.request("GET", "/api/info")
        return status == 200 and self.proc.poll() is None

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.stderr.close()
        return self.proc.returncode


@pytest.fixture
def start_viewer(tmp_path):
    started = []

    def start(*args):
        v = Viewer(args, tmp_path)
        started.append(v)
        return v

    yield start
    for v in started:
        v.stop()


@pytest.fixture
def cli():
    if not os.path.exists(CLI):
        pytest.skip("the exabricks command is not built at %s (set EXABRICKS)" % CLI)
    return CLI


@pytest.fixture
def artifacts():
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    return ARTIFACTS


@pytest.fixture
def flow_dataset(cli, tmp_path):
    """The default dataset written as files (flow.cells) with a third field, 'velocity', of both
    signs and large values (about -1.3e7 to 2.5e7): what a log mapping or a narrow box cannot show."""
    import numpy as np

    folder = tmp_path / "data"
    folder.mkdir()
    path = folder / "flow.cells"
    subprocess.run([cli, "-q", "convert", "-o", str(path)], check=True, capture_output=True)
    scalar = np.fromfile(folder / "flow.scalars", dtype="<f4")
    ((scalar - 0.5) * 2.6e7).astype("<f4").tofile(folder / "flow.velocity.scalars")
    return path


@pytest.fixture
def series_dataset(cli, tmp_path):
    """A tiny time series of three steps (s_0000.cells onwards), as the movie tests make it; the
    glob pattern that names it."""
    folder = tmp_path / "run"
    folder.mkdir()
    subprocess.run([cli, "-q", "generate", "--steps", "3", "-n", "20000", "-o", str(folder / "s.cells")], check=True,
                   capture_output=True)
    return str(folder / "s_*.cells")


@pytest.fixture
def scene_example(cli):
    """The library's example scene (`exabricks keys --example`: every structured key of scene
    files at its example value) as the viewer takes it: without its mesh file (the viewer reads
    no file a request names) and its input (the viewer renders the dataset it serves). Returns
    (that document, the whole example)."""
    example = json.loads(subprocess.run([cli, "keys", "--example"], check=True, capture_output=True,
                                        text=True).stdout)
    example = with_mesh_file(example)
    uploadable = json.loads(json.dumps(example))
    uploadable["meshes"] = [m for m in uploadable["meshes"] if "file" not in m]
    assert uploadable["meshes"], "the example has no inline mesh"
    del uploadable["input"]
    return uploadable, example
