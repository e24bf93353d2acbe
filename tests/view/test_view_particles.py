"""Particles in the viewer: /api/info lists the input's species, a scene that shows them is drawn
with its spheres (the refined view equal to the command line's render of the same scene), and the
page's particle controls appear only for data with particles."""
import json
import os
import pathlib
import subprocess
import time

import pytest

DATA = pathlib.Path(os.environ.get("EXABRICKS_DATA", pathlib.Path(__file__).resolve().parents[3] / "shared" / "data"))
ENZO = DATA / "particles" / "enzo_moving7_3d" / "DD0010" / "moving7_0010"


def enzo():
    if not ENZO.exists():
        pytest.skip("shared sample %s is absent (set EXABRICKS_DATA to the folder of shared samples)" % ENZO)
    return ENZO


def final_png(v, doc, timeout=120):
    request = v.render(doc)
    deadline = time.time() + timeout
    for header, _ in v.stream(timeout):
        assert time.time() < deadline
        if header.get("keepalive"):
            continue
        assert "error" not in header, header
        if header["request"] == request and header["final"]:
            break
    status, png, _ = v.request("GET", "/api/snapshot.png?request=%d" % request, timeout=timeout)
    assert status == 200
    return png


def test_the_viewer_lists_and_draws_particles_as_the_command_line_does(start_viewer, cli, tmp_path):
    v = start_viewer(str(enzo()), "--size", "96x96", "--spp", "1")
    info = v.info()
    (species,) = info["particles"]
    assert species["species"] == "dark_matter" and species["count"] == 9233 and "mass" in species["attributes"]
    doc = info["document"]
    without = final_png(v, doc)
    doc["particles"]["show"] = True
    doc["particles"]["radius"] = 0.006
    doc["particles"]["color_by"] = "mass"
    with_particles = final_png(v, doc)
    assert with_particles != without
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(doc))
    out = tmp_path / "cli.png"
    subprocess.run([cli, "-q", "render", "--scene", str(scene), "-o", str(out)], check=True)
    assert with_particles == out.read_bytes()
    # Spheres sized in pixels, and again with the camera halfway to its look-at point: the viewer
    # resizes them with the distance as the command line sizes them for its camera.
    doc["particles"]["radius_pixels"] = 2
    for step in range(2):
        if step:
            camera = doc["camera"]
            camera["position"] = [a + 0.5 * (p - a) for p, a in zip(camera["position"], camera["look_at"])]
        png = final_png(v, doc)
        scene.write_text(json.dumps(doc))
        subprocess.run([cli, "-q", "render", "--scene", str(scene), "-o", str(out)], check=True)
        assert png == out.read_bytes(), step
    doc["particles"]["radius_pixels"] = 0
    # A species the data lacks is refused with its name, and the viewer goes on.
    doc["particles"]["species"] = "stars"
    request = v.render(doc)
    for header, _ in v.stream(60):
        if header.get("request") == request and "error" in header:
            assert "no particle species 'stars'" in header["error"], header
            break
    assert v.alive()


def test_data_without_particles_lists_none(start_viewer):
    v = start_viewer("--size", "32x32")
    assert v.info()["particles"] == []
