"""exabricks.yt.ExaBricksSource in yt scenes: the image of the source alone is the exabricks
Scene of the converted camera and transfer function, and yt's opaque sources composite with it
in front of and behind the volume at the depths yt's z-buffer holds."""
import numpy as np
import pytest

import exabricks as eb
from conftest import shared

yt = pytest.importorskip("yt", reason="yt is not installed (Debian: python3-yt)")
yt.set_log_level(50)

from yt.visualization.volume_rendering.api import BoxSource, GridSource, LineSource, Scene  # noqa: E402

from exabricks.yt import ExaBricksSource  # noqa: E402

FIELD = ("stream", "density")
CENTRE = (0.45, 0.55, 0.5)  # of the ball, off the view axis so that a flipped image shows
RESOLUTION = (64, 48)  # (width, height), yt's order
RED, BLUE = (1.0, 0.0, 0.0, 1.0), (0.0, 0.0, 1.0, 1.0)


def ball_dataset():
    """A ball of density 1 (radius 0.2, falling to 0 at 0.25) in the unit cube, 32^3 cells: 0
    everywhere else."""
    x = (np.arange(32) + 0.5) / 32
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    r = np.sqrt((X - CENTRE[0]) ** 2 + (Y - CENTRE[1]) ** 2 + (Z - CENTRE[2]) ** 2)
    density = np.clip((0.25 - r) / 0.05, 0.0, 1.0)
    return yt.load_uniform_grid({"density": (density, "g/cm**3")}, density.shape, bbox=np.array([[0.0, 1.0]] * 3))


def green_tf(grey_opacity=True):
    """Dense green where the density is above 0.5, nothing below."""
    tf = yt.ColorTransferFunction((0.0, 1.2), grey_opacity=grey_opacity)
    tf.add_step(0.5, 1.2, [0.1, 0.9, 0.3, 40.0])
    return tf


def source_of(ds, data_source=None, **settings):
    src = ExaBricksSource(data_source if data_source is not None else ds, FIELD, **settings)
    src.log_field = False
    src.transfer_function = green_tf()
    return src


def set_camera(sc, ds, lens):
    """The camera on the +z side of the cube looking down at its centre, y up."""
    cam = sc.add_camera(ds, lens_type=lens)
    cam.resolution = RESOLUTION
    cam.set_width(ds.arr([1.2, 0.9, 1.5], "code_length"))
    cam.set_position(ds.arr([0.5, 0.5, 3.0], "code_length"), north_vector=[0, 1, 0])
    cam.set_focus(ds.arr([0.5, 0.5, 0.5], "code_length"))
    return cam


def scene_of(ds, lens, *sources):
    """A yt Scene of the sources (volumes first, as yt.create_scene adds them) and the camera."""
    sc = Scene()
    volumes = [s for s in sources if isinstance(s, ExaBricksSource)]
    for s in volumes:
        sc.add_source(s)
    set_camera(sc, ds, lens)
    for s in sources:
        if s not in volumes:
            sc.add_source(s)
    return sc


def exabricks_layout(image):
    """Scene.render's image (turned by 180 degrees from the sources') as exabricks lays out its
    images: (H, W, 4), row 0 at the top."""
    return np.asarray(image, dtype=np.float64).swapaxes(0, 1)


def converted_scene(ds, src, cam, **settings):
    """The exabricks Scene of the source's field, camera and transfer function, made by hand (8
    samples per pixel, unlit, unless `settings` say otherwise)."""
    dataset = eb.from_yt(ds, [FIELD])
    settings = {"spp": 8, "shading": "none", **settings}
    return eb.Scene(dataset, field="density", camera=eb.Camera.from_yt(cam),
                    transfer_function=eb.TransferFunction.from_yt(src, camera=cam, dataset=dataset),
                    width=RESOLUTION[0], height=RESOLUTION[1], **settings)


LENSES = ["plane-parallel", "perspective"]


@pytest.mark.parametrize("lens", LENSES)
def test_the_source_alone_is_the_exabricks_scene_of_the_converted_camera_and_tf(lens):
    ds = ball_dataset()
    src = source_of(ds)
    sc = scene_of(ds, lens, src)
    got = exabricks_layout(sc.render())
    # Unless told otherwise the source accumulates 8 jittered passes, unlit.
    assert src.exabricks_scene.spp == 8 and src.exabricks_scene.shading == "none"
    want = converted_scene(ds, src, sc.camera).render()
    assert got.shape == want.shape == (RESOLUTION[1], RESOLUTION[0], 4)
    assert want[..., 3].max() > 0.95 and 0.03 < (want[..., 3] > 0.5).mean() < 0.5
    assert np.abs(got - want).max() < 1e-6
    # The source's own image is in yt's layout: the ball's centre projects where yt's lens puts it.
    image = np.asarray(src.current_image)
    assert image.shape == RESOLUTION + (4,)
    px, py, _ = sc.camera.lens.project_to_plane(sc.camera, np.array([CENTRE]))
    i, j = np.indices(image.shape[:2]) + 0.5
    alpha = image[..., 3]
    centroid = ((alpha * i).sum() / alpha.sum(), (alpha * j).sum() / alpha.sum())
    assert abs(centroid[0] - (px[0] + 0.5)) < 1.0 and abs(centroid[1] - (py[0] + 0.5)) < 1.0, (centroid, px, py)
    # Scene.from_yt converts the same scene.
    np.testing.assert_array_equal(eb.Scene.from_yt(sc).render(), want)


@pytest.mark.parametrize("lens", LENSES)
def test_boxes_in_front_show_and_boxes_behind_the_volume_are_hidden(lens, tmp_path):
    ds = ball_dataset()

    def boxes():
        # Seen from the camera (z = 3), one box in front of the ball, one behind it; both outlines
        # cross the ball's silhouette, the one behind also runs outside it.
        return [BoxSource(ds.arr([0.35, 0.35, 0.85], "code_length"), ds.arr([0.65, 0.65, 0.9], "code_length"),
                          color=list(RED)),
                BoxSource(ds.arr([0.28, 0.28, 0.1], "code_length"), ds.arr([0.72, 0.72, 0.15], "code_length"),
                          color=list(BLUE))]

    volume = exabricks_layout(scene_of(ds, lens, source_of(ds)).render())
    lines = exabricks_layout(scene_of(ds, lens, *boxes()).render())
    sc = scene_of(ds, lens, source_of(ds), *boxes())
    both = exabricks_layout(sc.render())
    path = tmp_path / "boxes.png"
    sc.save(str(path))
    assert path.stat().st_size > 0

    dense = volume[..., 3] > 0.95  # rays end at 0.98 (early termination)
    empty = volume[..., 3] == 0.0
    front = np.all(lines == RED, axis=-1)
    back = np.all(lines == BLUE, axis=-1)
    # In front of the ball the box shows its own colour, nothing of the volume.
    assert (front & dense).sum() > 10
    assert np.all(both[front] == RED)
    # Behind the ball the box is hidden: what shows is the volume, with the box through what
    # the volume lets through.
    assert (back & dense).sum() > 10 and (back & empty).sum() > 10
    hidden = back & dense
    assert (both[hidden] - volume[hidden])[:, 2].max() < 0.05
    expected = volume + (1.0 - volume[..., 3:4]) * np.array(BLUE)
    assert np.abs(both[hidden] - expected[hidden]).max() < 1e-6
    assert np.all(both[back & empty] == BLUE)


@pytest.mark.parametrize("lens", LENSES)
def test_a_line_through_the_middle_shows_through_the_front_half(lens):
    # A red line across the ball at z = 0.5 (its centre's depth): in its pixels the image is the
    # volume in front of z = 0.5 (a clip plane removing z < 0.5) over the red.
    ds = ball_dataset()
    src = source_of(ds)
    line = LineSource(ds.arr([[[0.05, 0.55, 0.5], [0.95, 0.55, 0.5]]], "code_length"), np.array([RED]))
    sc = scene_of(ds, lens, src, line)
    got = exabricks_layout(sc.render())
    alone = LineSource(np.array([[[0.05, 0.55, 0.5], [0.95, 0.55, 0.5]]]), np.array([RED]))
    lines = exabricks_layout(scene_of(ds, lens, alone).render())
    front = converted_scene(ds, src, sc.camera)
    front.add_clip_plane((0.0, 0.0, 0.5), (0.0, 0.0, -1.0))
    want = front.render()
    on = np.all(lines == RED, axis=-1)
    assert on.sum() > 25
    composited = want + (1.0 - want[..., 3:4]) * np.array(RED)
    partly = on & (want[..., 3] > 0.3) & (want[..., 3] < 0.99)  # the line seen through the volume
    assert partly.sum() > 5
    assert np.abs(got[on] - composited[on]).max() < 1e-6
    # Off the line the whole ray is drawn.
    whole = exabricks_layout(scene_of(ds, lens, source_of(ds)).render())
    assert np.abs(got[~on] - whole[~on]).max() < 1e-6


def test_the_dataset_is_built_once_and_the_scene_follows_camera_and_tf(monkeypatch):
    import exabricks.yt as eyt

    builds = []

    def counting_from_yt(*args, **kwargs):
        builds.append(args)
        return eb.from_yt(*args, **kwargs)

    monkeypatch.setattr(eyt, "from_yt", counting_from_yt)
    ds = ball_dataset()
    src = source_of(ds, spp=2)
    sc = scene_of(ds, "plane-parallel", src)
    first = np.array(sc.render())
    scene = src.exabricks_scene
    assert scene.spp == 2 and scene.shading == "none"
    sc.camera.set_position(ds.arr([3.0, 0.5, 0.5], "code_length"), north_vector=[0, 0, 1])
    turned = np.array(sc.render())
    tf = yt.ColorTransferFunction((0.0, 1.2), grey_opacity=True)
    tf.add_step(0.5, 1.2, [0.9, 0.2, 0.1, 40.0])
    src.transfer_function = tf
    recoloured = np.array(sc.render())
    assert len(builds) == 1 and src.exabricks_scene is scene
    assert np.abs(turned - first).max() > 0.1 and np.abs(recoloured - turned).max() > 0.1
    np.testing.assert_array_equal(exabricks_layout(recoloured),
                                  converted_scene(ds, src, sc.camera, spp=2).render())


def test_yt_default_transfer_function_log_and_grey_opacity():
    ds = ball_dataset()
    src = ExaBricksSource(ds, FIELD)  # yt builds its default transfer function, logged
    sc = scene_of(ds, "perspective", src)
    got = exabricks_layout(sc.render())
    assert src.log_field and src.exabricks_scene.transfer_function.log
    assert not src.transfer_function.grey_opacity
    # Without grey opacity yt's volume sources give alpha 1 everywhere.
    assert np.all(got[..., 3] == 1.0) and got[..., :3].max() > 0.05
    want = eb.Scene.from_yt(sc).render()
    assert np.abs(got[..., :3] - want[..., :3]).max() < 1e-6


def test_a_box_of_the_data_clips_the_volume():
    ds = ball_dataset()
    # The box holds the ball's half at x <= 0.45 (its centre's x): seen from +z, the other half
    # is gone from the picture.
    region = ds.region([0.25, 0.5, 0.5], [0.0, 0.0, 0.0], [0.45, 1.0, 1.0])
    src = source_of(ds, data_source=region)
    sc = scene_of(ds, "plane-parallel", src)
    got = exabricks_layout(sc.render())
    want = converted_scene(ds, src, sc.camera, clip_box=(0.0, 0.0, 0.0, 0.45, 1.0, 1.0)).render()
    assert np.abs(got - want).max() < 1e-6
    whole = converted_scene(ds, src, sc.camera).render()
    shown, kept = (whole[..., 3] > 0.5).sum(), (got[..., 3] > 0.5).sum()
    assert 0.3 * shown < kept < 0.7 * shown, (kept, shown)


def test_what_the_source_cannot_render_is_refused():
    ds = ball_dataset()
    with pytest.raises(ValueError, match="whole dataset or a box of it"):
        ExaBricksSource(ds.sphere([0.5, 0.5, 0.5], 0.3), FIELD)
    with pytest.raises(AttributeError, match="no setting 'nope'"):
        ExaBricksSource(ds, FIELD, nope=1)
    with pytest.raises(ValueError, match="'width' comes from the yt camera"):
        ExaBricksSource(ds, FIELD, width=10)
    sc = scene_of(ds, "fisheye", source_of(ds))
    with pytest.raises(ValueError, match="plane-parallel and perspective lenses, not its FisheyeLens"):
        sc.render()
    sc = scene_of(ds, "plane-parallel", source_of(ds))
    sc.camera.set_width(ds.arr([1.2, 1.2, 1.5], "code_length"))  # 64 x 48 pixels
    with pytest.raises(ValueError, match="aspect of its resolution"):
        sc.render()


def test_an_amrex_plotfile_with_its_domain_outline(tmp_path):
    ds = yt.load(str(shared("amrex/advection_3d/plt_small")))
    field = ("boxlib", "phi")
    sc = yt.create_scene(ds, field)  # yt's default transfer function and camera
    key = list(sc.sources)[0]
    sc.sources[key] = ExaBricksSource(ds, field)
    sc.camera.resolution = (96, 96)
    alone = exabricks_layout(sc.render())
    want = eb.Scene.from_yt(sc).render()
    assert want[..., :3].max() > 0.05
    assert np.abs(alone[..., :3] - want[..., :3]).max() < 1e-6
    sc.annotate_domain(ds, color=[1, 1, 1, 1])
    got = exabricks_layout(sc.render())
    # The outline's pixels: where yt's lines left a depth in the z-buffer the source composited
    # with. yt's own render of the outline alone puts the same lines there, give or take a pixel
    # where a line runs along pixel boundaries (seen on some machines): most pixels agree.
    depth = np.asarray(sc.sources[key].zbuffer.z)[::-1, ::-1]  # the sources' layout, turned as the image
    on = np.isfinite(exabricks_layout(depth))
    assert on.sum() > 300
    outline = scene_of(ds, "plane-parallel", BoxSource(ds.domain_left_edge, ds.domain_right_edge, color=[1, 1, 1, 1]))
    outline.camera = sc.camera
    alone_outline = np.all(exabricks_layout(outline.render()) == 1.0, axis=-1)
    assert (on & alone_outline).sum() > 0.75 * on.sum()
    # The outline adds its light where it shows (through the data, or in front of it); off the
    # outline the picture is the same.
    assert np.all(got[on][:, :3] >= alone[on][:, :3] - 1e-6) and got[on][:, :3].mean() > 0.9
    np.testing.assert_array_equal(got[~on], alone[~on])
    sc.save(str(tmp_path / "plt_small.png"))


def test_yt_grid_annotations_composite_with_the_volume():
    # plt_small's grid boxes (yt's GridSource: opaque lines in each level's colour) over a volume
    # with a real alpha channel (grey opacity).
    ds = yt.load(str(shared("amrex/advection_3d/plt_small")))
    field = ("boxlib", "phi")
    sc = yt.create_scene(ds, field)
    src = ExaBricksSource(ds, field)
    src.log_field = False
    tf = yt.ColorTransferFunction((0.99, 2.0), grey_opacity=True)
    tf.add_layers(4, w=0.01, colormap="viridis", alpha=[5.0, 10.0, 20.0, 40.0])
    src.transfer_function = tf
    sc.sources[list(sc.sources)[0]] = src
    sc.camera.resolution = (96, 96)
    alone = exabricks_layout(sc.render())
    sc.annotate_grids(ds, alpha=1.0)
    got = exabricks_layout(sc.render())
    grids = Scene()
    grids.camera = sc.camera
    grids.add_source(GridSource(ds.all_data(), alpha=1.0))
    lines = exabricks_layout(grids.render())
    on = lines[..., 3] > 0
    assert on.sum() > 1000
    # Off the lines the picture is the volume's.
    np.testing.assert_array_equal(got[~on], alone[~on])
    # On them it is the volume in front of the line (a part of the whole ray: no more than it,
    # and at most as opaque) over the line: between (1 - alpha) x line and volume + line.
    line, volume, both = lines[on], alone[on], got[on]
    assert np.all(both >= (1.0 - volume[:, 3:4]) * line - 1e-6)
    assert np.all(both <= volume + line + 1e-6)
    # Neither drawn over the volume nor behind all of it: the lines inside the data hide what lies
    # beyond them, and the data in front of them dims them.
    behind_all = volume + (1.0 - volume[:, 3:4]) * line
    differs = lambda a, b: (np.abs(a - b).max(axis=-1) > 0.02).sum()
    assert differs(both, behind_all) > 0.5 * on.sum() and differs(both, line) > 0.5 * on.sum()
