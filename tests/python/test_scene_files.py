"""Scene files through Python: read and written by the command line's reader and writer, so that
every setting survives `render --write-scene` -> Scene.from_json -> save_json -> `render --scene`,
unknown keys are refused with the messages of `render --scene`, and a path is taken where a JSON
text is."""
import json
import math
import os
import pathlib
import subprocess

import numpy as np
import pytest

import exabricks as eb
from documents import assert_same, holds, with_mesh_file
from exabricks import _core

CAMERA = {"position": [150.0, 20.0, 60.0], "look_at": [30.0, 31.0, 33.0], "up": [0.0, 0.2, 1.0], "fov": 33.0,
          "orthographic": True, "ortho_height": 70.0}


def every_setting(mesh):
    """A scene file in which every setting differs from its default."""
    return {
        "camera": CAMERA,
        "camera_path": {"constant_speed": True, "keyframes": [
            {"time": 0, "camera": CAMERA, "opacity_scale": 0.02, "range": [0.01, 1.4], "iso_values": [0.5]},
            {"time": 2, "camera": dict(CAMERA, position=[60.0, 150.0, 80.0], fov=30.0), "opacity_scale": 0.2,
             "range": [0.1, 1.4], "iso_values": [0.9]}]},
        "frame": {"width": 40, "height": 30, "samples_per_pixel": 2, "noise_target": 3, "denoise": True, "rate": 0.75,
                  "jitter": False,
                  "seed": 7},
        "layers": [
            {"field": "scalar", "transfer_function": {"colormap": "magma", "opacity": [[0, 0], [0.5, 0.2], [1, 0.9]], "albedo": [[0, 0.2], [1, 0.9]],
                                                      "range": [0.05, 1.3], "log": True, "opacity_scale": 0.5}},
            {"field": "radius", "transfer_function": {"colormap": {"points": [[0, 0, 0, 1], [1, 1, 0.5, 0]]},
                                                      "opacity": [[0, 0.1], [1, 0]], "range": [0.1, 0.7],
                                                      "opacity_scale": 0.1}}],
        "volume": False,
        "iso": {"field": "scalar", "values": [0.3, 0.6], "colors": [[0.9, 0.5, 0.2], [0.2, 0.6, 0.9]],
                "color_field": "radius",
                "color_map": {"colormap": "inferno", "range": [0.1, 0.8], "opacity_scale": 0.7}},
        "meshes": [{"file": str(mesh), "color": [0.7, 0.2, 0.3]}],
        "particles": {"show": True, "species": "stars", "radius": 0.5, "radius_pixels": 3, "radius_by": "mass", "color": [0.2, 0.4, 0.6],
                      "color_by": "mass", "color_map": {"colormap": "viridis", "range": [1, 2], "log": True}},
        "clip": {"planes": [{"point": [32, 32, 32], "normal": [0, 0, 1]}], "box": [1, 2, 3, 60, 61, 62],
                 "meshes": True},
        "light": {"headlight": False, "direction": [1, -0.5, -1], "ambient": 0.2, "diffuse": 0.6, "specular": 0.4,
                  "shininess": 20},
        "shading": "central",
        "ambient_occlusion": {"rays": 2, "length": 5, "volume": True},
        "integration": {"sampling": "fixed", "reconstruction": "cells", "traversal": "embree",
                        "embree_below_visible_fraction": 0.3, "space_skipping": False, "uniform_stride": False,
                        "early_termination": False,
                        "termination_opacity": 0.9, "integrator": "pathtrace"},
        "pathtrace": {"albedo": 0.5, "anisotropy": 0.3, "bounces": 7, "emission": 0.5, "environment": [0.2, 0.3, 0.4],
                      "sky": [0.3, 0.5, 0.9], "ground": [0.1, 0.08, 0.05],
                      "sun_direction": [1, 2, -3], "sun_intensity": 2, "sun_angle": 2},
        "debug": "level",
        "background": [0.1, 0.2, 0.3],
        "alpha": True,
        "legends": {"color_bar": True, "annotation": True, "level_legend": True},
    }


@pytest.fixture
def dataset_file(cli, tmp_path):
    path = tmp_path / "b.cells"
    subprocess.run([cli, "-q", "generate", "-s", "blobs", "-n", "8000", "-o", str(path)], check=True)
    return path.resolve()


def test_every_setting_survives_python(cli, dataset_file, tmp_path):
    mesh = tmp_path / "tri.obj"
    mesh.write_text("v 10 10 10\nv 50 12 20\nv 30 50 40\nf 1 2 3\n")
    (tmp_path / "full.json").write_text(json.dumps(every_setting(mesh)))
    subprocess.run([cli, "-q", "render", str(dataset_file), "--scene", str(tmp_path / "full.json"), "-o",
                    str(tmp_path / "cli.png"), "--write-scene", str(tmp_path / "cli.json")], check=True)
    written = json.loads((tmp_path / "cli.json").read_text())
    # Every setting of the file differs from the library's default (else the test would miss it).
    defaults = json.loads(_core.scene_json("{}", "defaults"))
    for key, default in defaults.items():
        assert key in written, key
        if isinstance(default, dict):
            for k, v in default.items():
                assert written[key][k] != v, "%s.%s keeps its default %r" % (key, k, v)
        else:
            assert written[key] != default, "%s keeps its default %r" % (key, default)
    assert "camera_path" in written and "input" in written

    ds = eb.load(dataset_file)
    scene = eb.Scene.from_json(ds, tmp_path / "cli.json")  # a path, where a JSON text is also taken
    scene.save_json(tmp_path / "py.json")
    assert_same(written, json.loads((tmp_path / "py.json").read_text()))
    # And the command line renders the same picture from it, and writes it back unchanged.
    subprocess.run([cli, "-q", "render", str(dataset_file), "--scene", str(tmp_path / "py.json"), "-o",
                    str(tmp_path / "py.png"), "--write-scene", str(tmp_path / "again.json")], check=True)
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    assert_same(written, json.loads((tmp_path / "again.json").read_text()))
    # The text of the file reads the same as its path.
    from_text = eb.Scene.from_json(ds, (tmp_path / "cli.json").read_text())
    assert_same(json.loads(scene.to_json()), json.loads(from_text.to_json()))
    assert from_text.camera_path["constant_speed"] is True and from_text.reconstruction == "cells"


@pytest.mark.parametrize("bad", [{"lights": {}}, {"light": {"ambiant": 1}}, {"integration": {"vectorised": False}},
                                 {"frame": {"width": 0}}, {"shading": "phong"}])
def test_unknown_keys_and_bad_settings_are_refused_as_the_command_line_does(cli, tmp_path, bad):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(bad))
    r = subprocess.run([cli, "render", "--scene", str(path), "-o", str(tmp_path / "x.png")], capture_output=True,
                       text=True)
    assert r.returncode != 0
    message = r.stderr.strip().splitlines()[-1]
    prefix = "exabricks: error: "
    assert message.startswith(prefix), r.stderr
    ds = eb.load()
    with pytest.raises(ValueError) as e:
        eb.Scene.from_json(ds, path)
    assert str(e.value) == message[len(prefix):]
    with pytest.raises(ValueError) as e:  # as text: the same message, naming "scene"
        eb.Scene.from_json(ds, json.dumps(bad))
    assert str(e.value) == message[len(prefix):].replace(str(path), "scene", 1)


def test_a_scene_file_path_as_text_and_as_path(tmp_path):
    ds = eb.load()
    s = eb.Scene(ds, width=20, height=10, shading="central")
    s.save_json(tmp_path / "s.json")
    for given in (tmp_path / "s.json", str(tmp_path / "s.json"), (tmp_path / "s.json").read_text(),
                  (tmp_path / "s.json").read_bytes()):
        t = eb.Scene.from_json(ds, given)
        assert (t.width, t.height, t.shading) == (20, 10, "central")
    with pytest.raises(FileNotFoundError):
        eb.Scene.from_json(ds, str(tmp_path / "missing.json"))


def other_value(setting):
    """A value of a described setting in its range and different from its default (the rule of
    the library's test of the vocabulary)."""
    kind, default = setting["type"], setting["default"]
    if kind == "boolean":
        return not default
    if kind == "vector":
        return [0.25, 0.5, 0.75] if default is None else [default[1] + 0.5, default[2] + 0.25, default[0] + 0.125]
    if kind == "choice":
        return next(c for c in setting["choices"] if c != default)
    if kind == "integer":
        v = math.floor((setting["min"] + default) / 2)
        return default + 1 if v == default else v
    v = (setting["min"] + default) / 2
    if v != default:
        return v
    return (default + setting["max"]) / 2 if "max" in setting else default + 1


def at_key(doc, key):
    for part in key.split("."):
        doc = doc[part]
    return doc


def put_key(doc, key, value):
    *sections, leaf = key.split(".")
    for part in sections:
        doc = doc.setdefault(part, {})
    doc[leaf] = value


def test_every_described_setting_survives_write_scene_and_python(cli, dataset_file, tmp_path):
    vocabulary = eb.scene_vocabulary()
    assert {s["name"] for s in vocabulary} <= set(vars(eb.Scene(eb.load(), camera=eb.Camera())))
    doc = {"layers": [{"field": "scalar"}], "iso": {"values": [0.5]}, "camera": CAMERA}
    for s in vocabulary:
        put_key(doc, s["key"], other_value(s))
    (tmp_path / "every.json").write_text(json.dumps(doc))
    subprocess.run([cli, "-q", "render", str(dataset_file), "--scene", str(tmp_path / "every.json"), "-o",
                    str(tmp_path / "every.png"), "--write-scene", str(tmp_path / "cli.json")], check=True)
    text = (tmp_path / "cli.json").read_text()
    written = json.loads(text)
    for s in vocabulary:
        assert at_key(written, s["key"]) != s["default"], s["key"]
        assert_same(other_value(s), at_key(written, s["key"]), s["key"])
    # --scene then --write-scene keeps it.
    subprocess.run([cli, "-q", "render", str(dataset_file), "--scene", str(tmp_path / "cli.json"), "-o",
                    str(tmp_path / "again.png"), "--write-scene", str(tmp_path / "again.json")], check=True)
    assert (tmp_path / "again.json").read_text() == text
    # And so does the Python Scene, through its attributes of the same names.
    scene = eb.Scene.from_json(eb.load(dataset_file), text)
    for s in vocabulary:
        value = getattr(scene, s["name"])
        assert_same(at_key(written, s["key"]), list(value) if isinstance(value, tuple) else value, s["name"])
    assert_same(written, json.loads(scene.to_json()))


def test_legends_render_as_the_command_line_draws_them(cli, dataset_file, tmp_path):
    """The legend keys (color_bar, annotation, level_legend): Scene.render and save draw what
    `render --colorbar --annotate` draws."""
    subprocess.run([cli, "-q", "render", str(dataset_file), "--size", "160x120", "--colorbar", "--annotate", "-o",
                    str(tmp_path / "cli.png"), "--write-scene", str(tmp_path / "cli.json")], check=True)
    ds = eb.load(dataset_file)
    scene = eb.Scene.from_json(ds, tmp_path / "cli.json")
    assert scene.color_bar and scene.annotation and not scene.level_legend
    cli_image = eb.read_png(tmp_path / "cli.png")

    def srgb(a):  # over the black background, as the PNG stores it
        c = np.clip(a[..., :3].astype(np.float64), 0.0, 1.0)
        return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1.0 / 2.4) - 0.055)

    image = scene.render()
    assert np.abs(srgb(image) - srgb(cli_image)).max() <= 1 / 255 + 1e-6
    scene.save(tmp_path / "py.png")
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    # Without the keys: no legends, and the image differs where they were.
    scene.color_bar = scene.annotation = False
    plain = scene.render()
    assert np.abs(srgb(plain) - srgb(cli_image)).max() > 0.5
    assert json.loads(scene.to_json())["legends"] == {"color_bar": False, "annotation": False, "level_legend": False}


# The front ends' controls of scene settings: ParaView's properties and the viewer's inputs, by
# the vocabulary key they set. Each lets a user choose only values the vocabulary accepts (a
# control may offer a narrower range, as a slider does).
PARAVIEW_KEYS = {"SamplingRate": "frame.rate", "AmbientOcclusionRays": "ambient_occlusion.rays",
                 "SamplesPerPixel": "frame.samples_per_pixel", "Albedo": "pathtrace.albedo",
                 "ScatteringAnisotropy": "pathtrace.anisotropy", "Bounces": "pathtrace.bounces",
                 "Emission": "pathtrace.emission",
                 "SunIntensity": "pathtrace.sun_intensity", "SunAngle": "pathtrace.sun_angle"}
VIEWER_KEYS = {"ao-rays": "ambient_occlusion.rays", "spp": "frame.samples_per_pixel"}


def within_vocabulary(setting, low, high, where):
    lo, hi = setting["min"], setting.get("max", math.inf)
    ok_low = low > lo if setting.get("min_exclusive") else low >= lo
    ok_high = high < hi if setting.get("max_exclusive") else high <= hi
    assert ok_low and ok_high and low <= high, "%s offers [%s, %s]; %s accepts [%s, %s]" % (
        where, low, high, setting["key"], lo, hi)


def test_front_end_controls_offer_only_what_the_vocabulary_accepts():
    import xml.etree.ElementTree as ET

    root = pathlib.Path(__file__).resolve().parents[2]
    vocabulary = {s["key"]: s for s in eb.scene_vocabulary()}
    xml = ET.parse(root / "paraview" / "plugin" / "ExaBricks.xml")
    seen = set()
    for prop in xml.iter():
        name = prop.get("name")
        if name not in PARAVIEW_KEYS or prop.tag not in ("IntVectorProperty", "DoubleVectorProperty"):
            continue
        domain = next(d for d in prop if d.tag.endswith("RangeDomain"))
        setting = vocabulary[PARAVIEW_KEYS[name]]
        low = float(domain.get("min", setting["min"]))
        high = float(domain.get("max", setting.get("max", math.inf)))
        within_vocabulary(setting, low, high, "ParaView's %s" % name)
        default = float(prop.get("default_values"))
        within_vocabulary(setting, default, default, "ParaView's %s default" % name)
        seen.add(name)
    assert seen == set(PARAVIEW_KEYS), set(PARAVIEW_KEYS) - seen
    html = (root / "web" / "index.html").read_text()
    for element, key in VIEWER_KEYS.items():
        tag = html[html.index('id="%s"' % element):].split(">", 1)[0]
        attrs = dict(part.split("=", 1) for part in tag.replace('"', "").split() if "=" in part)
        low, high = float(attrs["min"]), float(attrs["max"])
        if "data-log2" in attrs:  # the slider's value is the setting's base-2 logarithm
            low, high = 2 ** low, 2 ** high
        within_vocabulary(vocabulary[key], low, high, "the viewer's %s" % element)


TRIANGLE_PLY = """ply
format ascii 1.0
element vertex 3
property float x
property float y
property float z
element face 1
property list uchar int vertex_indices
end_header
0 0 0
60 0 0
0 60 30
3 0 1 2
"""


def test_every_described_structured_key_survives_the_command_line_and_python(cli, dataset_file, tmp_path,
                                                                               monkeypatch):
    """The library's example scene file uses every structured key it describes (camera, layers and
    transfer functions, iso, meshes from a file and inline, clipping, camera path, background):
    `render --scene` then `--write-scene`, and Scene.from_json then to_json, keep each of them."""
    structure = eb.scene_structure()
    example = json.loads(_core.scene_example())
    top = {s["key"].split(".")[0].split("[")[0] for s in structure
           if "object" not in s and s.get("document", True) and s.get("written", True)}
    assert top <= set(example), top - set(example)
    example = with_mesh_file(example)
    monkeypatch.chdir(tmp_path)  # the mesh file as the working directory sees it
    (tmp_path / "triangle.ply").write_text(TRIANGLE_PLY)
    (tmp_path / "example.json").write_text(json.dumps(example))
    def files_resolved(doc):  # mesh files as one path, whether written relative or absolute
        for m in doc.get("meshes", []):
            if "file" in m:
                m["file"] = os.path.realpath(m["file"])
        return doc

    want = files_resolved(json.loads(json.dumps(example)))
    del want["input"]  # a front end given a dataset records the one it renders
    subprocess.run([cli, "-q", "render", str(dataset_file), "--scene", "example.json", "--size", "32x24", "-o",
                    "example.png", "--write-scene", "cli.json"], check=True, cwd=tmp_path)
    holds(files_resolved(json.loads((tmp_path / "cli.json").read_text())), want, "render --write-scene")
    scene = eb.Scene.from_json(eb.load(dataset_file), tmp_path / "example.json")
    holds(files_resolved(json.loads(scene.to_json())), want, "Scene.to_json")
    assert len(scene.meshes) == 2 and scene.meshes[1][0].triangles.tolist() == [[0, 1, 2]]
    # Scene.to_json's file is the command line's: it reads back to the same text.
    (tmp_path / "py.json").write_text(scene.to_json())
    subprocess.run([cli, "-q", "render", str(dataset_file), "--scene", "py.json", "--size", "32x24", "-o",
                    "py.png", "--write-scene", "again.json"], check=True, cwd=tmp_path)
    holds(files_resolved(json.loads((tmp_path / "again.json").read_text())), want, "Scene.to_json -> render")


def test_the_device_choices_are_the_described_ones(cli, dataset_file):
    device = next(s for s in eb.scene_structure() if s["key"] == "device")
    assert device["choices"] == ["auto", "cpu", "cuda", "portable"] and device["document"] is False
    for choice in ("cpu", "portable"):
        assert eb.Scene(eb.load(dataset_file), device=choice).render(24, 16).shape == (16, 24, 4)
    with pytest.raises(Exception, match=r"device is 'gpu' \(choose from: auto, cpu, cuda, portable\)"):
        eb.Scene(eb.load(dataset_file), device="gpu")
    bad = subprocess.run([cli, "render", str(dataset_file), "--device", "gpu", "-o", "/dev/null"],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "auto" in bad.stderr and "portable" in bad.stderr


def test_exabricks_keys_prints_the_description(cli):
    """`exabricks keys` lists every key with its help; --json is the library's description and
    --example its example scene file."""
    described = json.loads(subprocess.run([cli, "keys", "--json"], check=True, capture_output=True,
                                          text=True).stdout)
    assert described == {"settings": eb.scene_vocabulary(), "structure": eb.scene_structure()}
    example = subprocess.run([cli, "keys", "--example"], check=True, capture_output=True, text=True).stdout
    assert json.loads(example) == json.loads(_core.scene_example())
    text = subprocess.run([cli, "keys"], check=True, capture_output=True, text=True).stdout
    for s in eb.scene_vocabulary() + eb.scene_structure():
        assert s["help"] in text, s["key"]
    assert "camera_path.keyframes[].time" in text and "<camera>.fov  (number: (0, 180); default 40.0)" in text


def test_python_defaults_are_the_described_ones():
    """Camera(), TransferFunction() and a Scene's structured attributes start where the library's
    description says the scene file's keys do."""
    described = {("<%s>.%s" % (s["object"], s["key"]) if "object" in s else s["key"]): s["default"]
                 for s in eb.scene_structure()}
    camera = eb.Camera()
    for key in ("look_at", "up", "fov", "orthographic", "ortho_height"):
        value = getattr(camera, key)
        assert_same(described["<camera>." + key], list(value) if isinstance(value, tuple) else value, key)
    tf = eb.TransferFunction().to_dict()
    for key in ("colormap", "log", "opacity_scale"):
        assert tf[key] == described["<transfer_function>." + key], key
    tf = eb.TransferFunction()
    assert tf.opacity is None and tf.range is None and tf.albedo is None
    assert described["<transfer_function>.opacity"] is None and described["<transfer_function>.range"] is None
    scene = eb.Scene(eb.load())
    assert scene.iso_values == described["iso.values"] and scene.iso_colors == described["iso.colors"]
    assert scene.iso_field == described["iso.field"] and scene.iso_color_field == described["iso.color_field"]
    assert_same(described["iso.color_map"], scene.iso_color_map.to_dict())
    assert list(scene.background) == described["background"] and scene.clip_box == described["clip.box"]
    assert scene.clip_planes == described["clip.planes"] and scene.meshes == described["meshes"]
    with pytest.raises(ValueError, match=r'unknown key "colour" \(known: colormap, opacity, albedo, range, log, '
                                         r'opacity_scale\)'):
        eb.TransferFunction.from_dict({"colour": "red"})


def test_a_camera_without_up_takes_the_described_one(tmp_path):
    text = _core.scene_json(json.dumps({"camera": {"position": [100, 20, 30]}}), "s.json")
    camera = json.loads(text)["camera"]
    described = {s["key"]: s["default"] for s in eb.scene_structure() if s.get("object") == "camera"}
    for key in ("look_at", "up", "fov", "orthographic", "ortho_height"):
        assert camera[key] == described[key], key


def test_every_setting_flag_sets_its_key(cli, dataset_file, tmp_path):
    """The flags `render --help` lists with "(scene key K)" set K: each given at once at a value
    other than the default (switches flip it), `--write-scene` holds every one."""
    import re

    vocabulary = {s["key"]: s for s in eb.scene_vocabulary()}
    help_text = subprocess.run([cli, "render", "--help"], check=True, capture_output=True, text=True).stdout
    flags = re.findall(r"^\s+(--[a-z-]+)\b[^\n]*(?:\n\s{20,}[^\n]*)*?\(scene key ([a-z_.]+)\)", help_text, re.M)
    assert len(flags) >= 20, flags
    args, want = [], {}
    for flag, key in flags:
        s = vocabulary[key]
        value = other_value(s)
        if s["type"] == "boolean" and re.search(r"^\s+%s \{on,off\}" % re.escape(flag), help_text, re.M):
            args += [flag, "on" if value else "off"]  # a switch that takes its value
        elif s["type"] == "boolean":
            args.append(flag)  # a switch: on where the default is off, off where it is on
            assert value == (not flag.startswith("--no-")), flag
        else:
            args += [flag, str(value)]
        want[key] = value
    subprocess.run([cli, "-q", "render", str(dataset_file), "--size", "24x16", "--iso", "0.5", "-o",
                    str(tmp_path / "flags.png"), "--write-scene", str(tmp_path / "flags.json")] + args, check=True)
    written = json.loads((tmp_path / "flags.json").read_text())
    for key, value in want.items():
        assert_same(value, at_key(written, key), key)
