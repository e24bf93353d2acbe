"""The ExaBricks representation against the library's description of scene files, run by pvbatch:

    pvbatch check_paraview_scene.py PLUGIN EXABRICKS_CLI WORK_DIR [DATA_DIR]

The description is `exabricks keys --json` ({"settings", "structure"}). plt_small is shown as
"ExaBricks" (the view, colour map and opacity ramp of check_paraview.py), and:

1. every choice the representation offers (Shading, Integrator, Device) is exactly the described
   choices, in the described order, with the described default;
2. every number range it offers lies within the described range of its key;
3. for every described key it exposes (the table KEYS: property -> key, the representation's
   properties and the view's camera and size), the property is set to a value other than its
   default (the description's "example", or a value inside both ranges), the view is rendered,
   and the Scene Document the representation reports (the scene it rendered, as the library
   writes scene files) holds that value at that key;
4. the colour map and opacity function of ParaView are the layer's transfer function there;
5. `exabricks render --scene` reads the document back.

Prints "skipped: ..." (and exits 0) where the shared sample is absent."""
import json
import math
import os
import subprocess
import sys

import paraview.simple
from paraview.simple import GetColorTransferFunction, GetOpacityTransferFunction, LoadPlugin, Render

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pv_common import (ALPHA, COLORS, RANGE, finest_cell, information, map_color, plotfile_or_skip,  # noqa: E402
                       setup_view, srgb)

# Each property of the representation that stands for a described key: property -> key.
KEYS = {
    "SamplingRate": "frame.rate",
    "SamplesPerPixel": "frame.samples_per_pixel",
    "AmbientOcclusionRays": "ambient_occlusion.rays",
    "Shading": "shading",
    "Integrator": "integration.integrator",
    "Albedo": "pathtrace.albedo",
    "ScatteringAnisotropy": "pathtrace.anisotropy",
    "Bounces": "pathtrace.bounces",
    "Emission": "pathtrace.emission",
    "SunIntensity": "pathtrace.sun_intensity",
    "SunAngle": "pathtrace.sun_angle",
    "Environment": "pathtrace.environment",
    "Sky": "pathtrace.sky",
    "Ground": "pathtrace.ground",
    "SunDirection": "pathtrace.sun_direction",
    "IsoValues": "iso.values",
    "ClipPlanes": "clip.planes",
    "Device": "device",
}
# The view's properties that stand for described keys (the camera object's keys as camera.KEY).
VIEW_KEYS = {
    "CameraPosition": "camera.position",
    "CameraFocalPoint": "camera.look_at",
    "CameraViewUp": "camera.up",
    "CameraViewAngle": "camera.fov",
    "CameraParallelProjection": "camera.orthographic",
    "CameraParallelScale": "camera.ortho_height",  # half the height
    "ViewSize": "frame.width",  # and frame.height
}
# Properties that a key needs set before it is in the document.
NEEDS = {"Shading": {"Shade": 1}, "Sky": {"SkyGradient": 1}, "Ground": {"SkyGradient": 1}}
# Devices: every described choice is offered; the document does not hold the device (the key is
# an option of the front ends, "document": false), Device In Use says where the renderer runs.
# cuda is not set here (it reports an error where no GPU can be used).
DEVICES_RUN_HERE = ("cpu", "portable")

plugin, cli, work = sys.argv[1:4]
plotfile = plotfile_or_skip(sys.argv[4] if len(sys.argv) > 4 else None)
os.makedirs(work, exist_ok=True)
LoadPlugin(plugin, ns=globals())
paraview.simple._DisableFirstRenderCameraReset()

described = json.loads(subprocess.run([cli, "keys", "--json"], check=True, capture_output=True).stdout)
DESCRIPTION = {}
for entry in described["settings"] + described["structure"]:
    DESCRIPTION[entry["object"] + "." + entry["key"] if "object" in entry else entry["key"]] = entry

reader, view, display = setup_view(plotfile, finest_cell(cli, plotfile))
failures = []
# The values the properties start with: their defaults.
DEFAULTS = {name: display.SMProxy.GetProperty(name).GetElement(0) for name in KEYS
            if name not in ("IsoValues", "ClipPlanes")}


def expect(condition, message):
    if not condition:
        failures.append(message)
    return condition


def document():
    """The scene document of the view rendered now, as the representation reports it."""
    Render(view)
    text = information(display, "SceneDocument")
    return json.loads(text)


def at(doc, key):
    """The value at a dotted key of a document (None where absent)."""
    for part in key.split("."):
        if not isinstance(doc, dict) or part not in doc:
            return None
        doc = doc[part]
    return doc


def same(got, want, kind=None):
    """Equal values: numbers within float32 round-off, directions as directions."""
    if isinstance(want, dict):
        return isinstance(got, dict) and set(got) == set(want) and all(same(got[k], want[k]) for k in want)
    if isinstance(want, (list, tuple)):
        if not isinstance(got, list) or len(got) != len(want):
            return False
        if kind == "direction":
            g, w = math.sqrt(sum(x * x for x in got)), math.sqrt(sum(x * x for x in want))
            return g > 0 and all(math.isclose(a / g, b / w, rel_tol=1e-5, abs_tol=1e-6) for a, b in zip(got, want))
        return all(same(a, b) for a, b in zip(got, want))
    if isinstance(want, bool) or isinstance(want, str) or want is None:
        return got == want
    return isinstance(got, (int, float)) and math.isclose(got, want, rel_tol=1e-6, abs_tol=1e-9)


def smproperty(name):
    return display.SMProxy.GetProperty(name)


def bounds_of(entry):
    """The described range as (low, high, low open, high open); None for an unbounded end."""
    return (entry.get("min"), entry.get("max"), entry.get("min_exclusive", False), entry.get("max_exclusive", False))


def offered_range(name, index=0):
    """The range ParaView offers for a number property (None for an unbounded end)."""
    domain = smproperty(name).GetDomain("range")
    if domain is None:
        return None, None
    low = domain.GetMinimum(index) if domain.GetMinimumExists(index) else None
    high = domain.GetMaximum(index) if domain.GetMaximumExists(index) else None
    return low, high


def check_choices():
    """1. The choice lists against the description."""
    for name in ("Shading", "Integrator", "Device"):
        entry = DESCRIPTION[KEYS[name]]
        domain = smproperty(name).GetDomain("list")
        offered = [domain.GetString(i) for i in range(domain.GetNumberOfStrings())]
        default = DEFAULTS[name]
        print("%s offers %s (default %s); %s: %s (default %s)"
              % (name, offered, default, entry["key"], entry["choices"], entry["default"]))
        expect(offered == entry["choices"], "%s offers %s, %s has the choices %s"
               % (name, offered, entry["key"], entry["choices"]))
        expect(default == entry["default"], "%s's default is %s, %s's %s" % (name, default, entry["key"],
                                                                              entry["default"]))


def check_ranges():
    """2. Every offered number range within the described one (a vector's radiance: >= 0)."""
    for name, key in KEYS.items():
        entry = DESCRIPTION[key]
        if entry["type"] not in ("number", "integer", "vector"):
            continue
        for index in range(smproperty(name).GetNumberOfElements() if entry["type"] == "vector" else 1):
            low, high = offered_range(name, index)
            if entry["type"] == "vector":
                if entry.get("kind") == "radiance":
                    expect(low is not None and low >= 0, "%s offers radiance from %s" % (name, low))
                continue
            lo, hi, lo_open, hi_open = bounds_of(entry)
            low_ok = lo is None or (low is not None and (low > lo if lo_open else low >= lo))
            high_ok = hi is None or (high is not None and (high < hi if hi_open else high <= hi))
            print("%s offers [%s, %s]; %s accepts [%s, %s]" % (name, low, high, key, lo, hi))
            expect(low_ok and high_ok, "%s offers [%s, %s] beyond %s's [%s, %s]" % (name, low, high, key, lo, hi))


def value_inside(name, entry):
    """A value for a described number other than the described and the offered defaults, inside
    both ranges."""
    lo, hi, _, _ = bounds_of(entry)
    low, high = offered_range(name)
    low = max(v for v in (lo, low, -1e30) if v is not None)
    high = min(v for v in (hi, high, 1e30) if v is not None)
    defaults = {entry["default"], float(DEFAULTS[name])}
    if entry["type"] == "integer":
        return next(v for v in range(int(math.ceil(low)) + 1, int(math.ceil(low)) + 4) if v not in defaults)
    value = low + 0.25 * (high - low) if high < 1e30 else low + 0.5
    return value if value not in defaults else value + 0.125 * (high - low)


def value_for(name, entry):
    """The value a property is set to for its key: the example, a value inside the ranges, or
    for a vector setting a radiance or direction other than its default."""
    if entry["type"] == "vector":
        return [0.5, -1.0, 0.25] if entry.get("kind") == "direction" else [0.25, 0.5, 0.75]
    if "example" in entry:
        return entry["example"]
    return value_inside(name, entry)


def round_trip(name, value, key, want=None, kind=None):
    """Sets a property, renders, and checks the document holds `want` (the value) at the key."""
    setattr(display, name, value)
    got = at(document(), key)
    want = value if want is None else want
    print("%s = %s: %s is %s" % (name, value, key, json.dumps(got)))
    return expect(same(got, want, kind), "%s = %s: the scene document's %s is %s, not %s"
                  % (name, value, key, json.dumps(got), json.dumps(want)))


def check_settings():
    """3. The representation's settings: each choice in turn, numbers and vectors once."""
    for name, key in KEYS.items():
        entry = DESCRIPTION[key]
        if name in ("IsoValues", "ClipPlanes", "Device"):
            continue
        for prop, on in NEEDS.get(name, {}).items():
            setattr(display, prop, on)
        if entry["type"] == "choice":
            for choice in entry["choices"]:
                round_trip(name, choice, key)
            setattr(display, name, entry["default"])
            continue
        round_trip(name, value_for(name, entry), key, kind=entry.get("kind"))


def check_iso_and_clip():
    """3. Iso-values (each in the colour map's colour) and clip planes: the examples."""
    values = DESCRIPTION["iso.values"]["example"]
    if round_trip("IsoValues", values, "iso.values"):
        colors = at(document(), "iso.colors")
        want = [srgb(map_color(v)) for v in values]
        expect(same(colors, want) or all(max(abs(a - b) for a, b in zip(c, w)) < 2e-3 for c, w in zip(colors, want)),
               "iso.colors are %s, the colour map gives %s" % (colors, want))
    display.IsoValues = []
    planes = DESCRIPTION["clip.planes"]["example"]
    flat = [x for p in planes for x in p["point"] + p["normal"]]
    round_trip("ClipPlanes", flat, "clip.planes", want=planes)
    display.ClipPlanes = []


def check_saved_numbers():
    """State files saved while the choices were numbered enumerations keep their meaning."""
    display.Shade = 1
    for name, number, key, want in (("Shading", "1", "shading", "analytic"), ("Shading", "3", "shading", "none"),
                                    ("Integrator", "1", "integration.integrator", "pathtrace")):
        round_trip(name, number, key, want=want)
        setattr(display, name, DESCRIPTION[key]["default"])
    display.Device = "1"
    document()
    expect(information(display, "DeviceInUse") == "cpu", "Device 1 (cpu in saved states) is not the CPU")
    display.Device = DESCRIPTION["device"]["default"]


def check_devices():
    """3. Devices: not a document key; Device In Use follows the choice."""
    entry = DESCRIPTION["device"]
    expect(entry.get("document") is False, "device is a document key now: add it to the document check")
    expect(entry["example"] in DEVICES_RUN_HERE, "the device example %s is not run here" % entry["example"])
    for device in DEVICES_RUN_HERE:
        display.Device = device
        doc = document()
        in_use = information(display, "DeviceInUse")
        print("Device %s: in use %s" % (device, in_use))
        expect(in_use == device, "Device %s renders on %s" % (device, in_use))
        expect("device" not in doc, "the scene document holds a device")
    display.Device = entry["default"]


def check_layer():
    """4. The layer: the rendered array, ParaView's range, log scale, colour map and opacity."""
    layers = at(document(), "layers")
    if not expect(isinstance(layers, list) and len(layers) == 1, "the document's layers are %s" % layers):
        return
    expect(layers[0].get("field") == "phi", "layers[].field is %s, not phi" % layers[0].get("field"))
    tf = layers[0]["transfer_function"]
    points = tf["colormap"]["points"]
    expect(all(max(abs(a - b) for a, b in zip(p, [x, *srgb(c)])) < 2e-3
               for p, x, c in ((points[0], 0.0, COLORS[0]), (points[-1], 1.0, COLORS[1]))),
           "the colour map's ends are %s and %s, ParaView's %s" % (points[0], points[-1], COLORS))
    opacity = tf["opacity"]
    expect(abs(opacity[0][1] - ALPHA[0]) < 1e-4 and abs(opacity[-1][1] - ALPHA[1]) < 1e-4,
           "the opacity's ends are %s and %s, ParaView's %s" % (opacity[0], opacity[-1], ALPHA))
    expect(same(tf["range"], list(RANGE)), "the range is %s, ParaView's %s" % (tf["range"], RANGE))
    low, high = DESCRIPTION["transfer_function.range"]["example"]
    lut, pwf = GetColorTransferFunction("phi"), GetOpacityTransferFunction("phi")
    lut.RGBPoints = [low, *COLORS[0], high, *COLORS[1]]
    pwf.Points = [low, ALPHA[0], 0.5, 0.0, high, ALPHA[1], 0.5, 0.0]
    got = at(document(), "layers")[0]["transfer_function"]
    print("colour map over [%s, %s]: range %s" % (low, high, got["range"]))
    expect(same(got["range"], [low, high]), "the range is %s, ParaView's [%s, %s]" % (got["range"], low, high))
    lut.UseLogScale = int(DESCRIPTION["transfer_function.log"]["example"])
    got = at(document(), "layers")[0]["transfer_function"]
    print("log scale %d: log %s" % (lut.UseLogScale, got["log"]))
    expect(got["log"] == DESCRIPTION["transfer_function.log"]["example"], "log is %s" % got["log"])
    lut.UseLogScale = 0
    lut.RGBPoints = [RANGE[0], *COLORS[0], RANGE[1], *COLORS[1]]
    pwf.Points = [RANGE[0], ALPHA[0], 0.5, 0.0, RANGE[1], ALPHA[1], 0.5, 0.0]


def check_view():
    """3. The view's camera (the example camera) and size."""
    camera = DESCRIPTION["camera"]["example"]
    for name, key in VIEW_KEYS.items():
        expect(key in DESCRIPTION, "%s is not described" % key)
    settings = {"CameraPosition": camera["position"], "CameraFocalPoint": camera["look_at"],
                "CameraViewUp": camera["up"], "CameraViewAngle": camera["fov"],
                "CameraParallelProjection": int(camera["orthographic"]),
                "CameraParallelScale": camera["ortho_height"] / 2}
    for name, value in settings.items():
        setattr(view, name, value)
    got = at(document(), "camera")
    print("the example camera: the document's camera is %s" % json.dumps(got))
    for key in ("position", "look_at", "up", "fov", "orthographic", "ortho_height"):
        want = camera[key]
        expect(same(got.get(key), want, DESCRIPTION["camera." + key].get("kind")),
               "camera.%s is %s, not %s" % (key, got.get(key), want))
    size = [value_inside_size("frame.width", 200), value_inside_size("frame.height", 150)]
    view.ViewSize = size
    doc = document()
    print("View Size %s: frame %sx%s" % (size, at(doc, "frame.width"), at(doc, "frame.height")))
    expect([at(doc, "frame.width"), at(doc, "frame.height")] == size, "the frame is not %s" % size)
    return doc


def value_inside_size(key, value):
    entry = DESCRIPTION[key]
    expect(entry["min"] <= value <= entry["max"] and value != entry["default"], "%s %s" % (key, value))
    return value


def check_read_back(doc):
    """5. exabricks render reads the document the representation wrote."""
    path = os.path.join(work, "scene.json")
    with open(path, "w") as f:
        json.dump(doc, f, indent=2)
    run = subprocess.run([cli, "render", plotfile, "--scene", path, "-o", os.path.join(work, "scene.pfm")],
                         capture_output=True, text=True)
    print("exabricks render --scene (the document): exit %d" % run.returncode)
    expect(run.returncode == 0, "exabricks render did not read the document: %s" % run.stderr.strip())


for key in list(KEYS.values()) + list(VIEW_KEYS.values()):
    expect(key in DESCRIPTION, "%s is not a described key" % key)
if not failures:
    check_choices()
    check_ranges()
    check_settings()
    check_iso_and_clip()
    check_saved_numbers()
    check_devices()
    check_layer()
    check_read_back(check_view())
exposed = set(KEYS.values()) | set(VIEW_KEYS.values()) | {
    "frame.height", "camera", "layers", "layers[].field", "layers[].transfer_function", "transfer_function.colormap",
    "transfer_function.opacity", "transfer_function.range", "transfer_function.log", "iso", "iso.colors",
    "iso.colors[]", "clip", "clip.planes[].point", "clip.planes[].normal"}
print("described keys the representation does not offer: %s"
      % ", ".join(sorted(k for k in DESCRIPTION if k not in exposed and not k.startswith("camera."))))

if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("passed")
