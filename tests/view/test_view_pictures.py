"""Pictures saved by the viewer at publication size, through its API: the file is the command
line's render of the same scene at that size (8- and 16-bit PNG byte for byte), named after the
dataset, field and size, served only by the id the server made; a cancelled picture leaves no
file; bad requests are refused."""
import json
import re
import subprocess
import time

from test_view_api import small_scene


def make_picture(v, body, timeout=120):
    p = v.json("POST", "/api/picture", body)
    deadline = time.time() + timeout
    while p["state"] == "rendering" and time.time() < deadline:
        time.sleep(0.1)
        p = v.json("GET", "/api/picture?id=" + p["id"])
    return p


def test_a_picture_is_the_command_lines_render_at_that_size(start_viewer, cli, tmp_path):
    v = start_viewer()
    scene = small_scene(v)
    for fmt, extra in (("png", []), ("png16", ["--bits", "16"])):
        p = make_picture(v, {"scene": scene, "width": 96, "height": 64, "spp": 4, "format": fmt})
        assert p["state"] == "done", p
        assert p["done"] == p["tiles"] and p["passes"] == 4
        assert re.fullmatch(r"[A-Za-z0-9._-]+-scalar-96x64\.png", p["name"]), p["name"]
        status, data, headers = v.request("GET", p["file"])
        assert status == 200 and p["name"] in headers.get("Content-Disposition", "")
        doc = dict(scene, frame=dict(scene["frame"], width=96, height=64, samples_per_pixel=4))
        scene_file = tmp_path / ("scene-" + fmt + ".json")
        scene_file.write_text(json.dumps(doc))
        out = tmp_path / ("cli-" + fmt + ".png")
        subprocess.run([cli, "render", "--scene", str(scene_file), "-o", str(out)] + extra, check=True,
                       capture_output=True)
        assert data == out.read_bytes(), fmt
        assert data[24] == (16 if fmt == "png16" else 8)  # the IHDR's bit depth
    exr = make_picture(v, {"scene": scene, "width": 32, "height": 24, "spp": 1, "format": "exr"})
    assert exr["state"] == "done" and exr["name"].endswith("-32x24.exr")
    status, data, _ = v.request("GET", exr["file"])
    assert status == 200 and data[:4] == b"\x76\x2f\x31\x01"
    assert v.alive()


def test_a_cancelled_picture_stops_and_leaves_no_file(start_viewer):
    v = start_viewer()
    scene = small_scene(v)
    p = v.json("POST", "/api/picture", {"scene": scene, "width": 4096, "height": 4096, "spp": 1024, "format": "png"})
    status, data, _ = v.request("POST", "/api/picture", {"scene": scene, "width": 8, "height": 8, "spp": 1,
                                                         "format": "png"})
    assert status == 409 and b"already being rendered" in data
    v.json("POST", "/api/picture/cancel", {"id": p["id"]})
    deadline = time.time() + 60
    while p["state"] == "rendering" and time.time() < deadline:
        time.sleep(0.1)
        p = v.json("GET", "/api/picture?id=" + p["id"])
    assert p["state"] == "cancelled", p
    status, data, _ = v.request("GET", "/api/picture/file?id=" + p["id"])
    assert status == 409 and b"cancelled" in data
    assert v.request("GET", "/api/picture/file?id=" + "0" * 24)[0] == 404
    assert v.alive()


def test_bad_picture_requests_are_refused(start_viewer):
    v = start_viewer()
    scene = small_scene(v)
    good = {"scene": scene, "width": 16, "height": 16, "spp": 1, "format": "png"}
    for body, words in [
        (dict(good, format="gif"), b"choose from: png, png16, exr, pfm"),
        (dict(good, width=5000), b"outside 1..4096"),
        (dict(good, spp=0), b"samples_per_pixel"),
        (dict(good, path="/tmp/x.png"), b"unknown key 'path'"),
        ({"width": 16}, b"must be an object with a"),
    ]:
        status, data, _ = v.request("POST", "/api/picture", body)
        assert status == 400 and words in data, (body.get("format"), status, data[:300])
    assert v.request("POST", "/api/picture", good, token=False)[0] == 403
    assert v.request("GET", "/api/picture")[0] == 400
