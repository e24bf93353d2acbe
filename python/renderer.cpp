// exabricks._core.Renderer: a renderer over one dataset, driven by the scene and frame JSON of
// render/scene.h, with passes accumulated by a progressive view (workflows/progressive.h).
#include "exabricks/render/renderer.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"
#include "exabricks/documents/image.h"
#include "exabricks/documents/scene_file.h"
#include "exabricks/io/particles.h"
#include "exabricks/render/legends.h"
#include "exabricks/workflows/progressive.h"

#include "core.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <functional>
#include <thread>

namespace py = pybind11;

namespace exa::pymod {
namespace {

/// Whether the interpreter is shutting down (daemon threads then end when they take the GIL).
bool interpreterFinalizing() {
#if PY_VERSION_HEX >= 0x030D0000
  return Py_IsFinalizing() != 0;
#else
  return _Py_IsFinalizing() != 0;
#endif
}

/// A renderer over one dataset: the scene comes as JSON (plus meshes), frames as JSON; passes
/// accumulate in a progressive view until the scene, the frame or the depth limit changes.
class PyRenderer {
public:
  PyRenderer(std::shared_ptr<Dataset> d, const std::string& device)
      : dataset_(std::move(d)), renderer_(*dataset_->model, dataset_->info), view_(renderer_, device) {
    if (device != "auto" && device != "cpu") resolveDevice(device); // an unusable device fails here
  }

  std::string device() const { return dataset_->streamed ? "cpu" : deviceName(renderer_.device()); }

  py::dict setScene(const std::string& json,
                    const std::vector<std::pair<std::shared_ptr<Mesh>, std::vector<float>>>& meshes) {
    SceneDocument doc = readSceneJson(json, "scene");
    loadSceneMeshes(doc.scene, "scene");
    for (const auto& [mesh, color] : meshes) {
      if (color.size() != 3) fail("a mesh colour needs three numbers (sRGB)");
      doc.scene.meshes.push_back({mesh->mesh, srgbToLinear(vec3f(color[0], color[1], color[2])), ""});
    }
    if (doc.scene.particles.show) {
      Dataset& d = *dataset_;
      if (!d.particlesKnown) {
        py::gil_scoped_release release;
        if (!d.path.empty()) {
          ParticleSet set = readParticles(d.path);
          if (!set.species.empty()) d.particles = std::make_shared<const ParticleSet>(std::move(set));
        }
        d.particlesKnown = true;
      }
      if (d.streamed) d.streamed->setParticles(d.particles);
      if (!particlesGiven_) renderer_.setParticles(d.particles);
      particlesGiven_ = true;
    }
    SceneUpdate u;
    if (dataset_->streamed) {
      // A step in parts: each part's renderer takes the scene when the frame is drawn.
      streamedDrawn_ = streamedDrawn_ &&
                       exactSceneJson(documentOf(doc.scene)) == exactSceneJson(documentOf(streamedScene_)) &&
                       doc.scene.meshes.empty();
      streamedScene_ = doc.scene;
      if (dataset_->coarse) { // drafts from the coarse levels
        py::gil_scoped_release release;
        u = view_.showScene(doc.scene);
      }
    } else {
      // Any change of the scene starts the accumulation over.
      py::gil_scoped_release release;
      u = view_.showScene(doc.scene);
    }
    py::dict out;
    out["volume"] = u.volume;
    out["iso"] = u.iso;
    out["meshes"] = u.meshes;
    out["particles"] = u.particles;
    out["seconds"] = u.seconds();
    return out;
  }

  /// Adds passes until the buffer holds `passes` (or one more pass when 0) for the frame;
  /// returns the passes in the buffer. Ctrl-C cancels between tiles. `depthLimit`: None, or an
  /// (H, W) array of distances per pixel beyond which nothing is drawn (along the rays, or with
  /// `planar` along the view direction; Frame::depthLimit).
  int render(const std::string& frameJson, int passes, const py::object& depthLimit, bool planar) {
    Frame f = parseFrame(frameJson);
    const std::vector<float> limit = depthLimitOf(depthLimit, f);
    if (!depthLimit.is_none()) {
      f.depthLimit = limit.data();
      f.depthLimitPlanar = planar;
    }
    if (dataset_->streamed) return renderStreamedFrame(f, passes);
    view_.showFrame(f); // a change starts the accumulation over
    const int target = passes > 0 ? passes : view_.passes() + 1;
    bool interrupted = false, cancelled = false;
    const std::exception_ptr error =
        renderInWorker([&](const PassControl& control) { view_.refineTo(target, control); }, interrupted, cancelled);
    if (interrupted || cancelled) view_.restart(); // partial passes: start over next time
    if (interrupted) throw py::error_already_set();
    if (error) std::rethrow_exception(error);
    return int(view_.buffer().passes());
  }

  /// Shows the frame as render() does (without a depth limit) and renders the view's draft of it:
  /// the frame divided by the view's draft divisor, at the draft's share of its rate, one sample.
  /// The divisor of the next draft then adapts to `budget` seconds (the view's policy's when 0).
  /// Returns (image, divisor, seconds) with the scene's legends in the image, or None when
  /// cancelled; Ctrl-C cancels as in render().
  py::object renderDraft(const std::string& frameJson, double budget) {
    if (!(budget >= 0.0) || !std::isfinite(budget)) fail("budget must be a number of seconds >= 0, not ", budget);
    if (dataset_->streamed && !dataset_->coarse) return renderStreamedDraft(parseFrame(frameJson));
    view_.showFrame(parseFrame(frameJson)); // a change starts the accumulation over
    const Frame draft = view_.draftFrame();
    const int divisor = view_.draftDivisor();
    bool interrupted = false, cancelled = false, rendered = false;
    const std::exception_ptr error = renderInWorker(
        [&](const PassControl& control) { rendered = view_.renderDraft(draft, draftBuffer_, control, budget); },
        interrupted, cancelled);
    if (interrupted) throw py::error_already_set();
    if (error) std::rethrow_exception(error);
    if (cancelled || !rendered) return py::none();
    draftBuffer_.resolve(draftImage_);
    drawLegends(view_.shown().scene, draft, *dataset_->model, dataset_->info, legendText(), draftImage_);
    return py::make_tuple(pymod::imageArray(draftImage_), divisor, draftBuffer_.stats().seconds);
  }

  /// The divisor of the resolution for the next draft.
  int draftDivisor() const { return view_.draftDivisor(); }

  /// The last draft as PNG bytes, as png() encodes the accumulated image.
  py::bytes draftPng() const {
    const Scene& scene = shownScene();
    const std::vector<unsigned char> bytes = encodePng(draftImage_, scene.keepAlpha, scene.background);
    return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }

  /// Cancels the render in flight between tiles (from any thread, without the GIL), or the next
  /// one when none is: that render returns at once with the passes the buffer holds, which starts
  /// over at the next render.
  void cancel() { cancelRequested_ = true; }

  /// The accumulated image with the legends the scene asks for.
  Image resolved() const {
    Image img;
    if (dataset_->streamed) {
      streamedBuffer_.resolve(img);
      drawLegends(streamedScene_, streamedFrame_, *dataset_->model, dataset_->info, legendText(), img);
      return img;
    }
    view_.resolve(img);
    drawLegends(view_.shown().scene, view_.shown().frame, *dataset_->model, dataset_->info, legendText(), img);
    return img;
  }

  py::array_t<float> image() const { return pymod::imageArray(resolved()); }

  py::bytes png() const {
    const Image img = resolved();
    const Scene& scene = shownScene();
    const std::vector<unsigned char> bytes = encodePng(img, scene.keepAlpha, scene.background);
    return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }

  /// Writes the image; `brightest` rescales its colour so that the brightest channel of any
  /// pixel reaches 1 (as yt's own save does), alpha unchanged.
  void save(const std::string& path, int bits, bool brightest) const {
    Image img = resolved();
    if (brightest) {
      float top = 0.f;
      for (const vec4f& p : img.pixels)
        top = std::max({top, p.x, p.y, p.z});
      if (top > 0.f)
        for (vec4f& p : img.pixels)
          p.x /= top, p.y /= top, p.z /= top;
    }
    const ImageFormat format = imageFormatFor(path, bits);
    const Scene& scene = shownScene();
    writeImage(path, img, format, scene.keepAlpha, scene.background);
  }

  py::dict stats() const {
    const FrameBuffer& buffer = dataset_->streamed ? streamedBuffer_ : view_.buffer();
    const RenderStats& s = buffer.stats();
    py::dict d;
    d["seconds"] = s.seconds;
    d["rays"] = s.rays;
    d["samples"] = s.samples;
    d["regions_visited"] = s.regionsVisited;
    d["surface_hits"] = s.surfaceHits;
    d["iso_samples"] = s.isoSamples;
    d["ao_rays"] = s.aoRays;
    d["samples_per_second"] = s.samplesPerSecond();
    d["passes"] = buffer.passes();
    if (dataset_->streamed) {
      d["parts"] = dataset_->streamed->parts();
      d["parts_read"] = dataset_->streamed->partsRead();
      d["regions"] = dataset_->streamed->survey().regions;
      d["drafts"] = dataset_->leavesMerged ? "every cell merged" : dataset_->coarse ? "coarse levels" : "parts";
      return d;
    }
    d["visible_regions"] = renderer_.visibleRegions();
    d["iso_regions"] = renderer_.isoRegions();
    d["regions"] = dataset_->model->regions.regions.size();
    return d;
  }

  py::object visibleBounds() {
    box3d b;
    if (dataset_->streamed) {
      py::gil_scoped_release release;
      b = dataset_->streamed->visibleBounds(streamedScene_, RendererOptions());
    } else {
      b = renderer_.visibleBounds();
    }
    if (b.empty()) return py::none();
    return py::make_tuple(py::make_tuple(b.lower.x, b.lower.y, b.lower.z),
                          py::make_tuple(b.upper.x, b.upper.y, b.upper.z));
  }

  py::object pick(const std::vector<double>& origin, const std::vector<double>& direction) const {
    if (origin.size() != 3 || direction.size() != 3) fail("origin and direction need three numbers each");
    if (dataset_->streamed) fail("pick needs the whole step: this dataset is held in parts (memory_budget)");
    SurfaceHit hit;
    if (!renderer_.pick(vec3d(origin[0], origin[1], origin[2]), vec3d(direction[0], direction[1], direction[2]), hit))
      return py::none();
    py::dict d;
    d["kind"] = hit.kind == SurfaceHit::Mesh ? "mesh" : hit.kind == SurfaceHit::Particle ? "particle" : "iso";
    d["index"] = hit.index;
    d["distance"] = hit.distance;
    d["position"] = py::make_tuple(hit.position.x, hit.position.y, hit.position.z);
    d["normal"] = py::make_tuple(hit.normal.x, hit.normal.y, hit.normal.z);
    return d;
  }

private:
  const Scene& shownScene() const { return dataset_->streamed ? streamedScene_ : view_.shown().scene; }

  /// A step held in parts: the frame's passes (`passes`, or the frame's samples per pixel when 0)
  /// drawn part by part, front to back (renderStreamed); the same frame and scene again draw
  /// nothing new.
  int renderStreamedFrame(Frame f, int passes) {
    if (passes > 0) f.samplesPerPixel = passes;
    if (streamedDrawn_ && sameFrame(f, streamedFrame_)) return int(streamedBuffer_.passes());
    bool interrupted = false, cancelled = false, complete = false;
    const std::exception_ptr error = renderInWorker(
        [&](const PassControl& control) {
          streamedBuffer_.clear();
          complete =
              renderStreamed(*dataset_->streamed, streamedScene_, RendererOptions(), f, streamedBuffer_, control);
        },
        interrupted, cancelled);
    streamedFrame_ = f;
    streamedFrame_.depthLimit = nullptr; // not kept: only compared by its presence
    streamedDrawn_ = complete && !f.depthLimit;
    if (interrupted) throw py::error_already_set();
    if (error) std::rethrow_exception(error);
    return int(streamedBuffer_.passes());
  }

  /// A draft of a step held in parts: a quarter of the frame's resolution per axis, one sample at
  /// half its rate, drawn part by part. Returns (image, divisor, seconds) as renderDraft does.
  py::object renderStreamedDraft(const Frame& frame) {
    constexpr int kDivisor = 4;
    Frame draft = frame.preview(kDivisor, frame.rate * 0.5f);
    draft.samplesPerPixel = 1;
    // Spheres sized in pixels keep the frame's size in the draft's larger pixels.
    Scene scene = streamedScene_;
    resolveParticleRadius(scene, frame);
    scene.particles.radiusPixels = 0.f;
    bool interrupted = false, cancelled = false, complete = false;
    const std::exception_ptr error = renderInWorker(
        [&](const PassControl& control) {
          complete = renderStreamed(*dataset_->streamed, scene, RendererOptions(), draft, draftBuffer_, control);
        },
        interrupted, cancelled);
    if (interrupted) throw py::error_already_set();
    if (error) std::rethrow_exception(error);
    if (cancelled || !complete) return py::none();
    draftBuffer_.resolve(draftImage_);
    drawLegends(streamedScene_, draft, *dataset_->model, dataset_->info, legendText(), draftImage_);
    return py::make_tuple(pymod::imageArray(draftImage_), kDivisor, draftBuffer_.stats().seconds);
  }

  static SceneDocument documentOf(const Scene& scene) {
    SceneDocument d;
    d.scene = scene;
    d.hasCamera = true;
    return d;
  }

  static bool sameFrame(const Frame& a, const Frame& b) {
    SceneDocument x, y;
    x.frame = a, y.frame = b;
    x.hasCamera = y.hasCamera = true;
    return exactSceneJson(x) == exactSceneJson(y);
  }

  LegendText legendText() const {
    LegendText text;
    text.dataset = legendDatasetLabel(dataset_->name);
    return text;
  }

  static Frame parseFrame(const std::string& json) {
    const SceneDocument doc = readSceneJson(json, "frame");
    if (!doc.hasCamera) fail("frame: a camera is needed");
    return doc.frame;
  }

  /// The depth limit's distances (none for None), checked against the frame's size.
  static std::vector<float> depthLimitOf(const py::object& depthLimit, const Frame& f) {
    std::vector<float> limit;
    if (depthLimit.is_none()) return limit;
    const auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(depthLimit);
    if (!a) fail("depth_limit must be an array of numbers");
    if (a.ndim() != 2 || a.shape(0) != f.height || a.shape(1) != f.width) {
      std::string shape;
      for (py::ssize_t i = 0; i < a.ndim(); ++i)
        shape += strCat(i ? ", " : "", a.shape(i));
      fail("depth_limit must be an (H, W) = (", f.height, ", ", f.width, ") array like the image, not (", shape, ")");
    }
    limit.assign(a.data(), a.data() + a.size());
    return limit;
  }

  /// Runs `work` (passes of the view under the control it is given) on a worker thread without
  /// the GIL, looking every 20 ms for cancel(), Ctrl-C (`interrupted`: a Python error is set) and
  /// the interpreter's end, any of which cancels it. Returns what the worker threw, if anything.
  std::exception_ptr renderInWorker(const std::function<void(const PassControl&)>& work, bool& interrupted,
                                    bool& cancelled) {
    std::atomic<bool> cancel{false}, done{false};
    std::exception_ptr error;
    py::gil_scoped_release release;
    std::thread worker([&] {
      try {
        PassControl control;
        control.cancel = &cancel;
        work(control);
      } catch (...) {
        error = std::current_exception();
      }
      done = true;
    });
    // Taking the GIL as the interpreter finalizes ends this (daemon) thread by unwinding it,
    // even just after the check below said it was not finalizing: the worker is then stopped
    // and joined on the way out instead of leaving a joinable thread, and the GIL is not taken
    // again by the release's end (either would be std::terminate).
    struct StopOnUnwind {
      std::atomic<bool>& cancel;
      std::thread& worker;
      py::gil_scoped_release& release;
      ~StopOnUnwind() {
        if (!worker.joinable()) return;
        cancel = true;
        worker.join();
        if (interpreterFinalizing()) release.disarm();
      }
    } stopOnUnwind{cancel, worker, release};
    while (!done) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      if (cancelRequested_.exchange(false)) {
        cancelled = true;
        cancel = true;
        break;
      }
      if (interpreterFinalizing()) {
        // A daemon thread rendering while the interpreter exits: taking the GIL now would end
        // this thread by unwinding it with the worker still running (std::terminate). Stop the
        // worker and wait here for the process to end.
        cancel = true;
        worker.join();
        for (;;)
          std::this_thread::sleep_for(std::chrono::hours(1));
      }
      py::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() != 0) {
        interrupted = true;
        cancel = true;
        break;
      }
    }
    worker.join();
    return error;
  }

  std::shared_ptr<Dataset> dataset_; ///< declared first: outlives the renderer
  bool particlesGiven_ = false;      ///< the dataset's particles handed to the renderer
  Renderer renderer_;
  ProgressiveView view_;    ///< the passes of renderer_, on the device asked for (cpu, cuda, auto or portable)
  FrameBuffer draftBuffer_; ///< the last draft
  // A step held in parts (Dataset::streamed): the scene and the last frame drawn, and its image.
  Scene streamedScene_;
  Frame streamedFrame_;
  FrameBuffer streamedBuffer_;
  bool streamedDrawn_ = false;
  Image draftImage_; ///< the last draft resolved, with its legends
  std::atomic<bool> cancelRequested_{false};
};

} // namespace

void bindRenderer(py::module_& m) {
  py::class_<PyRenderer>(m, "Renderer")
      .def(py::init<std::shared_ptr<Dataset>, std::string>(), py::arg("dataset"), py::arg("device") = "auto")
      .def_property_readonly("device", &PyRenderer::device, "Where passes run: cpu, cuda or portable")
      .def("set_scene", &PyRenderer::setScene, py::arg("scene_json"), py::arg("meshes"))
      .def("render", &PyRenderer::render, py::arg("frame_json"), py::arg("passes") = 0,
           py::arg("depth_limit") = py::none(), py::arg("depth_limit_planar") = false)
      .def("image", &PyRenderer::image)
      .def("png", &PyRenderer::png)
      .def("save", &PyRenderer::save, py::arg("path"), py::arg("bits") = 8, py::arg("brightest") = false)
      .def("stats", &PyRenderer::stats)
      .def("pick", &PyRenderer::pick, py::arg("origin"), py::arg("direction"))
      .def("render_draft", &PyRenderer::renderDraft, py::arg("frame_json"), py::arg("budget") = 0.0,
           "Renders the view's draft of the frame: (image, divisor, seconds), or None when cancelled")
      .def_property_readonly("draft_divisor", &PyRenderer::draftDivisor, "The divisor of the next draft")
      .def("draft_png", &PyRenderer::draftPng, "The last draft as PNG bytes")
      .def("cancel", &PyRenderer::cancel, "Cancels the render in flight (or the next one)")
      .def("visible_bounds", &PyRenderer::visibleBounds);
}

} // namespace exa::pymod
