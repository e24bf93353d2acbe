"""exabricks as a render source of yt's volume rendering (yt 4).

    import yt
    from exabricks.yt import ExaBricksSource

    sc = yt.create_scene(ds, ("boxlib", "density"))          # or Scene() and sc.add_camera(ds)
    source = ExaBricksSource(ds, ("boxlib", "density"))
    sc.sources[list(sc.sources)[0]] = source                 # in place of yt's volume source
    sc.annotate_domain(ds, color=[1, 1, 1, 1])               # opaque sources composite with it
    sc.save("density.png")

ExaBricksSource is a yt VolumeSource: it takes yt's camera (position, focus, north vector, width,
resolution; plane-parallel and perspective lenses), transfer function (the one yt builds by
default too) and log setting, renders the leaf cells of the data with exabricks, and composites
with the opaque sources yt drew before it (boxes, lines, axes): each pixel's rays end at the
depth yt's z-buffer holds there, and what lies behind shows through the volume in front of it.
See docs/python.md, "yt render source".
"""

import numpy as np
from yt.data_objects.image_array import ImageArray
from yt.visualization.volume_rendering.render_source import VolumeSource
from yt.visualization.volume_rendering.transfer_functions import ProjectionTransferFunction
from yt.visualization.volume_rendering.zbuffer_array import ZBuffer

from . import Scene
from ._yt_scene import _YT_DEFAULTS, _yt_code, _yt_field_name, _yt_view, _yt_view_direction, from_yt

__all__ = ["ExaBricksSource"]

_LENSES = ("PlaneParallelLens", "PerspectiveLens")


def _exabricks_layout(a):
    """An array in yt's image layout, [i, j] with i along the camera's east vector and j along its
    north vector (before Scene.composite turns it by 180 degrees), in exabricks' layout, (row,
    column) with row 0 at the top; and back (the same exchange)."""
    return a[::-1, ::-1].swapaxes(0, 1)


def _view_depth(camera, z, origin):
    """yt's z-buffer as depth along the view direction from the plane through `origin` (the
    exabricks camera's position) across it, in code units, in yt's layout; +inf where yt has
    none."""
    z = np.asarray(z, dtype=np.float64)
    n = _yt_view_direction(camera)
    if type(camera.lens).__name__ == "PlaneParallelLens":
        # PlaneParallelLens.project_to_plane measures the depth back towards the camera from the
        # far face of the slab, half a depth width beyond the focus.
        far = _yt_code(camera.focus) + n * (0.5 * float(_yt_code(camera.width)[2]))
        offset, sign = float(np.dot(far - origin, n)), -1.0
    else:  # PerspectiveLens.project_to_plane: from the camera position along the view direction
        offset, sign = float(np.dot(_yt_code(camera.position) - origin, n)), 1.0
    finite = np.isfinite(z)
    depth = np.full(z.shape, np.inf)
    depth[finite] = np.maximum(offset + sign * z[finite], 0.0)
    return depth


class ExaBricksSource(VolumeSource):
    """A yt volume source rendered by exabricks, made as yt's VolumeSource(data_source, field) is:
    `data_source` is a yt dataset, its all_data() or a box of it (ds.region / ds.box: the volume
    is clipped to the box). Add it to a yt Scene with sc.add_source(source).

    The source's transfer_function, log_field (and set_log, set_transfer_function, tfh) work as
    yt's; without a transfer function it builds yt's default one. Each render converts yt's
    camera and transfer function as Scene.from_yt does (TransferFunction.from_yt, Camera.from_yt)
    and renders at the camera's resolution. The exabricks dataset of a field is built once, on
    the first render, and kept: later renders with another camera or transfer function only
    render again. `settings` (spp, rate, shading, ...) are those of exabricks.Scene, over the
    defaults of a scene converted from yt (Scene.from_yt): 8 samples per pixel and no shading.
    The scene itself is `exabricks_scene` after the first render.

    The image is yt's: (width, height, 4) float64, i along the camera's east vector, linear RGB
    premultiplied by alpha (alpha 1 unless the transfer function has grey_opacity, as yt's
    VolumeSource gives it), the opaque sources' image behind the volume composited into it. The
    volume is seen from the camera's position towards its focus."""

    volume_method = "ExaBricks"

    def __init__(self, data_source, field, **settings):
        super().__init__(data_source, field)
        _check_settings(settings)
        self.exabricks_settings = dict(settings)
        self._datasets = {}  # exabricks dataset per field
        self._scene = None
        self._clip_box = _clip_box(self.data_source)

    @property
    def exabricks_scene(self):
        """The exabricks Scene of the last render (None before the first)."""
        return self._scene

    def exabricks_dataset(self):
        """The exabricks dataset of the source's field, built on first use and kept."""
        key = self.field
        if key not in self._datasets:
            self._datasets[key] = from_yt(self.data_source.ds, [key])
        return self._datasets[key]

    def _get_volume(self):
        return self.exabricks_dataset()

    def _validate(self):
        super()._validate()
        if isinstance(self.transfer_function, ProjectionTransferFunction):
            raise ValueError("ExaBricksSource renders emission and absorption; yt's ProjectionTransferFunction "
                             "(a projection) is not one of its transfer functions")

    def _update_scene(self, camera):
        lens = type(camera.lens).__name__
        if lens not in _LENSES:
            raise ValueError("ExaBricksSource renders through yt's plane-parallel and perspective lenses, not its %s"
                             % lens)
        self._validate()
        dataset = self.exabricks_dataset()
        tf, view = _yt_view(camera, self, dataset)
        view["clip_planes"] = list(self.exabricks_settings.get("clip_planes", [])) + view["clip_planes"]
        name = _yt_field_name(self.field)
        if self._scene is None or self._scene.dataset is not dataset:
            settings = dict(_YT_DEFAULTS)
            settings.update(self.exabricks_settings)
            settings.update(view)
            self._scene = Scene(dataset, field=name, transfer_function=tf, **settings)
        else:
            self._scene.field = name
            self._scene.transfer_function = tf
            for key, value in view.items():
                setattr(self._scene, key, value)
        self._scene.clip_box = self._clip_box
        return self._scene

    def render(self, camera, zbuffer=None):
        """Renders the source for a yt camera, in front of the opaque image and depths of `zbuffer`
        (a yt ZBuffer, as Scene.composite passes it; None: nothing behind). Returns the image
        (also `current_image`); `zbuffer` keeps its depths and takes the image as its rgba, as
        yt's volume sources leave it."""
        self.zbuffer = zbuffer
        scene = self._update_scene(camera)
        shape = (scene.width, scene.height)  # yt's layout
        depth = None
        behind = None
        if zbuffer is not None:
            depth = _exabricks_layout(_view_depth(camera, np.reshape(zbuffer.z, shape), scene.camera.position))
            behind = np.reshape(np.asarray(zbuffer.rgba, dtype=np.float64), shape + (4,))
        # A depth limit of +inf everywhere changes nothing: leave it out.
        if depth is not None and np.isinf(depth).all():
            depth = None
        image = scene.render(depth_limit=depth, depth_limit_planar=True)
        image = np.ascontiguousarray(_exabricks_layout(image), dtype=np.float64)
        if behind is not None:
            image += (1.0 - image[..., 3:4]) * behind
        self.current_image = self.finalize_image(camera, ImageArray(image, info={"imtype": "rendering"}))
        if zbuffer is None:
            self.zbuffer = ZBuffer(self.current_image, np.full(self.current_image.shape[:2], np.inf))
        else:
            zbuffer.rgba = self.current_image
        return self.current_image

    def __repr__(self):
        return "<ExaBricks Source>:%s transfer_function:%s" % (self.data_source, self._transfer_function)


# Scene attributes the yt camera and data source set: not settings of the source.
_FROM_YT = ("camera", "width", "height", "clip_box")
# Scene attributes beside the settings of its vocabulary.
_SCENE_EXTRAS = ("background", "clip_planes", "iso_values", "iso_field", "iso_colors",
                 "iso_color_field", "iso_color_map")


def _check_settings(settings):
    from . import _VOCABULARY

    known = {s["name"] for s in _VOCABULARY} | set(_SCENE_EXTRAS)
    for key in settings:
        if key in _FROM_YT:
            raise ValueError("ExaBricksSource: '%s' comes from the yt camera and data source, not from a setting" % key)
        if key not in known:
            raise AttributeError("ExaBricksSource: exabricks.Scene has no setting '%s'" % key)


def _clip_box(data_source):
    """The clip box of a yt data source: None for the whole domain, a box's edges (code units)
    for a region; other shapes are refused."""
    ds = data_source.ds
    if type(data_source).__name__ != "YTRegion":
        raise ValueError("ExaBricksSource renders the whole dataset or a box of it (ds.region, ds.box), "
                         "not a yt %s" % type(data_source).__name__)
    left, right = _yt_code(data_source.left_edge), _yt_code(data_source.right_edge)
    lo, hi = _yt_code(ds.domain_left_edge), _yt_code(ds.domain_right_edge)
    if np.all(left <= lo) and np.all(right >= hi):
        return None
    return tuple(float(v) for v in np.concatenate([left, right]))
