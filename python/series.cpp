// exabricks._core.Series: a time series through the library's SeriesRenderer (workflows/series.h):
// its steps, value ranges over all of them, a step rendered with a scene, and a movie's frames
// written as numbered PNGs (the package encodes them).
#include "core.h"

#include "exabricks/core/error.h"
#include "exabricks/documents/image.h"
#include "exabricks/documents/scene_file.h"
#include "exabricks/render/legends.h"
#include "exabricks/workflows/series.h"

#include <pybind11/stl.h>

#include <filesystem>
#include <map>

namespace py = pybind11;

namespace exa::pymod {
namespace {

using MeshList = std::vector<std::pair<std::shared_ptr<Mesh>, std::vector<float>>>;

class PySeries {
public:
  PySeries(const std::vector<std::string>& inputs, const std::vector<std::string>& fields, bool prefetch, bool reuse)
      : series_(seriesSteps(inputs), options(fields, prefetch, reuse)) {}

  const std::vector<std::string>& steps() const { return series_.steps(); }

  /// The field's range over every step (the default field when empty), computed once per field.
  std::pair<float, float> range(const std::string& field) {
    const std::string name = fieldName(field);
    auto found = ranges_.find(name);
    if (found == ranges_.end()) {
      range1f r;
      {
        py::gil_scoped_release release;
        r = seriesRange(series_.steps(), series_.options().load, name).range;
      }
      found = ranges_.emplace(name, r).first;
    }
    return {found->second.lower, found->second.upper};
  }

  std::shared_ptr<Dataset> dataset(int step) {
    const SeriesStep& s = load(step);
    auto d = std::make_shared<Dataset>();
    d->model = s.model;
    d->info = s.info;
    d->name = series_.steps()[size_t(step)];
    d->loadSeconds = s.seconds;
    return d;
  }

  /// The legends the scene asks for, labelled with the step's dataset (as `exabricks movie` draws
  /// them).
  void drawStepLegends(const SeriesStep& step, const Scene& scene, const Frame& frame, Image& image) const {
    LegendText text;
    text.dataset = legendDatasetLabel(series_.steps()[size_t(step.index)]);
    drawLegends(scene, frame, *step.model, step.info, text, image);
  }

  /// Step `step` rendered with a scene document (JSON with camera and frame; `range`: "" keeps its
  /// value range, "global" takes the series', "per-step" each step's own).
  py::array_t<float> render(int step, const std::string& json, const MeshList& meshes, const std::string& range,
                            const std::string& source) {
    const SceneDocument doc = document(json, meshes, range, source);
    Image image;
    {
      py::gil_scoped_release release;
      image = series_.render(step, doc.scene, doc.frame);
      drawStepLegends(series_.current(), doc.scene, doc.frame, image);
    }
    return imageArray(image);
  }

  /// A movie's frames as FOLDER/frame_NNNNN.png: `frames` frames with the steps spread over them
  /// (0: framesPerStep per step), the camera along the scene's camera path where it has one.
  std::vector<std::string> writeFrames(const std::string& json, const MeshList& meshes, const std::string& range,
                                       const std::string& source, int frames, int framesPerStep,
                                       const std::string& folder) {
    const SceneDocument doc = document(json, meshes, range, source);
    const int steps = series_.size();
    FramePlan plan =
        frames > 0 && steps > 1 ? FramePlan::spread(steps, frames) : FramePlan::perStep(steps, framesPerStep);
    if (steps == 1 && frames > 0) plan.frames = frames;
    plan.path = doc.path;
    std::vector<int> all(size_t(plan.frames));
    for (int i = 0; i < plan.frames; ++i)
      all[size_t(i)] = i;
    std::vector<std::string> written;
    std::filesystem::create_directories(folder);
    py::gil_scoped_release release;
    series_.renderFrames(plan, doc.scene, doc.frame, all,
                         [&](int i, const SeriesStep& step, const Scene& scene, const Frame& frame, Image& image) {
                           drawStepLegends(step, scene, frame, image);
                           written.push_back(framePath(folder, i));
                           writePng(written.back(), image, scene.keepAlpha, scene.background);
                         });
    return written;
  }

  py::dict stats() const {
    const SeriesStats& s = series_.stats();
    py::dict d;
    d["steps_loaded"] = s.loaded;
    d["steps_reused"] = s.reused;
    d["load_seconds"] = s.loadSeconds;
    d["load_wait_seconds"] = s.waitSeconds;
    d["render_seconds"] = s.renderSeconds;
    return d;
  }

private:
  static SeriesOptions options(const std::vector<std::string>& fields, bool prefetch, bool reuse) {
    SeriesOptions o;
    o.load.fields = fields;
    o.prefetch = prefetch;
    o.reuse = reuse;
    return o;
  }

  const SeriesStep& load(int step) {
    if (step < 0 || step >= series_.size()) throw py::index_error(strCat("step ", step, " of ", series_.size()));
    py::gil_scoped_release release;
    return series_.load(step);
  }

  std::string fieldName(const std::string& field) {
    if (!field.empty()) return field;
    const Model& m = *load(series_.current().index < 0 ? 0 : series_.current().index).model;
    return m.fieldNames[size_t(m.requireField(""))];
  }

  SceneDocument document(const std::string& json, const MeshList& meshes, const std::string& range,
                         const std::string& source) {
    SceneDocument doc = readSceneJson(json, source);
    loadSceneMeshes(doc.scene, source);
    for (const auto& [mesh, color] : meshes) {
      if (color.size() != 3) fail("a mesh colour needs three numbers (sRGB)");
      doc.scene.meshes.push_back({mesh->mesh, srgbToLinear(vec3f(color[0], color[1], color[2])), ""});
    }
    if (!doc.hasCamera) fail(source, ": the scene needs a camera");
    range1f& r = doc.scene.layers.at(0).tf.valueRange;
    if (range == "global") {
      const auto [lo, hi] = this->range(doc.scene.layers[0].field);
      r = range1f{lo, hi};
    } else if (range == "per-step") {
      r = range1f();
    } else if (!range.empty()) {
      fail("range must be 'global', 'per-step' or None, not '", range, "'");
    }
    return doc;
  }

  SeriesRenderer series_;
  std::map<std::string, range1f> ranges_;
};

} // namespace

void bindSeries(py::module_& m) {
  py::class_<PySeries>(m, "Series")
      .def(py::init<const std::vector<std::string>&, const std::vector<std::string>&, bool, bool>(), py::arg("inputs"),
           py::arg("fields"), py::arg("prefetch") = true, py::arg("reuse") = true)
      .def_property_readonly("steps", &PySeries::steps)
      .def("range", &PySeries::range, py::arg("field"))
      .def("dataset", &PySeries::dataset, py::arg("step"))
      .def("render", &PySeries::render, py::arg("step"), py::arg("scene_json"), py::arg("meshes"), py::arg("range"),
           py::arg("source"))
      .def("write_frames", &PySeries::writeFrames, py::arg("scene_json"), py::arg("meshes"), py::arg("range"),
           py::arg("source"), py::arg("frames"), py::arg("frames_per_step"), py::arg("folder"))
      .def("stats", &PySeries::stats);
}

} // namespace exa::pymod
