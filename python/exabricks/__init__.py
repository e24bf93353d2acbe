"""exabricks: fast, seam-free rendering of structured AMR data (the ExaBricks method).

Data in:  load(path), from_cells(corners, levels, fields), from_grids(grids), from_yt(ds); a yt scene
as a whole: Scene.from_yt(sc); inside yt's own scenes: exabricks.yt.ExaBricksSource.
Rendering: Scene(dataset) with TransferFunction, Camera, iso-surfaces, meshes, clipping and
ambient occlusion; Scene.render() returns an (H, W, 4) float32 array of linear, premultiplied
RGBA. Dataset.sample(points) reconstructs values and gradients; Dataset.info() describes the
model as `exabricks info --json` does. Series(paths) renders the steps of a time series and makes
movies. See docs/python.md.
"""

import copy
import json
import os

from . import _core
from ._dataset import Dataset, from_cells, from_grids, load

__version__ = _core.VERSION

Dataset.__module__ = __name__  # users meet it as exabricks.Dataset
from ._yt_scene import _yt_scene_units, camera_from_yt, from_yt, scene_from_yt, transfer_function_from_yt

__all__ = [
    "Dataset", "TransferFunction", "Camera", "Scene", "load", "from_cells", "from_grids", "from_yt",
    "colormap_names", "list_fields", "scene_vocabulary", "scene_structure", "read_png", "Series",
]


def colormap_names():
    """Names of the built-in colour maps."""
    return list(_core.colormap_names())


def read_png(path):
    """An 8-bit PNG (such as a movie's frame) as an (H, W, 4) float32 array of linear,
    premultiplied RGBA, the form Scene.render returns."""
    return _core.read_png(str(path))


def list_fields(path):
    """Names of the fields an input holds, without building anything."""
    return list(_core.list_fields(str(path)))


def _file_stem(text):
    """A name fit for a file: letters, digits, '.', '-' and '_' kept, the rest '_'."""
    stem = "".join(c if c.isalnum() or c in "._-" else "_" for c in str(text)).strip("._")
    return stem or "picture"


def _srgb(color):
    c = [float(x) for x in color]
    if len(c) != 3 or not all(0.0 <= x <= 1.0 for x in c):
        raise ValueError("a colour is three sRGB numbers in [0, 1], not %r" % (color,))
    return c


# Every setting of a scene file with the library's defaults.
_DEFAULT_DOCUMENT = json.loads(_core.scene_json("{}", "defaults"))

# The settings of a scene file as the library describes them (key, name, type, default, range,
# choices, kind, help): each is the Scene attribute of its name.
_VOCABULARY = json.loads(_core.scene_vocabulary())
_TYPES = {"boolean": bool, "integer": int, "number": float, "choice": str,
          "vector": lambda v: None if v is None else [float(c) for c in v]}


def _attribute(setting, value):
    """A setting's value as the Scene attribute holds it (vectors as tuples)."""
    if setting["type"] == "vector":
        return None if value is None else tuple(value)
    return value


# The structured keys of a scene file (camera, layers, transfer functions, iso, meshes, clipping,
# camera path) and the device choice, as the library describes them.
_STRUCTURE = json.loads(_core.scene_structure())


def scene_structure():
    """The structured keys of a scene file and the device choice, as the library describes them:
    a list of dicts with "key" (a path; "[]" stands for a list's items; the keys of the camera
    and transfer-function objects carry "object"), "type", "kind", "min"/"max", "choices",
    "default", "example", "required" and "help" (see `exabricks keys`)."""
    return copy.deepcopy(_STRUCTURE)


def scene_vocabulary():
    """The settings of a scene file: a list of dicts with "key" (the path in the file), "name"
    (the Scene attribute), "type" (boolean, integer, number, choice or vector), "default", "min"/"max"
    where bounded, "choices", "kind" (a vector's: direction or radiance), "optional" and "help"."""
    return copy.deepcopy(_VOCABULARY)


def _document_value(doc, key):
    """The value at a setting's key, None where the document leaves it out (an unset optional one)."""
    for part in key.split("."):
        if part not in doc:
            return None
        doc = doc[part]
    return doc


def _set_document_value(doc, key, value):
    *sections, leaf = key.split(".")
    for part in sections:
        doc = doc.setdefault(part, {})
    doc[leaf] = value


class TransferFunction:
    """A colour map and a piecewise-linear opacity over a value range (linear or log10).

    colormap: a built-in name, or a list of (x, r, g, b) points with x from 0 to 1 (sRGB).
    opacity: (x, alpha) points over the normalised value; None is a ramp from 0 to 1.
    range: (low, high) in data units; None is the field's range.
    opacity_scale: multiplies every opacity; "auto" is the dataset's default scale.
    albedo: (x, albedo) points over the normalised value, the path tracer's single-scattering
        albedo there (piecewise linear as the opacity); None is the scene's `albedo`.
    """

    def __init__(self, colormap="viridis", opacity=None, range=None, log=False, opacity_scale="auto", albedo=None):
        self.colormap = colormap
        self.opacity = opacity
        self.range = range
        self.log = log
        self.opacity_scale = opacity_scale
        self.albedo = albedo

    @classmethod
    def from_file(cls, path, preset_range=False):
        """A transfer-function file: exabricks JSON or a ParaView colour-map preset. A preset is
        applied as ParaView applies it: its points span the data's range (preset_range=True
        keeps the span of its points instead) and its opacity takes the default scale."""
        text, preset = _core.transfer_function_json(str(path))
        tf = cls.from_dict(json.loads(text))
        if preset and not preset_range:
            tf.range = None
            tf.opacity_scale = "auto"
        return tf

    @classmethod
    def from_dict(cls, d):
        """A transfer function from its scene-file form (the keys `exabricks keys` lists under
        <transfer_function>); an unknown key raises ValueError, as the scene reader refuses it."""
        known = [e["key"] for e in _STRUCTURE if e.get("object") == "transfer_function"]
        for key in d:
            if key not in known:
                raise ValueError('transfer function: unknown key "%s" (known: %s)' % (key, ", ".join(known)))
        cm = d.get("colormap", "viridis")
        if isinstance(cm, dict):
            cm = [tuple(p) for p in cm["points"]]
        return cls(colormap=cm, opacity=[tuple(p) for p in d["opacity"]] if "opacity" in d else None,
                   range=tuple(d["range"]) if d.get("range") is not None else None, log=bool(d.get("log", False)),
                   opacity_scale=d.get("opacity_scale", "auto"),
                   albedo=[tuple(p) for p in d["albedo"]] if "albedo" in d else None)

    @classmethod
    def from_yt(cls, tf, log=None, points=None, camera=None, dataset=None):
        """A yt ColorTransferFunction, or the one of a yt VolumeSource (whose log_field then gives
        `log`): its red, green, blue and alpha channels over its x bounds, at each of its bins (or
        at `points` values). yt's x is log10 of the value when its source maps the field
        logarithmically (log=True, the default without a source) and the value itself otherwise.

        yt integrates emission colour x alpha and absorption alpha per unit of its ray parameter,
        which spans a length L of the camera (the depth width for a plane-parallel lens); with the
        yt `camera` and the exabricks `dataset` the opacity is converted exactly, the opacity per
        finest cell of width h being 1 - exp(-alpha h / L) (docs/python.md), so that renders agree
        in exposure. Without a camera, L is that of the camera yt's create_scene sets up (1.5
        times the longest side of the domain, plane-parallel). Without a dataset, the opacity
        peaks at 1 with the dataset's default scale ("auto"), as for any other transfer function.
        yt's colours are taken as the linear intensities yt integrates, and values at and outside
        its bounds are transparent, as in yt."""
        return transfer_function_from_yt(cls, tf, log, points, camera, dataset)

    def to_dict(self):
        d = {}
        if isinstance(self.colormap, str):
            d["colormap"] = self.colormap
        else:
            d["colormap"] = {"points": [[float(v) for v in p] for p in self.colormap]}
        if self.opacity is not None:
            d["opacity"] = [[float(x), float(a)] for x, a in self.opacity]
        if self.albedo is not None:
            d["albedo"] = [[float(x), float(a)] for x, a in self.albedo]
        if self.range is not None:
            lo, hi = self.range
            d["range"] = [float(lo), float(hi)]
        d["log"] = bool(self.log)
        d["opacity_scale"] = "auto" if self.opacity_scale == "auto" else float(self.opacity_scale)
        return d

    def copy(self):
        return copy.deepcopy(self)

    def __repr__(self):
        return "TransferFunction(%s)" % ", ".join("%s=%r" % kv for kv in self.to_dict().items())


class Camera:
    """A pinhole (or orthographic) camera in world coordinates."""

    def __init__(self, position=(0.0, 0.0, 1.0), look_at=(0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), fov=40.0,
                 orthographic=False, ortho_height=1.0):
        self.position = tuple(map(float, position))
        self.look_at = tuple(map(float, look_at))
        self.up = tuple(map(float, up))
        self.fov = float(fov)
        self.orthographic = bool(orthographic)
        self.ortho_height = float(ortho_height)

    @classmethod
    def frame(cls, bounds, azimuth=30.0, elevation=25.0, fov=40.0, orthographic=False):
        """A camera that sees the whole box ((x0, y0, z0), (x1, y1, z1)) from the direction given by
        azimuth (degrees around +z from +x) and elevation (degrees above the x-y plane), as the
        command line frames its default view."""
        d = _core.frame_camera(list(map(float, bounds[0])), list(map(float, bounds[1])), float(azimuth),
                               float(elevation), float(fov), bool(orthographic))
        return cls(d["position"], d["look_at"], d["up"], d["fov"], d["orthographic"], d["ortho_height"])

    @classmethod
    def from_yt(cls, camera):
        """The position, focus, north vector and width of a yt camera, in code units (the world
        units of from_yt): orthographic with yt's height when its lens is plane-parallel, else a
        perspective whose vertical angle is yt's, 2 atan(height / (2 depth width)). A
        plane-parallel lens casts its rays from the near face of a slab one depth width thick
        around the focus: the orthographic camera sits on that face (Scene.from_yt also clips the
        far one)."""
        return camera_from_yt(cls, camera)

    def to_dict(self):
        return {"position": list(self.position), "look_at": list(self.look_at), "up": list(self.up),
                "fov": self.fov, "orthographic": self.orthographic, "ortho_height": self.ortho_height}

    def __repr__(self):
        return "Camera(position=%s, look_at=%s, up=%s, fov=%g)" % (self.position, self.look_at, self.up, self.fov)


class Layer:
    """One volume field and its transfer function."""

    def __init__(self, field, transfer_function=None):
        self.field = field
        self.transfer_function = transfer_function or TransferFunction()


class Scene:
    """What is rendered and how: volume layers, iso-surfaces, meshes, clipping, light, ambient
    occlusion, camera and frame. Every attribute can change between renders; the renderer
    rebuilds only what a change needs."""

    def __init__(self, dataset, field=None, transfer_function=None, device="auto", **settings):
        """``device``: where passes run: "cpu", "cuda" (an NVIDIA GPU; an error where none can
        be used), "auto" (the GPU where one is present and the scene has nothing it lacks, else
        the CPU) or "portable" (the GPU's per-ray code on CPU threads, for comparisons)."""
        if not isinstance(dataset, Dataset):
            raise TypeError("Scene needs an exabricks.Dataset")
        self.dataset = dataset
        # Scene files record the dataset by absolute path, as the command line writes them.
        if dataset.name == _core.DEFAULT_DATASET_NAME:
            self._input = _core.EMBEDDED_INPUT
        else:
            self._input = "" if dataset.name.startswith("<") else os.path.abspath(dataset.name)
        self._renderer = _core.Renderer(dataset._core, device)  # holds the dataset alive
        field = field or dataset.default_field
        self.notes = []  # what the defaults chose, as the command line says on stderr
        if transfer_function is None:
            # The command line's first picture: log mapping for positive data spanning many
            # decades, transparent over the dominant background.
            tf_json, self.notes = dataset._core.adapt_transfer_function(
                field, json.dumps(TransferFunction().to_dict()), True, True)
            transfer_function = TransferFunction.from_dict(json.loads(tf_json))
        self.layers = [Layer(field, transfer_function)]
        for setting in _VOCABULARY:  # the described settings, with the library's defaults
            setattr(self, setting["name"], _attribute(setting, setting["default"]))
        self.iso_values = []
        self.iso_field = ""
        self.iso_colors = []
        self.iso_color_field = ""
        self.iso_color_map = TransferFunction("cool-to-warm")
        self.meshes = []  # (exabricks._core.Mesh, sRGB colour)
        # Particles as spheres (`particles`, `particle_radius`): one species or all (""), radius
        # by an attribute, one sRGB colour or an attribute through a colour map.
        self.particle_species = ""
        self.particle_radius_by = ""
        self.particle_color = (1.0, 0.7, 0.35)
        self.particle_color_by = ""
        self.particle_color_map = TransferFunction("plasma")
        self.clip_planes = []  # (point, normal)
        self.clip_box = None
        self.camera_path = None  # movies: {"keyframes": [...], "constant_speed": bool}, as in the scene file
        self.background = (0.0, 0.0, 0.0)
        self.camera = None
        for key, value in settings.items():
            if not hasattr(self, key):
                raise AttributeError("Scene has no setting '%s'" % key)
            setattr(self, key, value)
        if self.camera is None:
            self.camera = self.frame_visible()

    @property
    def device(self):
        """Where the last render ran: "cpu", "cuda" or "portable" (set by the first render)."""
        return self._renderer.device

    def frame_visible(self, azimuth=30.0, elevation=25.0, fov=40.0):
        """A camera that frames the part of the data the transfer functions show (the whole data
        when none of it is visible), as the command line's default view does."""
        self._update()
        box = self._renderer.visible_bounds() or self.dataset.bounds
        return Camera.frame(box, azimuth, elevation, fov)

    def warnings(self):
        """What in the scene can never show anything (iso-values outside the data, a range that
        excludes it, ...), as the command line warns."""
        return list(self.dataset._core.warnings(self._scene_json()))

    # -- convenience ------------------------------------------------------------------------
    @property
    def transfer_function(self):
        """The first layer's transfer function."""
        return self.layers[0].transfer_function

    @transfer_function.setter
    def transfer_function(self, tf):
        self.layers[0].transfer_function = tf

    @property
    def field(self):
        return self.layers[0].field

    @field.setter
    def field(self, name):
        self.layers[0].field = name

    def add_layer(self, field, transfer_function=None):
        self.layers.append(Layer(field, transfer_function))

    def add_mesh(self, vertices=None, triangles=None, color=(0.6, 0.6, 0.62), path=None):
        """A triangle mesh in world coordinates: numpy vertices (V, 3) and triangles (T, 3), or a
        file (OBJ, PLY, .tris)."""
        mesh = _core.Mesh.read(str(path)) if path is not None else _core.Mesh(vertices, triangles)
        self.meshes.append((mesh, _srgb(color)))
        return mesh

    def add_clip_plane(self, point, normal):
        """Removes the half-space the normal points into."""
        self.clip_planes.append((tuple(map(float, point)), tuple(map(float, normal))))

    def orbit(self, azimuth, elevation=25.0, fov=None):
        """Frames the visible part of the data from another direction."""
        self.camera = self.frame_visible(azimuth, elevation, fov or self.camera.fov)

    # -- the scene file -----------------------------------------------------------------------
    def to_dict(self, with_meshes=False):
        """The scene in the JSON form of `exabricks render --scene`. Meshes read from files are
        recorded by their file; those made from arrays are written inline (vertices and triangles)
        only with `with_meshes`, as to_json does."""
        d = {
            "input": self._input,
            "camera": self.camera.to_dict() if self.camera is not None else Camera().to_dict(),
            "layers": [{"field": l.field, "transfer_function": l.transfer_function.to_dict()} for l in self.layers],
            "iso": {"field": self.iso_field, "values": [float(v) for v in self.iso_values],
                    "colors": [_srgb(c) for c in self.iso_colors], "color_field": self.iso_color_field,
                    "color_map": self.iso_color_map.to_dict()},
            "particles": {"species": self.particle_species, "radius_by": self.particle_radius_by,
                          "color": _srgb(self.particle_color), "color_by": self.particle_color_by,
                          "color_map": self.particle_color_map.to_dict()},
            "clip": {"planes": [{"point": list(map(float, p)), "normal": list(map(float, n))} for p, n in self.clip_planes]},
            "background": _srgb(self.background),
        }
        for setting in _VOCABULARY:
            value = _TYPES[setting["type"]](getattr(self, setting["name"]))
            if value is not None:  # an optional setting left unset is not written
                _set_document_value(d, setting["key"], value)
        if not d["input"]:
            del d["input"]
        if self.clip_box is not None:
            d["clip"]["box"] = [float(v) for v in self.clip_box]
        meshes = []
        for m, c in self.meshes:
            if m.source:
                meshes.append({"file": m.source, "color": _srgb(c)})
            elif with_meshes:
                meshes.append({"vertices": m.vertices.tolist(), "triangles": m.triangles.tolist(), "color": _srgb(c)})
        if meshes:
            d["meshes"] = meshes
        if self.camera_path is not None:
            d["camera_path"] = copy.deepcopy(self.camera_path)
        return d

    def to_json(self):
        """The scene file's text, as the command line writes it (every setting; checked by its
        reader). For a dataset made from yt (from_yt), the file names what the command line reads:
        the output's path, the file's field names and values in the file's units."""
        d = self.to_dict(with_meshes=True)
        origin = getattr(self.dataset, "_yt_origin", None)
        if origin is not None and not self._input:
            d = _yt_scene_units(d, origin, to_file=True)
        return _core.scene_json(json.dumps(d), "scene")

    def save_json(self, path):
        """Writes the scene file `exabricks render --scene` reads."""
        text = self.to_json()
        with open(path, "w") as f:
            f.write(text)

    @classmethod
    def from_json(cls, dataset, text):
        """A scene from a scene file: its path, or its JSON text (as written by save_json or
        `render --write-scene`). It is read by the command line's reader, so that unknown keys and
        invalid settings are refused with the messages of `render --scene`, and every setting it
        holds is kept (save_json writes them back). Settings the file leaves out keep the
        defaults of Scene(dataset); the dataset is the one given, whatever input the file names."""
        source = "scene"
        if isinstance(text, bytes):
            text = text.decode("utf-8")
        if isinstance(text, os.PathLike) or (isinstance(text, str) and not text.lstrip().startswith(("{", "["))):
            source = os.fspath(text)
            with open(source, encoding="utf-8") as f:
                text = f.read()
        d = json.loads(_core.scene_json(text, source))  # checked, with every setting
        origin = getattr(dataset, "_yt_origin", None)
        if origin is not None:
            d = _yt_scene_units(d, origin, to_file=False)
        given = set(json.loads(text))
        s = cls(dataset)
        if "camera" in given:
            c = d["camera"]
            s.camera = Camera(c["position"], c["look_at"], c["up"], c["fov"], c["orthographic"], c["ortho_height"])
        for setting in _VOCABULARY:
            setattr(s, setting["name"], _attribute(setting, _document_value(d, setting["key"])))
        if "layers" in given:
            s.layers = [Layer(l["field"] or dataset.default_field, TransferFunction.from_dict(l["transfer_function"]))
                        for l in d["layers"]]
        iso = d["iso"]
        s.iso_values = list(iso["values"])
        s.iso_field = iso["field"]
        s.iso_colors = [tuple(c) for c in iso["colors"]]
        s.iso_color_field = iso["color_field"]
        s.iso_color_map = TransferFunction.from_dict(iso["color_map"])
        p = d["particles"]
        s.particle_species = p["species"]
        s.particle_radius_by = p["radius_by"]
        s.particle_color = tuple(p["color"])
        s.particle_color_by = p["color_by"]
        s.particle_color_map = TransferFunction.from_dict(p["color_map"])
        for m in d["meshes"]:
            if "file" in m:
                s.add_mesh(path=m["file"], color=m["color"])
            else:
                s.add_mesh(m["vertices"], m["triangles"], color=m["color"])
        clip = d["clip"]
        s.clip_planes = [(tuple(p["point"]), tuple(p["normal"])) for p in clip["planes"]]
        s.clip_box = tuple(clip["box"]) if clip.get("box") else None
        s.background = tuple(d["background"])
        s.camera_path = d.get("camera_path")
        return s

    @classmethod
    def from_yt(cls, scene, dataset=None, source=None, **settings):
        """The scene of a yt Scene: the field of its volume source (the first unless `source` is given)
        as a dataset (from_yt, unless `dataset` is given), its transfer function with the opacity
        converted for its camera (TransferFunction.from_yt), its camera and resolution, no shading
        (yt's volume rendering does not light) and 8 samples per pixel (yt's pictures show no sampling
        noise; 8 jittered passes hide it at yt's resolutions). The settings of an ExaBricksSource
        apply over these, and `settings` over all. Its image agrees in exposure with yt's."""
        return scene_from_yt(cls, scene, dataset, source, **settings)

    # -- rendering ----------------------------------------------------------------------------
    def _frame_json(self, width, height, spp, rate):
        frame = {"width": int(width), "height": int(height), "samples_per_pixel": int(spp), "rate": float(rate),
                 "noise_target": float(self.noise_target), "denoise": bool(self.denoise), "jitter": bool(self.jitter),
                 "seed": int(self.seed)}
        return json.dumps({"camera": self.camera.to_dict(), "frame": frame})

    def _scene_json(self):
        """The scene without camera, frame, input, camera path and mesh files (the meshes go to the
        renderer as made): what the renderer takes."""
        d = self.to_dict()
        for key in ("camera", "frame", "input", "camera_path", "meshes"):
            d.pop(key, None)
        return json.dumps(d)

    def _update(self):
        source = getattr(self.dataset, "_particle_source", None)
        if self.particles and source is not None and not getattr(self.dataset, "_particles_given", False):
            # A dataset made from yt: its particles come from yt, once.
            given = [(name, d["position"], {k: v for k, v in d.items() if k != "position"})
                     for name, d in source("").items()]
            self.dataset._core.set_particles(given)
            self.dataset._particles_given = True
        return self._renderer.set_scene(self._scene_json(), [(m, c) for m, c in self.meshes])

    def render(self, width=None, height=None, spp=None, rate=None, depth_limit=None, depth_limit_planar=False):
        """Renders the scene: an (H, W, 4) float32 array of linear RGB premultiplied by alpha (row 0
        at the top). The GIL is released while rendering; Ctrl-C cancels.

        `depth_limit`: an (H, W) array (float32; other numbers are converted) of world distances
        per pixel beyond which nothing is drawn, volume, iso-surfaces and meshes alike, as where
        opaque geometry drawn elsewhere hides the rest (compositing: lay the image over that
        geometry's); +inf is no limit. A distance is measured along the pixel's rays from their
        origin (the camera position, or its image plane when orthographic), or with
        `depth_limit_planar` along the view direction from the camera's plane, as a z-buffer
        holds depth."""
        self.render_progressive(width, height, spp, rate, passes=spp or self.spp, depth_limit=depth_limit,
                                depth_limit_planar=depth_limit_planar)
        return self._renderer.image()

    def render_progressive(self, width=None, height=None, spp=None, rate=None, passes=0, depth_limit=None,
                           depth_limit_planar=False):
        """Adds passes to the scene's accumulation buffer (one pass when `passes` is 0; otherwise
        until it holds `passes`) and returns the passes it holds. The buffer starts over when the
        scene, the frame or the depth limit (as render takes it) changes; `samples_per_pixel` of
        the frame is `spp` (or `passes`)."""
        w, h = int(width or self.width), int(height or self.height)
        target = int(spp or self.spp)
        self._update()
        self._last_frame = (w, h, max(target, passes or 1), rate or self.rate)
        return self._renderer.render(self._frame_json(w, h, max(target, passes or 1), rate or self.rate), int(passes),
                                     depth_limit, bool(depth_limit_planar))

    def _render_for_output(self, width, height, spp):
        """What save and png write: with no size or samples given, the last render's frame (its
        passes are kept while the scene is unchanged, so nothing renders again; after a change it
        renders again at that size and samples); else a render of the given frame."""
        last = getattr(self, "_last_frame", None)
        if width is None and height is None and spp is None and last is not None:
            w, h, samples, rate = last
            self.render(w, h, samples, rate)
            return w, h
        self.render(width, height, spp)
        return int(width or self.width), int(height or self.height)

    def render_draft(self, width=None, height=None, budget=0.035, spp=None, rate=None):
        """Renders the draft an interactive view shows of the frame before refining it, as the
        viewer's and ParaView's drafts are made: an (h, w, 4) float32 array like render's, the
        frame's size divided by the scene's draft divisor (a quarter at first), one sample per
        pixel at half the frame's rate. The divisor then adapts so that the next draft renders in
        about `budget` seconds, and stays while the time is within half to 1.4 times the budget
        (drafts do not flicker between two sizes). The frame (`spp` and `rate` as render takes
        them) becomes the one shown, as render_progressive shows it: its passes carry on when it
        is the same. None when cancelled."""
        w, h = int(width or self.width), int(height or self.height)
        self._update()
        draft = self._renderer.render_draft(self._frame_json(w, h, int(spp or self.spp), rate or self.rate),
                                            float(budget))
        return None if draft is None else draft[0]

    def image(self):
        """The accumulated image as an (H, W, 4) float32 array (linear, premultiplied)."""
        return self._renderer.image()

    def stats(self):
        """Statistics of the passes in the buffer: seconds, rays, samples, regions visited, ..."""
        return dict(self._renderer.stats())

    def save(self, path=None, width=None, height=None, spp=None, bits=8, normalize=False):
        """Renders and writes the picture; returns its path. The format follows the extension:
        .png (sRGB, `bits` 8 or 16 per channel, with alpha when `alpha` is set, else over the
        background), .jpg, .exr (linear, premultiplied alpha, 32-bit float: for compositing) or
        .pfm (linear RGB over the background). Without a path, DATASET-FIELD-WIDTHxHEIGHT.png in
        the current folder. Publication sizes work as any other: save("f.png", 4096, 4096, 64).
        `normalize`: rescale the colours so that the brightest channel of any pixel reaches 1,
        as yt's own Scene.save does (a scene converted from yt then looks as yt saves it).
        Without `width`, `height` and `spp`, the picture of the last render is written (render(spp=64)
        then save() saves those 64 samples per pixel, without rendering again unless the scene has
        changed since)."""
        w, h = self._render_for_output(width, height, spp)
        if path is None:
            name = os.path.splitext(os.path.basename(str(self.dataset.name).rstrip("/")))[0]
            path = "%s-%s-%dx%d.png" % (_file_stem(name), _file_stem(self.field or "volume"), w, h)
        self._renderer.save(str(path), int(bits), bool(normalize))
        return str(path)

    def png(self, width=None, height=None, spp=None):
        """Renders and returns the PNG bytes (without a size or samples: of the last render, as save)."""
        self._render_for_output(width, height, spp)
        return self._renderer.png()

    def pick(self, origin, direction):
        """The nearest iso-surface or mesh hit along a world ray (dict), or None."""
        self._update()
        return self._renderer.pick(list(map(float, origin)), list(map(float, direction)))

    def _repr_png_(self):
        w = min(int(self.width), 640)
        h = max(1, int(round(self.height * w / self.width)))
        return self.png(w, h)

    def widget(self, width=512, height=512, budget=0.035, passes=16):
        """An interactive view in Jupyter (ipywidgets): orbit, transfer-function range and
        opacity, iso-value; each change shows a draft (render_draft with `budget` seconds), then
        refines progressively up to `passes` samples per pixel."""
        from .widget import SceneWidget
        return SceneWidget(self, width, height, budget, passes).widget


from .series import Series  # noqa: E402  (it uses Dataset and Scene above)
