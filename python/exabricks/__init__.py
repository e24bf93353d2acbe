"""exabricks: fast, seam-free rendering of structured AMR data (the ExaBricks method).

Data in:  load(path), from_cells(corners, levels, fields), from_grids(grids), from_yt(ds).
Rendering: Scene(dataset) with TransferFunction, Camera, iso-surfaces, meshes, clipping and
ambient occlusion; Scene.render() returns an (H, W, 4) float32 array of linear, premultiplied
RGBA. Dataset.sample(points) reconstructs values and gradients; Dataset.info() describes the
model as `exabricks info --json` does. See docs/python.md.
"""

import copy
import json
import math

import numpy as np

from . import _core

__all__ = [
    "Dataset", "TransferFunction", "Camera", "Scene", "load", "from_cells", "from_grids", "from_yt",
    "colormap_names", "list_fields",
]


def colormap_names():
    """Names of the built-in colour maps."""
    return list(_core.colormap_names())


def list_fields(path):
    """Names of the fields an input holds, without building anything."""
    return list(_core.list_fields(str(path)))


class Dataset:
    """A built AMR dataset (bricks and active brick regions over leaf cells)."""

    def __init__(self, core):
        self._core = core

    @property
    def name(self):
        return self._core.name

    @property
    def fields(self):
        """Field names, in file order."""
        return list(self._core.fields)

    @property
    def cells(self):
        return self._core.cells

    @property
    def bounds(self):
        """World box ((x0, y0, z0), (x1, y1, z1)) of the cells."""
        return self._core.bounds

    @property
    def default_field(self):
        return self._core.default_field()

    @property
    def default_opacity_scale(self):
        """The opacity scale "auto" stands for: a ray through the whole data gathers an optical
        depth of about eight."""
        return self._core.default_opacity_scale

    def info(self):
        """The dictionary `exabricks info --json` prints."""
        return json.loads(self._core.info_json())

    def sample(self, points, field=None):
        """Values (N,) and gradients per world unit (N, 3) at world positions (N, 3); NaN where
        no cell has weight."""
        points = np.asarray(points, dtype=np.float64)
        if points.ndim == 1 and points.shape[0] == 3:
            points = points.reshape(1, 3)
        return self._core.sample(points, field or "")

    def __repr__(self):
        return "<exabricks.Dataset %s: %d cells, fields %s>" % (self.name, self.cells, ", ".join(self.fields))


def load(path=None, fields=None, max_brick_width=32, box=None):
    """Reads any input the command line reads (model file, NAME.cells, AMReX, Chombo, FLASH, Enzo,
    VTK AMR, raw volume; the embedded default dataset when path is None) and builds it.
    `box` (x0, y0, z0, x1, y1, z1, finest lattice units) keeps only the cells that overlap it."""
    return Dataset(_core.load("" if path is None else str(path), list(fields or []), max_brick_width,
                              list(box) if box is not None else []))


def from_cells(corners, levels, fields, origin=(0.0, 0.0, 0.0), spacing=(1.0, 1.0, 1.0), max_brick_width=32):
    """A dataset from leaf cells: integer lower corners (N, 3) in finest-lattice units, levels (N,)
    (a cell is 2**level finest cells wide; corners are multiples of the width), and one (N,) array
    per field in a dict. World = origin + spacing * lattice. A non-dict `fields` is the field
    "scalar"."""
    if not isinstance(fields, dict):
        fields = {"scalar": fields}
    pairs = [(str(name), np.asarray(values)) for name, values in fields.items()]
    for name, values in pairs:
        if values.dtype.kind not in "fiu":
            raise ValueError("field '%s' must hold numbers, not %s" % (name, values.dtype))
    corners = np.asarray(corners)
    levels = np.asarray(levels)
    if corners.dtype.kind not in "iu" or levels.dtype.kind not in "iu":
        raise ValueError("corners and levels must be integer arrays (finest-lattice units)")
    return Dataset(_core.from_cells(corners, levels, pairs, list(map(float, origin)), list(map(float, spacing)),
                                    max_brick_width))


def from_grids(grids, fields=None, bbox=None, max_brick_width=32):
    """A dataset from overlapping grids in the layout yt's load_amr_grids takes: a list of dicts
    with "left_edge", "right_edge", "level", "dimensions" and one array per field of shape
    `dimensions` (indexed [i, j, k]). Cells covered by a finer grid are dropped. `bbox`
    ([[x0, x1], [y0, y1], [z0, z1]], optional) gives the domain, whose lower corner is the lattice
    origin."""
    if not grids:
        raise ValueError("from_grids: no grids")
    reserved = {"left_edge", "right_edge", "level", "dimensions"}
    names = list(fields) if fields else [k for k in grids[0] if k not in reserved]
    if not names:
        raise ValueError("from_grids: the grids hold no field arrays")
    packed = []
    for g, grid in enumerate(grids):
        dims = [int(d) for d in grid["dimensions"]]
        arrays = []
        for name in names:
            if name not in grid:
                raise ValueError("from_grids: grid %d has no field '%s'" % (g, name))
            a = np.asarray(grid[name], dtype=np.float64)
            if list(a.shape) != dims:
                raise ValueError("from_grids: grid %d field '%s' has shape %s, dimensions are %s"
                                 % (g, name, tuple(a.shape), tuple(dims)))
            arrays.append(np.ascontiguousarray(a.transpose(2, 1, 0)).ravel())  # x fastest
        packed.append((list(map(float, grid["left_edge"])), list(map(float, grid["right_edge"])), dims, arrays))
    origin = [float(bbox[a][0]) for a in range(3)] if bbox is not None else []
    return Dataset(_core.from_grids(packed, [str(n) for n in names], origin, max_brick_width))


def _yt_field_name(field):
    return field[-1] if isinstance(field, tuple) else str(field)


def from_yt(ds, fields=None, max_brick_width=32):
    """A dataset from a loaded yt dataset (any code yt reads, through ds.index.grids): the leaf
    cells of its grids with the given fields (yt field names or (type, name) tuples; by default
    the first field yt lists for the output's own code). Values are taken in yt's units."""
    if fields is None:
        fields = [ds.field_list[0]]
    elif isinstance(fields, (str, tuple)):
        fields = [fields]
    grids = []
    for grid in ds.index.grids:
        entry = {
            "left_edge": np.asarray(grid.LeftEdge.d, dtype=np.float64),
            "right_edge": np.asarray(grid.RightEdge.d, dtype=np.float64),
            "level": int(grid.Level),
            "dimensions": [int(d) for d in grid.ActiveDimensions],
        }
        for f in fields:
            entry[_yt_field_name(f)] = np.asarray(grid[f].d if hasattr(grid[f], "d") else grid[f], dtype=np.float64)
        grids.append(entry)
        grid.clear_data()
    left = ds.domain_left_edge.d
    right = ds.domain_right_edge.d
    bbox = [[left[a], right[a]] for a in range(3)]
    return from_grids(grids, [_yt_field_name(f) for f in fields], bbox=bbox, max_brick_width=max_brick_width)


def _srgb(color):
    c = [float(x) for x in color]
    if len(c) != 3 or not all(0.0 <= x <= 1.0 for x in c):
        raise ValueError("a colour is three sRGB numbers in [0, 1], not %r" % (color,))
    return c


class TransferFunction:
    """A colour map and a piecewise-linear opacity over a value range (linear or log10).

    colormap: a built-in name, or a list of (x, r, g, b) points with x from 0 to 1 (sRGB).
    opacity: (x, alpha) points over the normalised value; None is a ramp from 0 to 1.
    range: (low, high) in data units; None is the field's range.
    opacity_scale: multiplies every opacity; "auto" is the dataset's default scale.
    """

    def __init__(self, colormap="viridis", opacity=None, range=None, log=False, opacity_scale="auto"):
        self.colormap = colormap
        self.opacity = opacity
        self.range = range
        self.log = log
        self.opacity_scale = opacity_scale

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
        cm = d.get("colormap", "viridis")
        if isinstance(cm, dict):
            cm = [tuple(p) for p in cm["points"]]
        return cls(colormap=cm, opacity=[tuple(p) for p in d["opacity"]] if "opacity" in d else None,
                   range=tuple(d["range"]) if d.get("range") is not None else None, log=bool(d.get("log", False)),
                   opacity_scale=d.get("opacity_scale", 1.0))

    @classmethod
    def from_yt(cls, tf, log=True, points=64):
        """A yt ColorTransferFunction (its red, green, blue and alpha channels over its x bounds),
        sampled at `points` values. yt's x is log10 of the value when its source maps the field
        logarithmically (log=True, yt's default for densities) and the value itself otherwise.
        yt's alpha scales its own ray integration; here it becomes the opacity per finest cell,
        with the dataset's default scale."""
        channels = [np.asarray(f.y, dtype=np.float64) for f in tf.funcs[:4]]
        x = np.asarray(tf.funcs[0].x, dtype=np.float64)
        x0, x1 = float(x[0]), float(x[-1])
        if not x1 > x0:
            raise ValueError("the yt transfer function spans no range")
        idx = np.unique(np.linspace(0, len(x) - 1, max(2, int(points))).round().astype(int))
        t = (x[idx] - x0) / (x1 - x0)
        rgb = np.clip(np.stack([c[idx] for c in channels[:3]], axis=1), 0.0, 1.0)
        alpha = np.clip(channels[3][idx], 0.0, None)
        if alpha.max() > 0:
            alpha = alpha / alpha.max()
        t[0], t[-1] = 0.0, 1.0
        colormap = [(float(ti), float(r), float(g), float(b)) for ti, (r, g, b) in zip(t, rgb)]
        opacity = [(float(ti), float(a)) for ti, a in zip(t, alpha)]
        value_range = (10.0 ** x0, 10.0 ** x1) if log else (x0, x1)
        return cls(colormap=colormap, opacity=opacity, range=value_range, log=bool(log), opacity_scale="auto")

    def to_dict(self):
        d = {}
        if isinstance(self.colormap, str):
            d["colormap"] = self.colormap
        else:
            d["colormap"] = {"points": [[float(v) for v in p] for p in self.colormap]}
        if self.opacity is not None:
            d["opacity"] = [[float(x), float(a)] for x, a in self.opacity]
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
        """The position, focus, north vector and width of a yt camera (orthographic when yt's lens
        is plane-parallel)."""
        pos = np.asarray(camera.position.d if hasattr(camera.position, "d") else camera.position, float)
        focus = np.asarray(camera.focus.d if hasattr(camera.focus, "d") else camera.focus, float)
        north = np.asarray(camera.north_vector, float)
        width = np.asarray(camera.width.d if hasattr(camera.width, "d") else camera.width, float)
        ortho = type(camera.lens).__name__ == "PlaneParallelLens"
        distance = float(np.linalg.norm(focus - pos))
        fov = math.degrees(2.0 * math.atan(0.5 * float(width[1]) / distance)) if distance > 0 else 40.0
        return cls(position=pos, look_at=focus, up=north, fov=fov, orthographic=ortho, ortho_height=float(width[1]))

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

    def __init__(self, dataset, field=None, transfer_function=None, **settings):
        if not isinstance(dataset, Dataset):
            raise TypeError("Scene needs an exabricks.Dataset")
        self.dataset = dataset
        self._input = "" if dataset.name.startswith("<") else dataset.name
        self._renderer = _core.Renderer(dataset._core)  # holds the dataset alive
        field = field or dataset.default_field
        self.notes = []  # what the defaults chose, as the command line says on stderr
        if transfer_function is None:
            # The command line's first picture: log mapping for positive data spanning many
            # decades, transparent over the dominant background.
            tf_json, self.notes = dataset._core.adapt_transfer_function(
                field, json.dumps(TransferFunction().to_dict()), True, True)
            transfer_function = TransferFunction.from_dict(json.loads(tf_json))
        self.layers = [Layer(field, transfer_function)]
        self.volume = True
        self.iso_values = []
        self.iso_field = ""
        self.iso_colors = []
        self.iso_color_field = ""
        self.iso_color_map = TransferFunction("cool-to-warm")
        self.meshes = []  # (exabricks._core.Mesh, sRGB colour)
        self.clip_planes = []  # (point, normal)
        self.clip_box = None
        self.clip_meshes = False
        self.headlight = True
        self.light_direction = (-1.0, -1.0, -1.0)
        self.ambient, self.diffuse, self.specular, self.shininess = 0.3, 0.7, 0.25, 40.0
        self.shading = "analytic"
        self.ao_rays, self.ao_length, self.ao_volume = 0, 0.0, False
        self.sampling = "adaptive"
        self.early_termination = True
        self.space_skipping = True
        self.traversal = "auto"
        self.debug = "none"
        self.background = (0.0, 0.0, 0.0)
        self.alpha = False
        self.camera = None
        self.width, self.height = 800, 800
        self.spp = 1
        self.rate = 1.0
        self.seed = 0
        self.jitter = True
        for key, value in settings.items():
            if not hasattr(self, key):
                raise AttributeError("Scene has no setting '%s'" % key)
            setattr(self, key, value)
        if self.camera is None:
            self.camera = self.frame_visible()

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
        """The scene in the JSON form of `exabricks render --scene` (meshes made from arrays are
        written inline only with with_meshes)."""
        d = {
            "input": self._input,
            "camera": self.camera.to_dict() if self.camera is not None else Camera().to_dict(),
            "frame": {"width": int(self.width), "height": int(self.height), "samples_per_pixel": int(self.spp),
                      "rate": float(self.rate), "jitter": bool(self.jitter), "seed": int(self.seed)},
            "layers": [{"field": l.field, "transfer_function": l.transfer_function.to_dict()} for l in self.layers],
            "volume": bool(self.volume),
            "iso": {"field": self.iso_field, "values": [float(v) for v in self.iso_values],
                    "colors": [_srgb(c) for c in self.iso_colors], "color_field": self.iso_color_field,
                    "color_map": self.iso_color_map.to_dict()},
            "clip": {"planes": [{"point": list(map(float, p)), "normal": list(map(float, n))} for p, n in self.clip_planes],
                     "meshes": bool(self.clip_meshes)},
            "light": {"headlight": bool(self.headlight), "direction": list(map(float, self.light_direction)),
                      "ambient": float(self.ambient), "diffuse": float(self.diffuse),
                      "specular": float(self.specular), "shininess": float(self.shininess)},
            "shading": self.shading,
            "ambient_occlusion": {"rays": int(self.ao_rays), "length": float(self.ao_length),
                                  "volume": bool(self.ao_volume)},
            "integration": {"sampling": self.sampling, "traversal": self.traversal,
                            "space_skipping": bool(self.space_skipping),
                            "early_termination": bool(self.early_termination)},
            "debug": self.debug,
            "background": _srgb(self.background),
            "alpha": bool(self.alpha),
        }
        if not d["input"]:
            del d["input"]
        if self.clip_box is not None:
            d["clip"]["box"] = [float(v) for v in self.clip_box]
        if with_meshes and self.meshes:
            raise ValueError("meshes made from arrays are kept by the Scene; write them with the mesh files instead")
        return d

    def to_json(self):
        return json.dumps(self.to_dict(), indent=2)

    def save_json(self, path):
        """Writes the scene file `exabricks render --scene` reads."""
        with open(path, "w") as f:
            f.write(self.to_json() + "\n")

    @classmethod
    def from_json(cls, dataset, text):
        """A scene from scene-file JSON (as written by save_json or `render --write-scene`)."""
        d = json.loads(text)
        s = cls(dataset)
        if "camera" in d:
            c = d["camera"]
            s.camera = Camera(c.get("position", (0, 0, 1)), c.get("look_at", (0, 0, 0)), c.get("up", (0, 0, 1)),
                              c.get("fov", 40.0), c.get("orthographic", False), c.get("ortho_height", 1.0))
        f = d.get("frame", {})
        s.width, s.height = f.get("width", s.width), f.get("height", s.height)
        s.spp, s.rate = f.get("samples_per_pixel", s.spp), f.get("rate", s.rate)
        s.jitter, s.seed = f.get("jitter", s.jitter), f.get("seed", s.seed)
        if "layers" in d:
            s.layers = [Layer(l.get("field") or dataset.default_field,
                              TransferFunction.from_dict(l.get("transfer_function", {"opacity_scale": "auto"})))
                        for l in d["layers"]]
        s.volume = d.get("volume", True)
        iso = d.get("iso", {})
        s.iso_values = list(iso.get("values", []))
        s.iso_field = iso.get("field", "")
        s.iso_colors = [tuple(c) for c in iso.get("colors", [])]
        s.iso_color_field = iso.get("color_field", "")
        if "color_map" in iso:
            s.iso_color_map = TransferFunction.from_dict(iso["color_map"])
        for m in d.get("meshes", []):
            s.add_mesh(path=m["file"], color=m.get("color", (0.6, 0.6, 0.62)))
        clip = d.get("clip", {})
        s.clip_planes = [(tuple(p["point"]), tuple(p["normal"])) for p in clip.get("planes", [])]
        s.clip_box = tuple(clip["box"]) if clip.get("box") else None
        s.clip_meshes = clip.get("meshes", False)
        light = d.get("light", {})
        s.headlight = light.get("headlight", True)
        s.light_direction = tuple(light.get("direction", s.light_direction))
        for k in ("ambient", "diffuse", "specular", "shininess"):
            setattr(s, k, light.get(k, getattr(s, k)))
        s.shading = d.get("shading", s.shading)
        ao = d.get("ambient_occlusion", {})
        s.ao_rays, s.ao_length, s.ao_volume = ao.get("rays", 0), ao.get("length", 0.0), ao.get("volume", False)
        integ = d.get("integration", {})
        s.sampling = integ.get("sampling", s.sampling)
        s.traversal = integ.get("traversal", s.traversal)
        s.space_skipping = integ.get("space_skipping", True)
        s.early_termination = integ.get("early_termination", True)
        s.debug = d.get("debug", "none")
        s.background = tuple(d.get("background", s.background))
        s.alpha = d.get("alpha", False)
        return s

    # -- rendering ----------------------------------------------------------------------------
    def _frame_json(self, width, height, spp, rate):
        return json.dumps({"camera": self.camera.to_dict(),
                           "frame": {"width": int(width), "height": int(height), "samples_per_pixel": int(spp),
                                     "rate": float(rate), "jitter": bool(self.jitter), "seed": int(self.seed)}})

    def _scene_json(self):
        """The scene without camera, frame and input: what the renderer takes."""
        d = self.to_dict()
        for key in ("camera", "frame", "input"):
            d.pop(key, None)
        return json.dumps(d)

    def _update(self):
        return self._renderer.set_scene(self._scene_json(), [(m, c) for m, c in self.meshes])

    def render(self, width=None, height=None, spp=None, rate=None):
        """Renders the scene: an (H, W, 4) float32 array of linear RGB premultiplied by alpha (row 0
        at the top). The GIL is released while rendering; Ctrl-C cancels."""
        self.render_progressive(width, height, spp, rate, passes=spp or self.spp)
        return self._renderer.image()

    def render_progressive(self, width=None, height=None, spp=None, rate=None, passes=0):
        """Adds passes to the scene's accumulation buffer (one pass when `passes` is 0; otherwise
        until it holds `passes`) and returns the passes it holds. The buffer starts over when the
        scene or the frame changes; `samples_per_pixel` of the frame is `spp` (or `passes`)."""
        w, h = int(width or self.width), int(height or self.height)
        target = int(spp or self.spp)
        self._update()
        return self._renderer.render(self._frame_json(w, h, max(target, passes or 1), rate or self.rate), int(passes))

    def image(self):
        """The accumulated image as an (H, W, 4) float32 array (linear, premultiplied)."""
        return self._renderer.image()

    def stats(self):
        """Statistics of the passes in the buffer: seconds, rays, samples, regions visited, ..."""
        return dict(self._renderer.stats())

    def save(self, path, width=None, height=None, spp=None):
        """Renders and writes an 8-bit sRGB PNG (over the background unless `alpha`)."""
        self.render(width, height, spp)
        self._renderer.save(str(path))

    def png(self, width=None, height=None, spp=None):
        """Renders and returns the PNG bytes."""
        self.render(width, height, spp)
        return self._renderer.png()

    def pick(self, origin, direction):
        """The nearest iso-surface or mesh hit along a world ray (dict), or None."""
        self._update()
        return self._renderer.pick(list(map(float, origin)), list(map(float, direction)))

    def _repr_png_(self):
        w = min(int(self.width), 640)
        h = max(1, int(round(self.height * w / self.width)))
        return self.png(w, h)

    def widget(self, width=512, height=512, preview=4, passes=16):
        """An interactive view in Jupyter (ipywidgets): orbit, transfer-function range and
        opacity, iso-value; each change renders a preview, then refines progressively."""
        from .widget import SceneWidget
        return SceneWidget(self, width, height, preview, passes).widget
