"""Datasets and scenes from yt's objects: from_yt (the leaf cells of a yt dataset's grids),
TransferFunction.from_yt, Camera.from_yt and Scene.from_yt, and the scene files of a dataset made
from yt (its field names and units against the file's). yt itself is not imported here: these
read the objects yt hands over. exabricks.yt, yt's render source, is built on them."""

import copy
import math
import os
import warnings

import numpy as np

from . import _core
from ._dataset import from_grids


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
    dataset._particle_source = lambda species: _yt_particles(ds, species)
    return dataset


def _yt_particles(ds, species):
    """yt's particles of a dataset, as Dataset.particles gives them: per particle type yt reads
    from the file (ds.particle_types_raw), "position" (N, 3) in code units and each other field of
    the type by name without its "particle_" prefix; None lists the types with their counts and
    attributes (Dataset.particle_species)."""
    ad = ds.all_data()
    out = {}
    for ptype in ds.particle_types_raw:
        names = sorted(f for t, f in ds.field_list if t == ptype)
        if not all("particle_position_" + a in names for a in "xyz"):
            continue
        attributes = [n for n in names if not n.startswith("particle_position_")]
        if species is None:
            count = int(ad[ptype, "particle_position_x"].shape[0])
            out[ptype] = {"name": ptype, "count": count, "attributes": [_strip(a) for a in attributes],
                          "precision": "double"}
            continue
        if species != "" and species != ptype:
            continue
        d = {"position": np.stack([_yt_code(ad[ptype, "particle_position_" + a]) for a in "xyz"], axis=1)}
        for a in attributes:
            v = ad[ptype, a]
            d[_strip(a)] = np.asarray(v.d if hasattr(v, "d") else v)
        out[ptype] = d
    if species not in (None, "") and species not in out:
        raise ValueError("no particle species '%s' (yt reads: %s)" % (species, ", ".join(ds.particle_types_raw)))
    return out


def _strip(name):
    return name[len("particle_"):] if name.startswith("particle_") else name


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


def transfer_function_from_yt(cls, tf, log=None, points=None, camera=None, dataset=None):
    """What TransferFunction.from_yt returns (documented there), as a `cls`."""
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


def camera_from_yt(cls, camera):
    """What Camera.from_yt returns (documented there), as a `cls`."""
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
    from . import Camera, TransferFunction

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


def scene_from_yt(cls, scene, dataset=None, source=None, **settings):
    """What Scene.from_yt returns (documented there), as a `cls`."""
    if source is None:
        volumes = [s for s in scene.sources.values() if hasattr(s, "transfer_function") and hasattr(s, "field")]
        if not volumes:
            raise ValueError("Scene.from_yt: the yt scene has no volume source")
        source = volumes[0]
    field = source.field
    if dataset is None:
        dataset = from_yt(source.data_source.ds, [field])
    tf, defaults = _yt_view(scene.camera, source, dataset)
    name, factor = _field_of_dataset(source.data_source.ds, field, dataset)
    if factor != 1.0 and tf.range is not None:
        tf.range = tuple(float(v) * factor for v in tf.range)
    defaults.update(_YT_DEFAULTS)
    defaults.update(getattr(source, "exabricks_settings", {}))
    defaults.update(settings)
    return cls(dataset, field=name, transfer_function=tf, **defaults)


def _field_of_dataset(ds, field, dataset):
    """The field of `dataset` that holds yt's `field`, and the factor from the yt field's values to
    that field's: the same name (factor 1), else a field of the dataset made from yt that reads the
    same field of the file (yt's alias of it in other units: ("gas", "density") for Enzo's
    "Density", in g/cm**3 where the dataset holds code units)."""
    name = _yt_field_name(field)
    if name in dataset.fields:
        return name, 1.0
    held = (getattr(dataset, "_yt_origin", None) or {}).get("fields", {})
    try:
        units = str(ds._get_field_info(field).units or "")
    except Exception:  # yt cannot say
        units = ""
    mine = _yt_origin(ds, [field], [name], {name: units})["fields"][name]
    for other, entry in held.items():
        if mine is not None and entry is not None and entry[0] == mine[0]:
            return other, entry[1] / mine[1]
    raise ValueError("the yt scene shows %r, which the dataset does not hold (fields: %s)%s: make the dataset with "
                     "exabricks.from_yt(ds, [%r])" % (field, ", ".join(dataset.fields),
                                                      "" if mine is None else ", nor the file's field '%s' behind it"
                                                      % mine[0], field))
