"""The viewer over a time series, through its API: the steps and their names, choosing a step
(a bad index is refused, the server reads no path a request names), the step's render equals the
command line's render of the saved scene, and movies: made, downloaded by id, cancelled."""
import json
import shutil
import subprocess
import time

import pytest

from test_view_api import cli_png, small_scene


def step_to(v, index, expect=200):
    status, data, _ = v.request("POST", "/api/step", {"index": index})
    assert status == expect, (status, data[:300])
    return json.loads(data)


def test_the_series_lists_its_steps_and_refuses_a_bad_step(start_viewer, series_dataset):
    v = start_viewer(series_dataset)
    s = v.json("GET", "/api/series")
    assert [x["name"] for x in s["steps"]] == ["s_0000.cells", "s_0001.cells", "s_0002.cells"]
    assert s["current"] == 0 and s["series"] is True
    info = v.info()
    assert info["steps"] == 3 and info["step"] == 0 and "simulation" in info
    assert all("units" in f for f in info["fields"])
    for body in [{"index": 3}, {"index": -1}]:
        status, data, _ = v.request("POST", "/api/step", body)
        assert status == 400 and b"outside the steps 0..2" in data, data
    for body in [{"index": "1"}, {"index": 1.5}, {}, {"index": 1, "path": "/etc/passwd"}, {"path": "x.cells"}]:
        status, data, _ = v.request("POST", "/api/step", body)
        assert status == 400 and b"error" in data, (body, data)
    status, _, _ = v.request("POST", "/api/step", {"index": 1}, token=False)
    assert status == 403
    assert v.json("GET", "/api/series")["current"] == 0
    after = step_to(v, 2)
    assert after["current"] == 2 and after["steps"][2]["loaded"]
    assert v.info()["step"] == 2
    assert v.alive()


def test_a_step_renders_as_the_command_line_renders_its_saved_scene(start_viewer, cli, series_dataset, tmp_path):
    v = start_viewer(series_dataset)
    first = small_scene(v)
    step_to(v, 1)
    request = v.render(first)
    v.wait_final(request)
    status, png, _ = v.request("GET", "/api/snapshot.png")
    assert status == 200
    saved = json.loads(v.request("GET", "/api/scene")[1])
    assert saved["input"].endswith("s_0001.cells")
    # The range over all steps, as `movie` maps it, is in the scene; the image is the command line's.
    assert saved["layers"][0]["transfer_function"]["range"] == first["layers"][0]["transfer_function"]["range"]
    assert png == cli_png(cli, tmp_path, saved)
    # Step 0's image differs (the blobs move).
    step_to(v, 0)
    request = v.render(first)
    v.wait_final(request)
    assert v.request("GET", "/api/snapshot.png")[1] != png


def wait_movie(v, movie_id, states, timeout=120):
    deadline = time.time() + timeout
    while time.time() < deadline:
        m = v.json("GET", "/api/movie?id=" + movie_id)
        if m["state"] in states:
            return m
        time.sleep(0.1)
    raise AssertionError("the movie is still %s" % m)


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not installed")
def test_a_movie_of_the_series_is_made_and_downloaded_by_its_id(start_viewer, series_dataset, tmp_path):
    v = start_viewer(series_dataset)
    m = v.json("POST", "/api/movie", {"scene": small_scene(v, samples_per_pixel=1)})
    assert m["frames"] == 3 and m["state"] in ("rendering", "encoding", "done")
    done = wait_movie(v, m["id"], ("done", "failed"))
    assert done["state"] == "done", done
    status, data, headers = v.request("GET", done["file"])
    assert status == 200 and data[4:8] == b"ftyp" and len(data) == done["bytes"]
    assert "attachment" in headers["Content-Disposition"]
    # Each of the three steps holds for a second (24 frames at 24 frames per second), not 1/24 s.
    movie = tmp_path / "series.mp4"
    movie.write_bytes(data)
    probe = subprocess.run(["ffprobe", "-v", "error", "-show_entries", "format=duration", "-of", "csv=p=0",
                            str(movie)], capture_output=True, text=True, check=True)
    assert float(probe.stdout) == pytest.approx(3.0, abs=0.1), probe.stdout
    # Only ids the server made name movies.
    for path in ["/api/movie?id=nothere", "/api/movie/file?id=../../etc/passwd"]:
        assert v.request("GET", path)[0] == 404
    assert v.request("GET", done["file"], token=False)[0] == 403


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not installed")
def test_a_cancelled_movie_stops_and_leaves_no_file(start_viewer):
    v = start_viewer()
    scene = small_scene(v, width=160, height=120, samples_per_pixel=4)
    m = v.json("POST", "/api/movie", {"scene": scene, "frames": 400})
    assert m["frames"] == 400
    status, data, _ = v.request("POST", "/api/movie", {"scene": scene})
    assert status == 409 and b"already" in data
    cancelled = v.json("POST", "/api/movie/cancel", {"id": m["id"]})
    assert cancelled["id"] == m["id"]
    end = wait_movie(v, m["id"], ("cancelled", "done", "failed"))
    assert end["state"] == "cancelled" and end["done"] < 400
    status, data, _ = v.request("GET", "/api/movie/file?id=" + m["id"])
    assert status == 409 and b"cancelled" in data
    assert v.request("POST", "/api/movie/cancel", {"id": "nothere"})[0] == 404
    assert v.request("POST", "/api/movie", {"scene": scene, "frames": 0})[0] == 400
    # A new movie can start once the cancelled one stopped.
    again = v.json("POST", "/api/movie", {"scene": small_scene(v, samples_per_pixel=1), "frames": 2})
    assert wait_movie(v, again["id"], ("done", "failed"))["state"] == "done"


def test_a_single_dataset_has_one_step(start_viewer):
    v = start_viewer()
    s = v.json("GET", "/api/series")
    assert len(s["steps"]) == 1 and s["current"] == 0 and s["series"] is False
    assert step_to(v, 0)["current"] == 0
    status, data, _ = v.request("POST", "/api/step", {"index": 1})
    assert status == 400 and b"outside the steps 0..0" in data


def test_nan_as_holes_reads_the_step_again(start_viewer, series_dataset):
    """A step with a NaN is refused by name until the page asks for holes; then it is read again
    with the NaN's cell a hole (counted), later steps load the same way, and asking to refuse
    again keeps the step that cannot be read so."""
    import glob
    import struct
    step1 = sorted(glob.glob(series_dataset))[1].replace(".cells", ".scalars")
    with open(step1, "r+b") as f:
        f.seek(7 * 4)
        f.write(struct.pack("<f", float("nan")))
    v = start_viewer(series_dataset, "--range", "per-step")  # a range over every step would read step 1 first
    assert v.info()["nan_as_holes"] is False
    status, data, _ = v.request("POST", "/api/step", {"index": 1})
    assert status == 500 and b"record 7" in data, data[:300]
    holes = v.json("POST", "/api/holes", {"holes": True})
    assert holes["nan_as_holes"] is True and holes["holes"]["cells"] == 0  # step 0 has no NaN
    after = step_to(v, 1)
    assert after["current"] == 1
    request = v.render(small_scene(v))
    v.wait_final(request)
    assert v.request("GET", "/api/snapshot.png")[0] == 200
    again = v.json("POST", "/api/holes", {"holes": True})
    assert again["holes"]["cells"] == 1 and again["holes"]["fields"] == {"scalar": 1, "radius": 0}
    status, data, _ = v.request("POST", "/api/holes", {"holes": False})
    assert status == 400 and b"record 7" in data, data[:300]
    assert v.info()["nan_as_holes"] is True and v.info()["step"] == 1
    for body in [{"holes": "yes"}, {}, {"holes": True, "path": "x"}]:
        assert v.request("POST", "/api/holes", body)[0] == 400
    assert v.request("POST", "/api/holes", {"holes": True}, token=False)[0] == 403
    assert v.alive()


def test_a_truncated_step_is_marked_and_the_others_open(start_viewer, series_dataset, cli):
    """One step cut short (its values file truncated) does not keep the series from opening: the
    viewer starts on the readable steps, the page's step list marks the bad one with the reason,
    and asking for it answers the reason without losing the step on screen. When the first step
    is the bad one, the viewer opens on the next."""
    import glob
    import os

    paths = sorted(glob.glob(series_dataset))
    for bad in (1, 0):
        values = paths[bad].replace(".cells", ".scalars")
        with open(values, "r+b") as f:
            f.truncate(os.path.getsize(values) // 2)
        v = start_viewer(series_dataset)
        s = v.json("GET", "/api/series")
        assert len(s["steps"]) == 3 and s["current"] == (1 if bad == 0 else 0)
        assert "error" in s["steps"][bad] and "scalars" in s["steps"][bad]["error"], s["steps"][bad]
        assert all("error" not in s["steps"][k] for k in range(3) if k != bad)
        status, data, _ = v.request("POST", "/api/step", {"index": bad})
        assert status >= 400 and b"scalars" in data, data
        assert v.json("GET", "/api/series")["current"] == s["current"]
        v.stop()
        subprocess.run([cli, "-q", "generate", "--steps", "3", "-n", "20000",
                        "-o", paths[0].replace("_0000.cells", ".cells")], check=True, capture_output=True)
