"""Time series: exabricks.Series renders the steps of a series with one scene, and makes movies,
through the library's series renderer (the command line's `exabricks movie` uses the same). See
docs/movies.md and docs/python.md."""

import json
import os
import shutil
import subprocess
import warnings

from . import _core

__all__ = ["Series"]

_MOVIE_TYPES = {
    ".mp4": ["-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18", "-movflags", "+faststart", "-f", "mp4"],
    ".webm": ["-c:v", "libvpx-vp9", "-b:v", "0", "-crf", "32", "-pix_fmt", "yuv420p", "-f", "webm"],
}


def _as_inputs(paths):
    if isinstance(paths, (str, os.PathLike)):
        return [os.fspath(paths)]
    return [os.fspath(p) for p in paths]


class Series:
    """The steps of a time series: files, dataset folders, folders of datasets or glob patterns, in
    the order given (a folder or pattern in numeric order: plt200 before plt1000; a step named
    twice plays once). Steps load when first rendered: the next one a movie needs on a background
    thread, and a step whose cells equal the step before it only rebuilds its values."""

    def __init__(self, paths, fields=None, prefetch=True, reuse=True):
        self._core = _core.Series(_as_inputs(paths), list(fields or []), bool(prefetch), bool(reuse))

    def __len__(self):
        return len(self._core.steps)

    @property
    def steps(self):
        """The steps' paths, in playing order."""
        return list(self._core.steps)

    @property
    def names(self):
        """The steps' names: the last component of each path."""
        return [os.path.basename(os.path.normpath(p)) for p in self._core.steps]

    def _index(self, step):
        if isinstance(step, str):
            for i, (path, name) in enumerate(zip(self._core.steps, self.names)):
                if step in (path, name):
                    return i
            raise KeyError("no step named '%s' in the series (%s)" % (step, ", ".join(self.names)))
        i = int(step)
        if i < 0:
            i += len(self)
        if not 0 <= i < len(self):
            raise IndexError("step %d of a series of %d steps" % (int(step), len(self)))
        return i

    def range(self, field=None):
        """The value range (low, high) of a field over every step (the default field when None):
        from metadata where the format records it, else reading that field alone."""
        return tuple(self._core.range(field or ""))

    def dataset(self, step=0):
        """Step `step` (an index or a name) as an exabricks.Dataset, e.g. to make a Scene from."""
        from . import Dataset
        return Dataset(self._core.dataset(self._index(step)))

    def scene(self, step=0, field=None, **settings):
        """An exabricks.Scene over a step (the first by default), for render() and movie()."""
        from . import Scene
        return Scene(self.dataset(step), field=field, **settings)

    @staticmethod
    def _document(scene, width=None, height=None, spp=None):
        """The scene document's JSON, the meshes made from arrays, and the name errors give."""
        meshes, source = [], "scene"
        if isinstance(scene, (str, os.PathLike)):
            source = os.fspath(scene)
            with open(source) as f:
                doc = json.load(f)
        elif isinstance(scene, dict):
            doc = json.loads(json.dumps(scene))
        else:
            doc = scene.to_dict()
            meshes = [(m, c) for m, c in scene.meshes if not m.source]
        frame = doc.setdefault("frame", {})
        for key, value in (("width", width), ("height", height), ("samples_per_pixel", spp)):
            if value is not None:
                frame[key] = int(value)
        return json.dumps(doc), meshes, source

    def render(self, step, scene, width=None, height=None, spp=None, range=None):
        """Renders step `step` (an index or a name) with a scene: an exabricks.Scene, a scene
        dictionary or a scene file's path (with its camera and frame). Returns an (H, W, 4) float32
        array of linear, premultiplied RGBA, as Scene.render does. `range`: None keeps the scene's
        value range, "global" takes the series' range, "per-step" each step's own."""
        text, meshes, source = self._document(scene, width, height, spp)
        return self._core.render(self._index(step), text, meshes, range or "", source)

    def write_frames(self, folder, scene, frames=None, frames_per_step=1, range="global", width=None, height=None,
                     spp=None):
        """Writes a movie's frames as FOLDER/frame_00000.png...: `frames` frames with the steps
        spread over them, or `frames_per_step` frames per step; the camera follows the scene's
        camera path where it has one. Returns the files written."""
        text, meshes, source = self._document(scene, width, height, spp)
        return list(self._core.write_frames(text, meshes, range or "", source, int(frames or 0), int(frames_per_step),
                                            os.fspath(folder)))

    def movie(self, path, scene, frames=None, fps=24, frames_per_step=1, range="global", width=None, height=None,
              spp=None):
        """Renders the series into a movie: PATH.mp4 (H.264) or PATH.webm (VP9) encoded with ffmpeg
        from the frames in PATH.frames, or the PNG frames alone into the folder PATH. Without
        ffmpeg on PATH the frames stay and a warning says so. Returns the path of what was written
        (the movie, or the frames' folder)."""
        path = os.fspath(path)
        ext = os.path.splitext(path)[1].lower()
        to_folder = ext == "" or os.path.isdir(path)
        if not to_folder and ext not in _MOVIE_TYPES:
            raise ValueError("%s: write .mp4 (H.264), .webm (VP9) or a folder for the frames alone" % path)
        if not 0 < float(fps) <= 1000:
            raise ValueError("fps must be in (0, 1000], not %s" % fps)
        folder = path if to_folder else path + ".frames"
        written = self.write_frames(folder, scene, frames, frames_per_step, range, width, height, spp)
        if to_folder:
            return folder
        ffmpeg = shutil.which("ffmpeg")
        if ffmpeg is None:
            warnings.warn("ffmpeg is not on PATH, so %s was not encoded; the %d frames are in %s"
                          % (path, len(written), folder))
            return folder
        temporary = "%s.encoding-%d%s" % (path, os.getpid(), ext)
        args = [ffmpeg, "-y", "-loglevel", "error", "-framerate", str(fps), "-i",
                os.path.join(folder, "frame_%05d.png"), "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"]
        r = subprocess.run(args + _MOVIE_TYPES[ext] + [temporary], capture_output=True, text=True)
        if r.returncode != 0:
            if os.path.exists(temporary):
                os.remove(temporary)
            raise RuntimeError("%s: ffmpeg failed (exit status %d): %s; the frames are in %s"
                               % (path, r.returncode, r.stderr.strip(), folder))
        os.replace(temporary, path)
        return path

    def stats(self):
        """Steps loaded and reused, and the seconds spent loading, waiting and rendering."""
        return dict(self._core.stats())

    def __repr__(self):
        return "<exabricks.Series of %d steps: %s>" % (len(self), ", ".join(self.names[:3] + (["..."] if len(self) > 3 else [])))
