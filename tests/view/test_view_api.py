"""The viewer's HTTP API over loopback: rendering equals the command line, access needs the token,
bad requests get a 4xx and leave the server serving, newer requests supersede older ones."""
import json
import signal
import socket
import subprocess
import time

import pytest
from documents import holds


def small_scene(viewer, **frame):
    doc = viewer.info()["document"]
    doc["frame"].update({"width": 72, "height": 56, "samples_per_pixel": 3})
    doc["frame"].update(frame)
    return doc


def cli_png(cli, tmp_path, doc, name="cli"):
    scene = tmp_path / (name + ".json")
    scene.write_text(json.dumps(doc))
    out = tmp_path / (name + ".png")
    subprocess.run([cli, "render", "--scene", str(scene), "-o", str(out)], check=True, capture_output=True)
    return out.read_bytes()


def test_binds_to_localhost_and_prints_the_address(start_viewer):
    v = start_viewer()
    assert v.host == "127.0.0.1"
    assert len(v.token) >= 32
    assert v.alive()


def test_rendering_through_the_api_equals_the_command_line(start_viewer, cli, tmp_path):
    v = start_viewer()
    doc = small_scene(v)
    values = [f["range"] for f in v.info()["fields"] if f["name"] == "scalar"][0]
    doc["iso"] = {"values": [values[0] + 0.4 * (values[1] - values[0])], "colors": [[0.9, 0.6, 0.3]]}
    doc["clip"] = {"planes": [{"point": [48, 48, 40], "normal": [0, 0, 1]}]}
    doc["layers"][0]["transfer_function"]["opacity"] = [[0, 0], [0.5, 0.1], [1, 0.9]]
    request = v.render(doc)
    frames, jpeg = v.wait_final(request)
    assert jpeg[:2] == b"\xff\xd8"
    final = frames[-1]
    assert final["passes"] == 3 and final["target_passes"] == 3 and not final["draft"]
    assert (final["width"], final["height"]) == (72, 56)
    status, png, headers = v.request("GET", "/api/snapshot.png")
    assert status == 200 and headers["X-Exabricks-Request"] == str(request)
    # The same scene given to `render --scene`: the same bytes.
    assert png == cli_png(cli, tmp_path, doc)
    # The scene the server reports (what the page saves) renders the same image too.
    status, saved, _ = v.request("GET", "/api/scene")
    assert status == 200
    saved_doc = json.loads(saved)
    assert saved_doc["iso"]["values"] == pytest.approx(doc["iso"]["values"])
    assert png == cli_png(cli, tmp_path, saved_doc, "saved")


def test_drafts_come_first_and_refinement_adds_passes(start_viewer):
    v = start_viewer()
    request = v.render(small_scene(v, width=128, height=128, samples_per_pixel=4))
    frames, _ = v.wait_final(request)
    mine = [f for f in frames if f["request"] == request]
    assert mine[0]["draft"] and mine[0]["width"] <= 128
    refined = [f["passes"] for f in mine if not f["draft"]]
    assert refined == [1, 2, 3, 4]
    sequences = [f["sequence"] for f in frames]
    assert sequences == sorted(sequences)
    # An interactive request gets its draft only.
    request = v.render(small_scene(v, width=128, height=128), interactive=True)
    for header, _ in v.stream(30):
        if header.get("request") == request:
            assert header["draft"]
            break
    time.sleep(0.5)
    status, _, headers = v.request("GET", "/api/snapshot.png")
    assert headers.get("X-Exabricks-Request") != str(request)


def test_a_path_traced_view_refines_to_its_noise_target_and_equals_the_command_line(start_viewer, cli, tmp_path):
    # --integrator pathtrace without --spp: rounds of the tiles whose denoised picture is above
    # 2/255 until none is; the last frame says so, and the picture is the command line's of the
    # same scene (denoised alike).
    v = start_viewer("--integrator", "pathtrace", "--size", "48x40")
    doc = v.info()["document"]
    assert doc["frame"]["noise_target"] == 2 and doc["frame"]["samples_per_pixel"] == 1024 and doc["frame"]["denoise"]
    request = v.render(doc)
    frames, _ = v.wait_final(request)
    final = frames[-1]
    assert "noise target 2/255 (denoised) reached" in final.get("data", ""), final
    refined = [f["passes"] for f in frames if f["request"] == request and not f["draft"]]
    # The stream sends the latest frame: on a loaded machine the client sees fewer of the rounds
    # (never one out of order), and the last holds the passes of rounds beyond the first.
    assert refined == sorted(refined) and len(refined) >= 2 and refined[-1] >= 8, refined
    status, png, _ = v.request("GET", "/api/snapshot.png?request=%d" % request)
    assert status == 200 and png == cli_png(cli, tmp_path, doc)


def test_a_newer_request_supersedes_the_one_in_flight(start_viewer):
    v = start_viewer()
    slow = v.render(small_scene(v, width=256, height=256, samples_per_pixel=200))
    frames = v.stream(60)
    # Wait until the slow request is refining, then replace it.
    for header, _ in frames:
        if header.get("request") == slow and not header["draft"]:
            break
    fast = v.render(small_scene(v, width=64, height=64, samples_per_pixel=2))
    seen_fast = False
    for header, _ in frames:
        if header.get("keepalive"):
            continue
        if header["request"] == fast:
            seen_fast = True
            if header["final"]:
                break
        else:
            # Frames of the old request may still be in the pipe before the new one's first frame,
            # never after it.
            assert not seen_fast, "a frame of the superseded request arrived after the newer one"
            assert header["passes"] < 200
    # The superseded request never completes.
    time.sleep(0.3)
    status, _, headers = v.request("GET", "/api/snapshot.png")
    assert headers["X-Exabricks-Request"] == str(fast)


def test_requests_without_the_token_are_refused(start_viewer):
    v = start_viewer()
    for path in ["/", "/index.html", "/viewer.js", "/api/info", "/api/stream", "/api/snapshot.png", "/api/scene"]:
        status, body, _ = v.request("GET", path, token=False)
        assert status == 403, path
        assert b"token" in body
        status, _, _ = v.request("GET", path, token="0" * len(v.token))
        assert status == 403, path
    status, _, _ = v.request("POST", "/api/render", {"scene": {}}, token="wrong")
    assert status == 403
    # The page itself, with the token in its address, sets a cookie its other requests carry.
    status, body, headers = v.request("GET", "/?token=" + v.token, token=False)
    assert status == 200 and b"viewer.js" in body
    cookie = headers["Set-Cookie"].split(";")[0]
    assert "HttpOnly" in headers["Set-Cookie"]
    status, _, _ = v.request("GET", "/viewer.js", token=False, headers={"Cookie": cookie})
    assert status == 200


def test_bad_requests_get_4xx_and_the_server_keeps_serving(start_viewer):
    v = start_viewer()
    doc = v.info()["document"]
    cases = [
        ("POST", "/api/render", b"{not json", 400, b"not valid JSON"),
        ("POST", "/api/render", json.dumps([1, 2]), 400, b"scene"),
        ("POST", "/api/render", json.dumps({"scene": doc, "extra": 1}), 400, b"unknown key"),
        ("POST", "/api/render", json.dumps({"scene": doc, "interactive": "yes"}), 400, b"interactive"),
        ("POST", "/api/render", json.dumps({"scene": dict(doc, frame=dict(doc["frame"], width=100000))}), 400,
         b"frame.width"),
        ("POST", "/api/render", json.dumps({"scene": dict(doc, frame=dict(doc["frame"], samples_per_pixel=0))}),
         400, b"frame.samples_per_pixel"),
        ("POST", "/api/render", json.dumps({"scene": dict(doc, layers=[{"field": "nosuchfield"}])}), 400,
         b"nosuchfield"),
        ("POST", "/api/render", json.dumps({"scene": dict(doc, light={"ambiant": 1})}), 400, b"ambiant"),
        ("POST", "/api/render", json.dumps({"scene": dict(doc, meshes=[{"file": "/etc/passwd"}])}), 400,
         b"reads no file"),
        ("POST", "/api/scene", b"[]", 400, b"uploaded scene"),
        ("POST", "/api/transfer-function", b"{\"colormap\": \"nosuchmap\"}", 400, b"nosuchmap"),
        ("GET", "/api/histogram?field=scalar&bins=0", None, 400, b"bins"),
        ("GET", "/api/histogram?field=nosuch", None, 400, b"unknown field"),
        ("GET", "/api/histogram?field=scalar&lo=abc", None, 400, b"not a number"),
        ("GET", "/api/histogram?field=scalar&lo=2&hi=1", None, 400, b"below"),
        ("GET", "/api/nothing", None, 404, b"no such"),
        ("GET", "/../../etc/passwd", None, 404, b""),
    ]
    for method, path, body, expect, message in cases:
        status, data, _ = v.request(method, path, body)
        assert status == expect, (path, body, status, data)
        assert message in data, (path, data)
        assert json.loads(data)["error"]
    # Oversized body: refused before it is read whole.
    status, _, _ = v.request("POST", "/api/render", b"x" * (9 << 20))
    assert status == 413
    # Garbage on the socket.
    with socket.create_connection((v.host, v.port), timeout=10) as s:
        s.sendall(b"\x00\x01GARBAGE\r\n\r\n")
        reply = s.recv(100)
        assert reply.startswith(b"HTTP/1.1 4"), reply
    # A client that connects and says nothing does not stall the others.
    idle = socket.create_connection((v.host, v.port), timeout=10)
    assert v.alive()
    idle.close()
    request = v.render(small_scene(v))
    v.wait_final(request)


def test_uploads_scene_and_preset(start_viewer):
    v = start_viewer()
    doc = v.info()["document"]
    doc.pop("camera")
    r = v.json("POST", "/api/scene", json.dumps(doc))
    assert r["has_camera"] is False and "camera" in r["document"]
    preset = [{"Name": "Two", "ColorSpace": "RGB", "RGBPoints": [0, 0, 0, 1, 1, 1, 0, 0]}]
    r = v.json("POST", "/api/transfer-function", json.dumps(preset))
    assert r["preset"] is True
    points = r["transfer_function"]["colormap"]["points"]
    assert points[0][:4] == [0, 0, 0, 1] and points[-1][0] == 1
    # A preset's colours in a scene render like any other.
    doc = small_scene(v)
    doc["layers"][0]["transfer_function"]["colormap"] = r["transfer_function"]["colormap"]
    v.wait_final(v.render(doc))


def test_histogram_counts_every_value_once(start_viewer):
    v = start_viewer()
    info = v.info()
    lo, hi = [f["range"] for f in info["fields"] if f["name"] == "scalar"][0]
    h = v.json("GET", "/api/histogram?field=scalar&bins=64&lo=%r&hi=%r" % (lo, hi))
    assert len(h["counts"]) == 64
    assert sum(h["counts"]) + h["below"] + h["above"] + h["excluded"] == info["cells"]
    mid = (lo + hi) / 2
    upper = v.json("GET", "/api/histogram?field=scalar&bins=8&lo=%r&hi=%r" % (mid, hi))
    assert upper["below"] == sum(h["counts"][:32]) + h["below"] or upper["below"] > 0


def test_ctrl_c_stops_cleanly(start_viewer):
    v = start_viewer()
    frames = v.stream(30)
    next(frames)  # a page is connected and streaming
    t = time.time()
    v.proc.send_signal(signal.SIGINT)
    assert v.proc.wait(10) == 0
    assert time.time() - t < 5
    assert "stopped" in v.stderr_path.read_text()


def test_scene_options_set_the_first_view(start_viewer):
    v = start_viewer("--colormap", "inferno", "--iso", "0.5", "--spp", "2", "--size", "100x80")
    doc = v.info()["document"]
    assert doc["layers"][0]["transfer_function"]["colormap"] == "inferno"
    assert doc["iso"]["values"] == [0.5]
    assert (doc["frame"]["width"], doc["frame"]["samples_per_pixel"]) == (100, 2)


def test_port_in_use_is_a_clear_error(cli):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        r = subprocess.run([cli, "view", "--port", str(port)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 1
    assert "cannot listen" in r.stderr and str(port) in r.stderr


def test_a_second_viewer_on_the_same_port_is_refused(start_viewer, cli):
    v = start_viewer()
    t = time.time()
    r = subprocess.run([cli, "view", "--port", str(v.port)], capture_output=True, text=True, timeout=60)
    assert r.returncode != 0, r.stderr
    assert "port %d" % v.port in r.stderr and "in use" in r.stderr, r.stderr
    assert "viewing" not in r.stderr  # refused before loading and serving
    assert time.time() - t < 20
    # The first viewer still answers every request (none went to a second server).
    for _ in range(20):
        status, _, _ = v.request("GET", "/api/info")
        assert status == 200


def test_the_page_names_the_dataset_and_the_hint_names_this_host(start_viewer, flow_dataset):
    v = start_viewer(str(flow_dataset.resolve()))
    info = v.info()
    assert info["name"] == "flow.cells"
    assert info["input"] == str(flow_dataset.resolve())
    text = v.stderr_path.read_text()
    assert "ssh -L %d:localhost:%d %s," % (v.port, v.port, socket.gethostname()) in text, text
    assert "THIS_HOST" not in text


def test_save_waits_for_the_view_on_screen_to_refine(start_viewer, cli, tmp_path):
    v = start_viewer()
    first = v.render(small_scene(v))
    v.wait_final(first)
    # A second view, still refining when the save is asked for: the save gets that view, refined.
    doc = small_scene(v, width=96, height=96, samples_per_pixel=40)
    doc["camera"]["position"] = [p + 30 for p in doc["camera"]["position"]]
    second = v.render(doc)
    status, png, headers = v.request("GET", "/api/snapshot.png?request=%d" % second, timeout=120)
    assert status == 200, png[:300]
    assert headers["X-Exabricks-Request"] == str(second) and headers["X-Exabricks-Passes"] == "40"
    assert png == cli_png(cli, tmp_path, doc)
    # An older view is gone once a newer one was asked for; unknown requests and drafts are refused.
    status, body, _ = v.request("GET", "/api/snapshot.png?request=%d" % first)
    assert status == 409 and b"changed" in body
    status, body, _ = v.request("GET", "/api/snapshot.png?request=%d" % (second + 5))
    assert status == 404
    draft = v.render(small_scene(v), interactive=True)
    status, body, _ = v.request("GET", "/api/snapshot.png?request=%d" % draft)
    assert status == 409 and b"dragged" in body
    status, body, _ = v.request("GET", "/api/snapshot.png?request=abc")
    assert status == 400


def test_first_picture_of_a_field_is_the_command_lines(start_viewer, cli, flow_dataset, tmp_path):
    v = start_viewer(str(flow_dataset), "--log")
    for field in ["velocity", "radius", "scalar"]:
        chosen = v.json("GET", "/api/first-picture?field=" + field)
        scene = tmp_path / ("first-%s.json" % field)
        subprocess.run([cli, "-q", "render", str(flow_dataset), "-f", field, "--size", "8x8", "-o",
                        str(tmp_path / "first.png"), "--write-scene", str(scene)], check=True, capture_output=True)
        expected = json.loads(scene.read_text())["layers"][0]["transfer_function"]
        got = chosen["transfer_function"]
        assert got["log"] == expected["log"] and got["opacity"] == expected["opacity"], (field, got, expected)
        assert got.get("range") == pytest.approx(expected.get("range")), (field, got, expected)
        assert got["opacity_scale"] == expected["opacity_scale"]
    velocity = v.json("GET", "/api/first-picture?field=velocity")["transfer_function"]
    assert velocity["log"] is False  # negative values: never logarithmic, whatever the first view used
    status, body, _ = v.request("GET", "/api/first-picture?field=nosuch")
    assert status == 400 and b"nosuch" in body


def test_the_vocabulary_and_unknown_keys_as_the_command_line_has_them(start_viewer, cli, tmp_path):
    v = start_viewer()
    vocabulary = v.json("GET", "/api/vocabulary")
    shading = next(s for s in vocabulary if s["key"] == "shading")
    assert shading["choices"] == ["analytic", "central", "smooth", "none"] and shading["default"] == "smooth"
    assert all(s["help"] and "default" in s for s in vocabulary)
    status, _, _ = v.request("GET", "/api/vocabulary", token=False)
    assert status == 403
    # An unknown key: the message of `render --scene`, naming the upload instead of the file.
    bad = {"integration": {"bogus": 1}}
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(bad))
    r = subprocess.run([cli, "render", "--scene", str(path), "-o", str(tmp_path / "x.png")], capture_output=True,
                       text=True)
    prefix = "exabricks: error: "
    message = r.stderr.strip().splitlines()[-1]
    assert r.returncode != 0 and message.startswith(prefix), r.stderr
    status, data, _ = v.request("POST", "/api/scene", json.dumps(bad))
    assert status == 400
    assert json.loads(data)["error"] == message[len(prefix):].replace(str(path), "uploaded scene", 1)


def test_the_snapshot_carries_the_legends_the_scene_asks_for(start_viewer, cli, tmp_path):
    import io

    from PIL import Image

    v = start_viewer()

    def snapshot(doc):
        request = v.render(doc)
        v.wait_final(request)
        status, png, headers = v.request("GET", "/api/snapshot.png?request=%d" % request, timeout=120)
        assert status == 200 and headers["X-Exabricks-Request"] == str(request)
        return png

    doc = small_scene(v, width=200, height=160, samples_per_pixel=1)
    plain = snapshot(doc)
    assert v.info()["document"]["legends"] == {"color_bar": False, "annotation": False, "level_legend": False}
    doc["legends"] = {"color_bar": True}
    bar = snapshot(doc)
    # The colour bar sits at the right edge, its title above it: no pixel changes at the left.
    a = Image.open(io.BytesIO(plain)).convert("RGB")
    b = Image.open(io.BytesIO(bar)).convert("RGB")
    changed = [(x, y) for y in range(a.height) for x in range(a.width) if a.getpixel((x, y)) != b.getpixel((x, y))]
    assert len(changed) > 200
    assert all(x > a.width // 4 for x, _ in changed)
    # The same scene given to `render --scene`: the same bytes, legend included.
    assert bar == cli_png(cli, tmp_path, doc, "bar")
    # The scene the server reports (what the page saves) keeps the key.
    status, saved, _ = v.request("GET", "/api/scene")
    assert status == 200 and json.loads(saved)["legends"]["color_bar"] is True


def key_paths(doc, prefix=""):
    """Every key path of a document, "[]" standing for each item of a list."""
    paths = set()
    if isinstance(doc, dict):
        for k, value in doc.items():
            path = prefix + "." + k if prefix else k
            paths |= {path} | key_paths(value, path)
    elif isinstance(doc, list):
        for value in doc:
            paths |= {prefix + "[]"} | key_paths(value, prefix + "[]")
    return paths


def test_every_described_key_of_a_scene_comes_back_from_the_viewer(start_viewer, cli, scene_example):
    v = start_viewer()
    structure = v.json("GET", "/api/structure")
    assert structure == json.loads(subprocess.run([cli, "keys", "--json"], check=True, capture_output=True,
                                                  text=True).stdout)["structure"]
    status, _, _ = v.request("GET", "/api/structure", token=False)
    assert status == 403
    uploadable, example = scene_example
    # The example uses every key a scene file holds (those read only, or kept out of documents, aside).
    paths = key_paths(example)
    for entry in structure:
        if entry.get("written") is False or entry.get("document") is False:
            continue
        if "object" in entry:
            owners = [e["key"] for e in structure if e["type"] == entry["object"] and "object" not in e]
            assert any(o + "." + entry["key"] in paths for o in owners), entry
        else:
            assert entry["key"] in paths, entry
    # A mesh file named by a request is refused, saying why; the rest comes back whole.
    status, data, _ = v.request("POST", "/api/scene", json.dumps(example))
    assert status == 400 and b"reads no file" in data and b"triangle.ply" in data, data
    r = v.json("POST", "/api/scene", json.dumps(uploadable))
    assert r["has_camera"] is True
    holds(r["document"], uploadable, "POST /api/scene")
    assert r["document"].get("input", "") in ("", "<embedded>", v.info()["input"])
    # Rendered, it is the scene in effect, whole.
    doc = dict(r["document"], frame=dict(r["document"]["frame"], width=64, height=48, samples_per_pixel=1))
    v.wait_final(v.render(doc))
    holds(v.json("GET", "/api/scene"), uploadable, "GET /api/scene")
