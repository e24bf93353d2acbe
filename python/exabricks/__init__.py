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
import math
import os
import warnings

import numpy as np

from . import _core

__all__ = [
    "Dataset", "TransferFunction", "Camera", "Scene", "load", "from_cells", "from_grids", "from_yt",
    "colormap_names", "list_fields", "scene_vocabulary", "read_png", "Series",
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
    def units(self):
        """Units per field name, as the input states them ("" where unknown): read by the file's
        reader, given to from_cells / from_grids, or taken from yt by from_yt."""
        return dict(zip(self._core.fields, self._core.units))

    def field_units(self, name=None):
        """The units of a field (the default field when None); "" where unknown."""
        fields = list(self._core.fields)
        name = name or self.default_field
        if name not in fields:
            raise ValueError("unknown field '%s' (the dataset has %s)" % (name, ", ".join(fields)))
        return self._core.units[fields.index(name)]

    def field_label(self, name=None):
        """The title the command line's colour bar gives a field: "name [units]", or the name
        alone where its units are unknown."""
        name = name or self.default_field
        units = self.field_units(name)
        return "%s [%s]" % (name, units) if units else name

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
    def opacity_reference_width(self):
        """The world length opacity is given per: the finest cell's width (averaged over the
        axes where the spacing differs)."""
        return self._core.opacity_reference_width

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


def load(path=None, fields=None, max_brick_width=32, box=None, nan_as_holes=False):
    """Reads any input the command line reads (model file, NAME.cells, AMReX, Chombo, FLASH, Enzo,
    VTK AMR, raw volume; the embedded default dataset when path is None) and builds it.
    `box` (x0, y0, z0, x1, y1, z1, finest lattice units) keeps only the cells that overlap it.
    `nan_as_holes`: cells with a NaN or infinite value in any loaded field become holes (dropped
    from every field, counted on stderr) instead of an error (as `--nan-as-holes`)."""
    return Dataset(_core.load("" if path is None else str(path), list(fields or []), max_brick_width,
                              list(box) if box is not None else [], bool(nan_as_holes)))


def _units_list(units, names):
    """Units per name from a dict (missing names have none) or a list in the names' order."""
    if units is None:
        return []
    if isinstance(units, dict):
        unknown = [k for k in units if k not in names]
        if unknown:
            raise ValueError("units given for %s, which are not among the fields %s" % (unknown, list(names)))
        return [str(units.get(n) or "") for n in names]
    units = [str(u or "") for u in units]
    if len(units) != len(names):
        raise ValueError("%d units given for %d fields" % (len(units), len(names)))
    return units


def from_cells(corners, levels, fields, origin=(0.0, 0.0, 0.0), spacing=(1.0, 1.0, 1.0), max_brick_width=32,
               units=None):
    """A dataset from leaf cells: integer lower corners (N, 3) in finest-lattice units, levels (N,)
    (a cell is 2**level finest cells wide; corners are multiples of the width), and one (N,) array
    per field in a dict. World = origin + spacing * lattice. A non-dict `fields` is the field
    "scalar". `units`: a dict of units per field name (or a list in field order)."""
    if not isinstance(fields, dict):
        fields = {"scalar": fields}
    pairs = [(str(name), np.asarray(values)) for name, values in fields.items()]
    unit_list = _units_list(units, [name for name, _ in pairs])
    for name, values in pairs:
        if values.dtype.kind not in "fiu":
            raise ValueError("field '%s' must hold numbers, not %s" % (name, values.dtype))
    corners = np.asarray(corners)
    levels = np.asarray(levels)
    if corners.dtype.kind not in "iu" or levels.dtype.kind not in "iu":
        raise ValueError("corners and levels must be integer arrays (finest-lattice units)")
    return Dataset(_core.from_cells(corners, levels, pairs, list(map(float, origin)), list(map(float, spacing)),
                                    max_brick_width, unit_list))


def from_grids(grids, fields=None, bbox=None, max_brick_width=32, units=None):
    """A dataset from overlapping grids in the layout yt's load_amr_grids takes: a list of dicts
    with "left_edge", "right_edge", "level", "dimensions" and one array per field of shape
    `dimensions` (indexed [i, j, k]). Cells covered by a finer grid are dropped. `bbox`
    ([[x0, x1], [y0, y1], [z0, z1]], optional) gives the domain, whose lower corner is the lattice
    origin. `units`: a dict of units per field name (or a list in field order)."""
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
    names = [str(n) for n in names]
    return Dataset(_core.from_grids(packed, names, origin, max_brick_width, _units_list(units, names)))


def _yt_field_name(field):
    return field[-1] if isinstance(field, tuple) else str(field)


def _yt_mesh_fields(ds):
    """The fields yt holds on the grids (not particles), in the file's order where yt keeps it
    (AMReX plotfiles), else in yt's order."""
    index = ds.index
    order = list(getattr(index, "field_order", None) or ds.field_list)
    particle_types = set(getattr(ds, "particle_types", ())) | set(getattr(ds, "particle_types_raw", ()))
    fields = []
    for f in order:
        if isinstance(f, tuple) and f[0] in particle_types:
            continue
        info = getattr(ds, "field_info", None)
        try:
            if info is not None and info[f].sampling_type == "particle":
                continue
        except (KeyError, AttributeError, TypeError):
            pass
        fields.append(f)
    return fields


def _yt_default_field(ds):
    """The field the command line would take from the same output: among the mesh fields, the
    principal one where the data names it, else the first."""
    fields = _yt_mesh_fields(ds)
    if not fields:
        raise ValueError("from_yt: the dataset has no mesh fields (only particles, which exabricks does not "
                         "render); yt lists %s" % (list(ds.field_list),))
    return fields[_core.default_field_index([_yt_field_name(f) for f in fields])]


def _yt_units(values):
    """The units of an array yt returned, as yt writes them; "" for none ("dimensionless": yt's
    word for a field whose units the output does not state, or a pure number)."""
    units = getattr(values, "units", None)
    text = str(units) if units is not None else ""
    return "" if text in ("dimensionless", "1") else text


def _yt_code(value):
    """A yt length (or array of lengths) in code units: the world units of from_yt."""
    if hasattr(value, "in_units"):
        try:
            return np.array(value.in_units("code_length").d, dtype=np.float64)
        except Exception:  # no code units in its registry: take the numbers
            pass
    return np.array(value.d if hasattr(value, "d") else value, dtype=np.float64)


def from_yt(ds, fields=None, max_brick_width=32):
    """A dataset from a loaded yt dataset (any code yt reads, through ds.index.grids): the leaf
    cells of its grids with the given fields (yt field names or (type, name) tuples). Without
    fields, the mesh field the command line would choose: the principal one where the data names
    it (scalar, Density, density, dens, rho), else the first in the file's order; particle fields
    are never taken. Values are taken in yt's units, and each field carries the units of the data
    yt returns (Dataset.units; "" where yt has none but "dimensionless"). World coordinates are
    yt's code units."""
    if fields is None:
        fields = [_yt_default_field(ds)]
    elif isinstance(fields, (str, tuple)):
        fields = [fields]
    names = [_yt_field_name(f) for f in fields]
    units = {}
    grids = []
    for grid in ds.index.grids:
        entry = {
            "left_edge": _yt_code(grid.LeftEdge),
            "right_edge": _yt_code(grid.RightEdge),
            "level": int(grid.Level),
            "dimensions": [int(d) for d in grid.ActiveDimensions],
        }
        for f, name in zip(fields, names):
            values = grid[f]
            if name not in units:
                units[name] = _yt_units(values)
            entry[name] = np.asarray(values.d if hasattr(values, "d") else values, dtype=np.float64)
        grids.append(entry)
        grid.clear_data()
    left = _yt_code(ds.domain_left_edge)
    right = _yt_code(ds.domain_right_edge)
    bbox = [[left[a], right[a]] for a in range(3)]
    dataset = from_grids(grids, names, bbox=bbox, max_brick_width=max_brick_width, units=units)
    dataset._yt_origin = _yt_origin(ds, fields, names, units)
    return dataset


def _yt_origin(ds, fields, names, units):
    """What the command line reads for a dataset made from yt: the output's path, and per field
    (by its name here) the field's name in the file and the factor from the file's values to
    yt's (yt converts code units; the command line reads the file's numbers). A field yt derives
    (no field of the file behind it) maps to None."""
    path = getattr(ds, "parameter_filename", None)
    origin = {"input": os.path.abspath(path) if path and os.path.exists(path) else None, "fields": {}}
    on_disk = set(ds.field_list)
    for f, name in zip(fields, names):
        entry = None
        try:
            info = ds._get_field_info(f)
            disk = info.alias_name if getattr(info, "is_alias", False) else info.name
            if disk in on_disk:
                disk_units = str(ds._get_field_info(disk).units or "") or "dimensionless"
                factor = float(ds.quan(1.0, disk_units).to(units.get(name) or "dimensionless").d)
                if factor > 0 and np.isfinite(factor):
                    entry = (_yt_field_name(disk), factor)
        except Exception:  # yt cannot say: the field stays yt's
            entry = None
        origin["fields"][name] = entry
    return origin


def _yt_scene_units(d, origin, to_file):
    """A scene document of a dataset made from yt, with yt's field names and units (to_file
    False) or the file's (to_file True, with the output's path as its input): field names
    mapped, value ranges and iso-values scaled. Where a field the scene shows has no field of the
    file behind it (yt derives it), or the output's path is unknown, the document is returned as
    it is (to_file: with a warning, since the command line cannot read it)."""
    fields = origin["fields"]
    if to_file:
        table = {name: entry for name, entry in fields.items() if entry is not None}
    else:
        table = {entry[0]: (name, entry[1]) for name, entry in fields.items() if entry is not None}
    d = copy.deepcopy(d)
    layers = d.get("layers", [])
    iso = d.get("iso", {})
    first = layers[0]["field"] if layers else ""
    shown = [l["field"] for l in layers]
    if iso.get("values"):
        shown.append(iso.get("field") or first)
    if iso.get("color_field"):
        shown.append(iso["color_field"])
    missing = [n for n in shown if n and n not in table]
    if missing or (to_file and not origin["input"]):
        if to_file:
            why = ("yt derives %s: no field of the file lies behind it" % ", ".join("'%s'" % n for n in missing)
                   if missing else "yt does not say which file the data came from")
            warnings.warn("the scene file names no input the command line can read (%s)" % why, stacklevel=3)
        return d

    def scale(name):
        factor = table[name][1]
        return 1.0 / factor if to_file else factor

    def scaled_range(tf, name):
        if tf.get("range") is not None:
            tf["range"] = [float(v) * scale(name) for v in tf["range"]]

    for layer in layers:
        if layer["field"]:
            scaled_range(layer["transfer_function"], layer["field"])
            layer["field"] = table[layer["field"]][0]
    if iso.get("values"):
        name = iso.get("field") or first
        if name:
            iso["values"] = [float(v) * scale(name) for v in iso["values"]]
            if iso.get("field"):
                iso["field"] = table[iso["field"]][0]
    if iso.get("color_field"):
        scaled_range(iso["color_map"], iso["color_field"])
        iso["color_field"] = table[iso["color_field"]][0]
    if to_file:
        d["input"] = origin["input"]
    return d


def _file_stem(text):
    """A name fit for a file: letters, digits, '.', '-' and '_' kept, the rest '_'."""
    stem = "".join(c if c.isalnum() or c in "._-" else "_" for c in str(text)).strip("._")
    return stem or "picture"


def _srgb_encode(linear):
    """sRGB numbers of linear intensities in [0, 1]."""
    c = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    return [float(v) for v in np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1.0 / 2.4) - 0.055)]


def _longest_side(bounds):
    return float(np.max(np.asarray(bounds[1], float) - np.asarray(bounds[0], float)))


def _yt_ray_length(camera):
    """The world length (code units) of one unit of yt's ray parameter: yt's alpha is opacity per
    this length. A plane-parallel lens casts its rays across the depth width; perspective and
    spherical lenses scale their rays to reach the whole domain from the camera (the central
    ray's length; yt's off-axis rays are longer); a fisheye lens to the largest width."""
    lens = type(camera.lens).__name__
    if lens == "PlaneParallelLens":
        return float(_yt_code(camera.width)[2])
    if lens in ("PerspectiveLens", "StereoPerspectiveLens", "SphericalLens", "StereoSphericalLens"):
        centre = _yt_code(camera._domain_center)
        return float(np.linalg.norm(_yt_code(camera.position) - centre)
                     + 0.5 * np.linalg.norm(_yt_code(camera._domain_width)))
    if lens == "FisheyeLens":
        return float(_yt_code(camera.width).max())
    raise ValueError("TransferFunction.from_yt: yt's %s is not known" % lens)


def _srgb(color):
    c = [float(x) for x in color]
    if len(c) != 3 or not all(0.0 <= x <= 1.0 for x in c):
        raise ValueError("a colour is three sRGB numbers in [0, 1], not %r" % (color,))
    return c


# Every setting of a scene file with the library's defaults.
_DEFAULT_DOCUMENT = json.loads(_core.scene_json("{}", "defaults"))

# The scalar settings of a scene file as the library describes them (key, name, type, default,
# range, choices, help): each is the Scene attribute of its name.
_VOCABULARY = json.loads(_core.scene_vocabulary())
_TYPES = {"boolean": bool, "integer": int, "number": float, "choice": str}


def scene_vocabulary():
    """The scalar settings of a scene file: a list of dicts with "key" (the path in the file),
    "name" (the Scene attribute), "type", "default", "min"/"max" where bounded, "choices" and "help"."""
    return copy.deepcopy(_VOCABULARY)


def _document_value(doc, key):
    for part in key.split("."):
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
                   opacity_scale=d.get("opacity_scale", "auto"))

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
        if not hasattr(tf, "funcs") and hasattr(tf, "transfer_function"):  # a VolumeSource
            if log is None:
                log = bool(getattr(tf, "log_field", True))
            tf = tf.transfer_function
        log = True if log is None else bool(log)
        channels = [np.asarray(f.y, dtype=np.float64) for f in tf.funcs[:4]]
        x = np.asarray(tf.funcs[0].x, dtype=np.float64)
        x0, x1 = float(x[0]), float(x[-1])
        if not x1 > x0:
            raise ValueError("the yt transfer function spans no range")
        if points is None:
            idx = np.arange(len(x))
        else:
            idx = np.unique(np.linspace(0, len(x) - 1, max(2, int(points))).round().astype(int))
        t = (x[idx] - x0) / (x1 - x0)
        t[0], t[-1] = 0.0, 1.0
        rgb = np.clip(np.stack([c[idx] for c in channels[:3]], axis=1), 0.0, 1.0)
        alpha = np.clip(channels[3][idx], 0.0, None)
        alpha[0] = alpha[-1] = 0.0  # yt's tables give nothing at and beyond their bounds
        if dataset is not None:
            # Without a camera, that of yt's create_scene: a depth width of 1.5 times the longest side.
            length = _yt_ray_length(camera) if camera is not None else 1.5 * _longest_side(dataset.bounds)
            alpha = -np.expm1(-alpha * float(dataset.opacity_reference_width) / length)
            scale = float(alpha.max())
        elif camera is not None:
            raise ValueError("TransferFunction.from_yt: converting for a yt camera needs the exabricks dataset "
                             "(dataset=...), whose finest cell the opacity is given per")
        else:
            scale = "auto"
        peak = float(alpha.max())
        if peak > 0:
            alpha = alpha / peak
        elif scale != "auto":
            scale = 1.0  # nothing is visible; the scale must stay positive
        # Colour map points are sRGB; the renderer integrates their linear values.
        colormap = [(float(ti),) + tuple(_srgb_encode(c)) for ti, c in zip(t, rgb)]
        opacity = [(float(ti), float(a)) for ti, a in zip(t, alpha)]
        value_range = (10.0 ** x0, 10.0 ** x1) if log else (x0, x1)
        return cls(colormap=colormap, opacity=opacity, range=value_range, log=log, opacity_scale=scale)

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
        """The position, focus, north vector and width of a yt camera, in code units (the world
        units of from_yt): orthographic with yt's height when its lens is plane-parallel, else a
        perspective whose vertical angle is yt's, 2 atan(height / (2 depth width)). A
        plane-parallel lens casts its rays from the near face of a slab one depth width thick
        around the focus: the orthographic camera sits on that face (Scene.from_yt also clips the
        far one)."""
        pos = _yt_code(camera.position)
        focus = _yt_code(camera.focus)
        north = np.asarray(camera.north_vector, float)
        width = _yt_code(camera.width)
        ortho = type(camera.lens).__name__ == "PlaneParallelLens"
        if ortho:
            pos = focus - _yt_view_direction(camera) * (0.5 * float(width[2]))
        else:
            # yt's perspective lens makes the height the width times the resolution's aspect
            # when it renders.
            resolution = [float(r) for r in camera.resolution]
            width[1] = width[0] * resolution[1] / resolution[0]
        fov = math.degrees(2.0 * math.atan(0.5 * float(width[1]) / float(width[2]))) if width[2] > 0 else 40.0
        return cls(position=pos, look_at=focus, up=north, fov=fov, orthographic=ortho, ortho_height=float(width[1]))

    def to_dict(self):
        return {"position": list(self.position), "look_at": list(self.look_at), "up": list(self.up),
                "fov": self.fov, "orthographic": self.orthographic, "ortho_height": self.ortho_height}

    def __repr__(self):
        return "Camera(position=%s, look_at=%s, up=%s, fov=%g)" % (self.position, self.look_at, self.up, self.fov)


def _yt_view_direction(camera):
    """The unit vector from a yt camera's position to its focus."""
    d = _yt_code(camera.focus) - _yt_code(camera.position)
    return d / np.linalg.norm(d)


# The settings of a scene converted from yt unless told otherwise: yt does not light volumes, and
# its pictures show no sampling noise.
_YT_DEFAULTS = {"shading": "none", "spp": 8}


def _yt_view(camera, source, dataset):
    """What a yt camera and volume source give a Scene of `dataset`: the transfer function
    (TransferFunction.from_yt, converted for the camera) and the settings camera, width, height
    (yt's resolution is (width, height)) and clip_planes (a plane-parallel lens's slab ends one
    half depth width beyond the focus)."""
    width, height = [int(r) for r in camera.resolution]
    planes = []
    if type(camera.lens).__name__ == "PlaneParallelLens":
        w = _yt_code(camera.width)
        if abs(w[0] * height - w[1] * width) > 1e-6 * abs(w[0] * height):
            raise ValueError("the yt camera's width %g x %g does not have the aspect of its resolution %d x %d: "
                             "exabricks renders square pixels (set the width to the resolution's aspect)"
                             % (w[0], w[1], width, height))
        n = _yt_view_direction(camera)
        far = _yt_code(camera.focus) + n * (0.5 * float(w[2]))
        planes.append((tuple(map(float, far)), tuple(map(float, n))))
    tf = TransferFunction.from_yt(source, camera=camera, dataset=dataset)
    return tf, {"camera": Camera.from_yt(camera), "width": width, "height": height, "clip_planes": planes}


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
        for setting in _VOCABULARY:  # the scalar settings, with the library's defaults
            setattr(self, setting["name"], setting["default"])
        self.iso_values = []
        self.iso_field = ""
        self.iso_colors = []
        self.iso_color_field = ""
        self.iso_color_map = TransferFunction("cool-to-warm")
        self.meshes = []  # (exabricks._core.Mesh, sRGB colour)
        self.clip_planes = []  # (point, normal)
        self.clip_box = None
        self.light_direction = tuple(_DEFAULT_DOCUMENT["light"]["direction"])
        # Path tracing (integrator "pathtrace"): linear environment radiance, the sun's direction of travel.
        self.environment = tuple(_DEFAULT_DOCUMENT["pathtrace"]["environment"])
        self.sun_direction = tuple(_DEFAULT_DOCUMENT["pathtrace"]["sun_direction"])
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
        """The scene in the JSON form of `exabricks render --scene` (meshes made from arrays are
        written inline only with with_meshes)."""
        d = {
            "input": self._input,
            "camera": self.camera.to_dict() if self.camera is not None else Camera().to_dict(),
            "layers": [{"field": l.field, "transfer_function": l.transfer_function.to_dict()} for l in self.layers],
            "iso": {"field": self.iso_field, "values": [float(v) for v in self.iso_values],
                    "colors": [_srgb(c) for c in self.iso_colors], "color_field": self.iso_color_field,
                    "color_map": self.iso_color_map.to_dict()},
            "clip": {"planes": [{"point": list(map(float, p)), "normal": list(map(float, n))} for p, n in self.clip_planes]},
            "light": {"direction": list(map(float, self.light_direction))},
            "pathtrace": {"environment": list(map(float, self.environment)),
                          "sun_direction": list(map(float, self.sun_direction))},
            "background": _srgb(self.background),
        }
        for setting in _VOCABULARY:
            _set_document_value(d, setting["key"], _TYPES[setting["type"]](getattr(self, setting["name"])))
        if not d["input"]:
            del d["input"]
        if self.clip_box is not None:
            d["clip"]["box"] = [float(v) for v in self.clip_box]
        # Meshes read from files are recorded by their file; those made from arrays are not.
        files = [{"file": m.source, "color": _srgb(c)} for m, c in self.meshes if m.source]
        if files:
            d["meshes"] = files
        if with_meshes and len(files) < len(self.meshes):
            raise ValueError("meshes made from arrays are kept by the Scene; write them with the mesh files instead")
        if self.camera_path is not None:
            d["camera_path"] = copy.deepcopy(self.camera_path)
        return d

    def to_json(self):
        """The scene file's text, as the command line writes it (every setting; checked by its
        reader). For a dataset made from yt (from_yt), the file names what the command line reads:
        the output's path, the file's field names and values in the file's units."""
        d = self.to_dict()
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
            setattr(s, setting["name"], _document_value(d, setting["key"]))
        if "layers" in given:
            s.layers = [Layer(l["field"] or dataset.default_field, TransferFunction.from_dict(l["transfer_function"]))
                        for l in d["layers"]]
        iso = d["iso"]
        s.iso_values = list(iso["values"])
        s.iso_field = iso["field"]
        s.iso_colors = [tuple(c) for c in iso["colors"]]
        s.iso_color_field = iso["color_field"]
        s.iso_color_map = TransferFunction.from_dict(iso["color_map"])
        for m in d["meshes"]:
            if "file" not in m:
                raise ValueError("%s: meshes given inline are not read into a Scene; add them with add_mesh" % source)
            s.add_mesh(path=m["file"], color=m["color"])
        clip = d["clip"]
        s.clip_planes = [(tuple(p["point"]), tuple(p["normal"])) for p in clip["planes"]]
        s.clip_box = tuple(clip["box"]) if clip.get("box") else None
        s.light_direction = tuple(d["light"]["direction"])
        s.environment = tuple(d["pathtrace"]["environment"])
        s.sun_direction = tuple(d["pathtrace"]["sun_direction"])
        s.background = tuple(d["background"])
        s.camera_path = d.get("camera_path")
        return s

    @classmethod
    def from_yt(cls, scene, dataset=None, source=None, **settings):
        """The scene of a yt Scene: the field of its volume source (the first unless `source` is
        given) as a dataset (from_yt, unless `dataset` is given), its transfer function with the
        opacity converted for its camera (TransferFunction.from_yt), its camera and resolution,
        no shading (yt's volume rendering does not light) and 8 samples per pixel (yt's pictures
        show no sampling noise; 8 jittered passes hide it at yt's resolutions). The settings of an
        exabricks.yt.ExaBricksSource apply over these, and `settings` over all. Its render's image
        array agrees in exposure with the one yt's render returns."""
        if source is None:
            volumes = [s for s in scene.sources.values() if hasattr(s, "transfer_function") and hasattr(s, "field")]
            if not volumes:
                raise ValueError("Scene.from_yt: the yt scene has no volume source")
            source = volumes[0]
        field = source.field
        if dataset is None:
            dataset = from_yt(source.data_source.ds, [field])
        tf, defaults = _yt_view(scene.camera, source, dataset)
        defaults.update(_YT_DEFAULTS)
        defaults.update(getattr(source, "exabricks_settings", {}))
        defaults.update(settings)
        return cls(dataset, field=_yt_field_name(field), transfer_function=tf, **defaults)

    # -- rendering ----------------------------------------------------------------------------
    def _frame_json(self, width, height, spp, rate):
        return json.dumps({"camera": self.camera.to_dict(),
                           "frame": {"width": int(width), "height": int(height), "samples_per_pixel": int(spp),
                                     "rate": float(rate), "jitter": bool(self.jitter), "seed": int(self.seed)}})

    def _scene_json(self):
        """The scene without camera, frame, input, camera path and mesh files (the meshes go to the
        renderer as made): what the renderer takes."""
        d = self.to_dict()
        for key in ("camera", "frame", "input", "camera_path", "meshes"):
            d.pop(key, None)
        return json.dumps(d)

    def _update(self):
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
        return self._renderer.render(self._frame_json(w, h, max(target, passes or 1), rate or self.rate), int(passes),
                                     depth_limit, bool(depth_limit_planar))

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
        as yt's own Scene.save does (a scene converted from yt then looks as yt saves it)."""
        self.render(width, height, spp)
        if path is None:
            w, h = self.width, self.height
            name = os.path.splitext(os.path.basename(str(self.dataset.name).rstrip("/")))[0]
            path = "%s-%s-%dx%d.png" % (_file_stem(name), _file_stem(self.field or "volume"), w, h)
        self._renderer.save(str(path), int(bits), bool(normalize))
        return str(path)

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


from .series import Series  # noqa: E402  (it uses Dataset and Scene above)
