"""An interactive view of a Scene in Jupyter (ipywidgets): orbit, transfer-function range and
opacity scale, iso-value. Every change shows the scene's draft at once (Scene.render_draft: the
library's progressive view sizes it to a time budget and samples it at a lower rate); a
background thread then refines the full-resolution image pass by pass until the target is
reached or the next change.
When the interpreter exits, the refinement is cancelled and its thread joined first (a daemon
thread still rendering at exit would otherwise be torn down mid-render)."""

import atexit
import threading
import weakref

import numpy as np

_live = weakref.WeakSet()


@atexit.register
def _close_all():
    for widget in list(_live):
        widget.close()


class SceneWidget:
    def __init__(self, scene, width=512, height=512, budget=0.035, passes=16):
        import ipywidgets as w

        self.scene = scene
        self.width, self.height = int(width), int(height)
        self.budget = float(budget)  # the seconds a draft aims at
        self.passes = max(1, int(passes))
        self._generation = 0
        self._lock = threading.Lock()
        self._thread = None
        self._threads = []
        _live.add(self)
        field = scene.field
        info = scene.dataset.info()
        rng = next((f["range"] for f in info["fields"] if f["name"] == field), {"min": 0.0, "max": 1.0})
        lo, hi = float(rng["min"] or 0.0), float(rng["max"] or 1.0)
        if not hi > lo:
            hi = lo + 1.0
        step = (hi - lo) / 200.0
        self.image = w.Image(format="png", width=self.width, height=self.height)
        self.azimuth = w.FloatSlider(value=30.0, min=-180.0, max=180.0, step=1.0, description="azimuth")
        self.elevation = w.FloatSlider(value=25.0, min=-89.0, max=89.0, step=1.0, description="elevation")
        self.range = w.FloatRangeSlider(value=[lo, hi], min=lo, max=hi, step=step, description="range")
        self.opacity = w.FloatSlider(value=0.0, min=-2.0, max=2.0, step=0.05, description="log10 opacity×")
        self.iso = w.FloatSlider(value=0.5 * (lo + hi), min=lo, max=hi, step=step, description="iso-value")
        self.iso_on = w.Checkbox(value=False, description="iso-surface")
        self.status = w.Label()
        for control in (self.azimuth, self.elevation, self.range, self.opacity, self.iso, self.iso_on):
            control.observe(self._changed, names="value")
        controls = w.VBox([self.azimuth, self.elevation, self.range, self.opacity, w.HBox([self.iso_on, self.iso]),
                           self.status])
        self.widget = w.HBox([self.image, controls])
        base = scene.transfer_function.opacity_scale
        # The slider multiplies the scale in effect ("auto": the dataset's default scale).
        self._base_scale = scene.dataset.default_opacity_scale if base == "auto" else float(base)
        self._changed(None)

    def _apply(self):
        s = self.scene
        s.orbit(self.azimuth.value, self.elevation.value)
        tf = s.transfer_function
        tf.range = tuple(self.range.value)
        tf.opacity_scale = self._base_scale * 10.0 ** self.opacity.value
        s.iso_values = [self.iso.value] if self.iso_on.value else []

    def _changed(self, _change):
        with self._lock:
            self._generation += 1
            generation = self._generation
            self._apply()
            # The view's draft at once (it shows the frame the passes refine); None when cancelled.
            draft = self.scene.render_draft(self.width, self.height, self.budget, spp=self.passes)
            if draft is not None:
                self.image.value = self.scene._renderer.draft_png()
        if draft is not None:
            self.status.value = "preview %dx%d" % (draft.shape[1], draft.shape[0])
        self._thread = threading.Thread(target=self._refine, args=(generation,), daemon=True)
        self._threads = [t for t in self._threads if t.is_alive()] + [self._thread]
        self._thread.start()

    def _refine(self, generation):
        for _ in range(self.passes):
            with self._lock:
                if generation != self._generation:
                    return
                done = self.scene.render_progressive(self.width, self.height, self.passes)
                self.image.value = self.scene._renderer.png()
            self.status.value = "%d of %d samples per pixel" % (done, self.passes)
            if done >= self.passes:
                return

    @property
    def preview(self):
        """The divisor of the resolution for the next draft (the view's, adapted to the budget)."""
        return self.scene._renderer.draft_divisor

    def close(self):
        """Stops refining: cancels the pass in flight and waits for the background threads."""
        self._generation += 1  # a refining thread stops before its next pass
        self.scene._renderer.cancel()
        for thread in self._threads:
            if thread is not threading.current_thread():
                thread.join()
        self._threads = []

    def wait(self):
        """Waits for the refinement in progress (for scripts and tests)."""
        if self._thread is not None:
            self._thread.join()
        return np.asarray(self.scene.image())
