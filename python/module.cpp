// exabricks._core: the library for Python. Datasets (loaded, from numpy cells or from grids),
// a renderer driven by the scene JSON of render/scene.h (renderer.cpp), meshes from numpy arrays,
// sampling and the model description, time series (series.cpp). The pure-Python package
// (python/exabricks) builds on it.
#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/documents/image.h"
#include "exabricks/documents/mesh.h"
#include "exabricks/documents/scene_file.h"
#include "exabricks/documents/transfer_function_file.h"
#include "exabricks/io/grids.h"
#include "exabricks/io/load.h"
#include "exabricks/io/model_info.h"
#include "exabricks/io/particles.h"
#include "exabricks/render/defaults.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/scene_vocabulary.h"
#include "exabricks/workflows/coarse_first.h"
#include "exabricks/workflows/progressive.h"

#include "core.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

namespace py = pybind11;
using namespace exa;
using exa::pymod::Dataset;
using exa::pymod::Mesh;

py::array_t<float> exa::pymod::imageArray(const Image& img) {
  py::array_t<float> out({size_t(img.height), size_t(img.width), size_t(4)});
  std::memcpy(out.mutable_data(), img.pixels.data(), img.pixels.size() * sizeof(vec4f));
  return out;
}

namespace {

/// Units per field, one each or none at all (every field without units).
void checkUnits(const std::vector<std::string>& units, size_t fields) {
  if (!units.empty() && units.size() != fields)
    fail("units: ", units.size(), " given for ", fields, " fields (one per field, or none)");
}

std::shared_ptr<Dataset> makeDataset(Model&& m, std::string name, double seconds) {
  auto d = std::make_shared<Dataset>();
  d->model = std::make_shared<const Model>(std::move(m));
  d->info = DatasetInfo::of(*d->model);
  d->name = std::move(name);
  d->loadSeconds = seconds;
  return d;
}

std::shared_ptr<Dataset> load(const std::string& path, const std::vector<std::string>& fields, int maxBrickWidth,
                              const std::vector<int>& box, bool nanAsHoles, const std::string& memoryBudget) {
  LoadOptions o;
  o.fields = fields;
  if (nanAsHoles) o.nonFinite = NonFinite::Holes;
  o.build.bricks.maxBrickWidth = maxBrickWidth;
  if (!box.empty()) {
    if (box.size() != 6) fail("box must hold six integers x0, y0, z0, x1, y1, z1 (finest lattice units)");
    o.box = box3i(vec3i(box[0], box[1], box[2]), vec3i(box[3], box[4], box[5]));
  }
  Timer t;
  if (!memoryBudget.empty()) {
    uint64_t budget = 0;
    if (!parseByteSize(memoryBudget, budget))
      fail("memory_budget: '", memoryBudget, "' is not a size (e.g. 512M, 2G, or a number of bytes)");
    if (!box.empty()) fail("memory_budget and box: choose one (a box already reads only its cells)");
    std::shared_ptr<StreamedStep> step;
    std::optional<CoarseLevels> coarse;
    {
      py::gil_scoped_release release;
      // Room for a 1024² frame of a few passes beside what drafts come from (the coarse levels
      // where the format reads them alone, else every cell merged where it can be) and the parts
      // planned beside it.
      const uint64_t frameBytes = streamedFrameBytes(1024, 1024, 4);
      if (std::optional<CoarseBeside> c = coarseBesideParts(path, o, budget, frameBytes, 0, "a Scene")) {
        if (c->coarse.level > 0) coarse = loadCoarseLevels(path, o, c->coarse);
        if (c->mergedCells > 0) coarse = loadMergedLeavesFirst(path, o, c->mergedCells);
        step = std::make_shared<StreamedStep>(path, o, std::move(c->parts), coarse ? coarse->model.get() : nullptr);
        step->survey();
      }
    }
    if (step) {
      auto d = std::make_shared<Dataset>();
      d->model = coarse ? coarse->model : std::make_shared<const Model>(step->skeleton());
      d->coarse = coarse.has_value();
      d->leavesMerged = coarse && coarse->leavesMerged;
      d->info = step->survey().dataset;
      d->name = path.empty() ? kDefaultDatasetName : path;
      d->path = path;
      d->loadSeconds = t.seconds();
      d->streamed = std::move(step);
      return d;
    }
  }
  Model m;
  {
    py::gil_scoped_release release;
    m = loadModel(path, o);
  }
  std::shared_ptr<Dataset> d = makeDataset(std::move(m), path.empty() ? kDefaultDatasetName : path, t.seconds());
  d->path = path;
  return d;
}

std::shared_ptr<Dataset> fromCells(py::array_t<int64_t, py::array::c_style | py::array::forcecast> corners,
                                   py::array_t<int64_t, py::array::c_style | py::array::forcecast> levels,
                                   const std::vector<std::pair<std::string, py::array>>& fields,
                                   const std::vector<double>& origin, const std::vector<double>& spacing,
                                   int maxBrickWidth, const std::vector<std::string>& units) {
  if (corners.ndim() != 2 || corners.shape(1) != 3) fail("corners must be an (N, 3) integer array");
  const size_t n = size_t(corners.shape(0));
  if (levels.ndim() != 1 || size_t(levels.shape(0)) != n)
    fail("levels must be an (N,) integer array with one level per corner (", n, " corners, ",
         levels.ndim() == 1 ? size_t(levels.shape(0)) : size_t(0), " levels)");
  if (origin.size() != 3 || spacing.size() != 3) fail("origin and spacing need three numbers each");
  CellSet set;
  set.world.origin = vec3d(origin[0], origin[1], origin[2]);
  set.world.scale = vec3d(spacing[0], spacing[1], spacing[2]);
  for (int a = 0; a < 3; ++a)
    if (!(set.world.scale[a] > 0.0) || !std::isfinite(set.world.scale[a]) || !std::isfinite(set.world.origin[a]))
      fail("spacing must be positive and finite, origin finite");
  set.cells.resize(n);
  const int64_t* c = corners.data();
  const int64_t* l = levels.data();
  for (size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      const int64_t v = c[3 * i + size_t(a)];
      if (v < -kLatticeLimit || v > kLatticeLimit)
        fail("cell ", i, ": corner ", v, " is outside the supported lattice range (±2^29)");
      set.cells[i].lower[a] = int32_t(v);
    }
    if (l[i] < 0 || l[i] > kMaxLevel) fail("cell ", i, ": level ", l[i], " is outside 0..", kMaxLevel);
    set.cells[i].level = int(l[i]);
  }
  if (fields.empty()) fail("at least one field is needed");
  checkUnits(units, fields.size());
  for (const auto& [name, array] : fields) {
    const auto values = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(array);
    if (!values || values.ndim() != 1 || size_t(values.shape(0)) != n)
      fail("field '", name, "' must be an (N,) array of numbers with one value per cell (", n, " cells)");
    set.fields.push_back({name, std::vector<float>(values.data(), values.data() + n),
                          units.empty() ? std::string() : units[set.fields.size()]});
  }
  BuildOptions bo;
  bo.bricks.maxBrickWidth = maxBrickWidth;
  Timer t;
  Model m;
  {
    py::gil_scoped_release release;
    validateCells(set, "cells");
    m = buildModel(std::move(set), bo);
  }
  return makeDataset(std::move(m), "<numpy cells>", t.seconds());
}

/// The species of an input, each a dict of its name, count, attributes and precision.
py::list listParticleSpecies(const std::string& path) {
  py::list out;
  for (const ParticleSpeciesInfo& s : listParticles(path)) {
    py::dict d;
    d["name"] = s.name;
    d["count"] = s.count;
    d["attributes"] = s.attributes;
    d["precision"] = s.precision;
    out.append(std::move(d));
  }
  return out;
}

/// Every species (or the one named) read: a dict per species name of "position" (N, 3) and each
/// attribute (N,), float64 arrays (integer attributes as int64).
py::dict readParticleSpecies(const std::string& path, const std::string& species) {
  ParticleSet set;
  {
    py::gil_scoped_release release;
    set = readParticles(path, species);
  }
  py::dict out;
  for (const ParticleSpecies& s : set.species) {
    py::dict d;
    py::array_t<double> position({py::ssize_t(s.count()), py::ssize_t(3)});
    std::copy(s.position.begin(), s.position.end(), position.mutable_data());
    d["position"] = std::move(position);
    for (const ParticleAttribute& a : s.attributes) {
      if (a.integer) {
        py::array_t<int64_t> v(py::ssize_t(a.values.size()));
        std::transform(a.values.begin(), a.values.end(), v.mutable_data(), [](double x) { return int64_t(x); });
        d[py::str(a.name)] = std::move(v);
      } else {
        py::array_t<double> v(py::ssize_t(a.values.size()));
        std::copy(a.values.begin(), a.values.end(), v.mutable_data());
        d[py::str(a.name)] = std::move(v);
      }
    }
    out[py::str(s.name)] = std::move(d);
  }
  return out;
}

/// Particles given from Python: (name, position (N, 3), {attribute: (N,)}) per species.
void setParticles(
    Dataset& d,
    const std::vector<std::tuple<std::string, py::array_t<double, py::array::c_style | py::array::forcecast>,
                                 std::map<std::string, py::array>>>& species) {
  auto set = std::make_shared<ParticleSet>();
  for (const auto& [name, position, attributes] : species) {
    if (position.ndim() != 2 || position.shape(1) != 3)
      fail("particles '", name, "': position must be an (N, 3) array");
    ParticleSpecies s;
    s.name = name;
    s.precision = "double";
    s.position.assign(position.data(), position.data() + position.size());
    const size_t n = size_t(position.shape(0));
    for (const auto& [attr, values] : attributes) {
      auto v = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
      if (!v || v.ndim() != 1 || size_t(v.shape(0)) != n)
        fail("particles '", name, "': attribute '", attr, "' must be an (N,) array of ", n, " numbers");
      s.attributes.push_back(
          {attr, std::vector<double>(v.data(), v.data() + n), py::dtype::of<int64_t>().is(values.dtype())});
    }
    set->species.push_back(std::move(s));
  }
  d.particles = std::move(set);
  d.particlesKnown = true;
}

/// grids: list of (lower xyz, upper xyz, cells xyz, [arrays per field, x fastest]).
std::shared_ptr<Dataset> fromGrids(const py::list& grids, const std::vector<std::string>& names,
                                   const std::vector<double>& origin, int maxBrickWidth,
                                   const std::vector<std::string>& units) {
  checkUnits(units, names.size());
  std::vector<GridPatch> patches;
  for (size_t g = 0; g < grids.size(); ++g) {
    const py::tuple t = grids[g].cast<py::tuple>();
    GridPatch p;
    const auto lo = t[0].cast<std::vector<double>>(), hi = t[1].cast<std::vector<double>>();
    const auto n = t[2].cast<std::vector<int64_t>>();
    if (lo.size() != 3 || hi.size() != 3 || n.size() != 3)
      fail("grid ", g, ": edges and dimensions need three numbers");
    p.lower = vec3d(lo[0], lo[1], lo[2]);
    p.upper = vec3d(hi[0], hi[1], hi[2]);
    p.cells = vec3l(n[0], n[1], n[2]);
    for (const py::handle& a : t[3].cast<py::list>()) {
      const auto v = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
      if (!v) fail("grid ", g, ": field values must be numeric arrays");
      p.values.emplace_back(v.data(), v.data() + v.size());
    }
    patches.push_back(std::move(p));
  }
  vec3d o;
  if (origin.size() == 3)
    o = vec3d(origin[0], origin[1], origin[2]);
  else if (!origin.empty())
    fail("origin needs three numbers");
  BuildOptions bo;
  bo.bricks.maxBrickWidth = maxBrickWidth;
  Timer t;
  Model m;
  {
    py::gil_scoped_release release;
    PatchSource source = patchesOfGrids(std::move(patches), names, "grids", origin.empty() ? nullptr : &o);
    for (size_t f = 0; f < units.size() && f < source.fieldUnits.size(); ++f)
      source.fieldUnits[f] = units[f];
    m = buildModelOfPatches(source, {}, bo);
    if (m.bricks.empty()) fail("grids: no cells");
  }
  return makeDataset(std::move(m), "<grids>", t.seconds());
}

py::tuple sample(const Dataset& d, py::array_t<double, py::array::c_style | py::array::forcecast> points,
                 const std::string& field) {
  if (points.ndim() != 2 || points.shape(1) != 3) fail("points must be an (N, 3) array of world positions");
  const int f = d.model->requireField(field);
  const size_t n = size_t(points.shape(0));
  py::array_t<double> values(n);
  py::array_t<double> gradients({n, size_t(3)});
  const double* p = points.data();
  double* v = values.mutable_data();
  double* g = gradients.mutable_data();
  if (d.streamed) {
    std::vector<vec3d> at(n);
    for (size_t i = 0; i < n; ++i)
      at[i] = vec3d(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    std::vector<double> vs;
    std::vector<vec3d> gs;
    std::vector<bool> found;
    {
      py::gil_scoped_release release;
      d.streamed->sample(f, at, vs, gs, found);
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (size_t i = 0; i < n; ++i) {
      v[i] = found[i] ? vs[i] : nan;
      g[3 * i] = found[i] ? gs[i].x : nan, g[3 * i + 1] = found[i] ? gs[i].y : nan,
            g[3 * i + 2] = found[i] ? gs[i].z : nan;
    }
    return py::make_tuple(values, gradients);
  }
  {
    py::gil_scoped_release release;
    for (size_t i = 0; i < n; ++i) {
      double value;
      vec3d grad;
      if (d.model->sampleWorld(f, vec3d(p[3 * i], p[3 * i + 1], p[3 * i + 2]), value, grad)) {
        v[i] = value;
        g[3 * i] = grad.x, g[3 * i + 1] = grad.y, g[3 * i + 2] = grad.z;
      } else {
        v[i] = g[3 * i] = g[3 * i + 1] = g[3 * i + 2] = std::numeric_limits<double>::quiet_NaN();
      }
    }
  }
  return py::make_tuple(values, gradients);
}

std::shared_ptr<Mesh> makeMesh(py::array_t<float, py::array::c_style | py::array::forcecast> vertices,
                               py::array_t<int64_t, py::array::c_style | py::array::forcecast> triangles) {
  if (vertices.ndim() != 2 || vertices.shape(1) != 3) fail("mesh vertices must be an (V, 3) array");
  if (triangles.ndim() != 2 || triangles.shape(1) != 3) fail("mesh triangles must be a (T, 3) integer array");
  auto mesh = std::make_shared<TriangleMesh>();
  const float* v = vertices.data();
  for (py::ssize_t i = 0; i < vertices.shape(0); ++i)
    mesh->vertices.push_back({v[3 * i], v[3 * i + 1], v[3 * i + 2]});
  const int64_t* t = triangles.data();
  for (py::ssize_t i = 0; i < triangles.shape(0); ++i) {
    vec3i tri;
    for (int k = 0; k < 3; ++k) {
      const int64_t idx = t[3 * i + k];
      if (idx < 0 || idx >= vertices.shape(0))
        fail("mesh triangle ", i, " refers to vertex ", idx, " of ", vertices.shape(0));
      tri[k] = int32_t(idx);
    }
    mesh->triangles.push_back(tri);
  }
  auto m = std::make_shared<Mesh>();
  m->mesh = mesh;
  return m;
}

/// The command line's `info --json`: the model's description, the device object and the
/// particle species.
std::string infoJson(const Dataset& d) {
  const std::string particles =
      ",\"particles\":" +
      particleSpeciesJson(d.path.empty() ? std::vector<ParticleSpeciesInfo>() : listParticles(d.path)) + "}";
  std::string j =
      d.streamed ? d.streamed->infoJson(d.name, d.loadSeconds) : modelInfoJson(*d.model, d.name, d.loadSeconds);
  const size_t end = j.find_last_of('}');
  if (end == std::string::npos) fail("internal: model information is not a JSON object");
  if (d.streamed) return j.substr(0, end) + particles;
  return j.substr(0, end) + ",\"device\":" + deviceInfoJson(*d.model) + particles;
}

void bindDataset(py::module_& m) {
  py::class_<Dataset, std::shared_ptr<Dataset>>(m, "Dataset")
      .def_property_readonly("name", [](const Dataset& d) { return d.name; })
      .def_property_readonly("fields", [](const Dataset& d) { return d.model->fieldNames; })
      .def_property_readonly(
          "units",
          [](const Dataset& d) {
            std::vector<std::string> u;
            for (size_t f = 0; f < d.model->fieldNames.size(); ++f)
              u.push_back(d.model->unitsOf(int(f)));
            return u;
          },
          "Units per field, in field order (empty where unknown)")
      .def_property_readonly(
          "cells", [](const Dataset& d) { return d.streamed ? d.streamed->survey().cells : d.model->cellCount(); })
      .def_property_readonly("memory",
                             [](const Dataset& d) -> py::object {
                               if (!d.streamed) return py::none();
                               const MemoryPlan& p = d.streamed->plan();
                               py::dict memory;
                               memory["budget_bytes"] = p.budget;
                               memory["parts"] = d.streamed->parts();
                               memory["resident_parts"] = d.streamed->residentParts();
                               memory["parts_read"] = d.streamed->partsRead();
                               memory["largest_part_bytes"] = p.largestPartBytes();
                               memory["peak_rss_bytes"] = peakResidentBytes();
                               return py::object(std::move(memory));
                             })
      .def_property_readonly("bounds",
                             [](const Dataset& d) {
                               const box3i b = d.cellBounds();
                               const vec3d lo = d.model->world.toWorld(vec3d(b.lower));
                               const vec3d hi = d.model->world.toWorld(vec3d(b.upper));
                               return py::make_tuple(py::make_tuple(lo.x, lo.y, lo.z),
                                                     py::make_tuple(hi.x, hi.y, hi.z));
                             })
      .def("default_field", [](const Dataset& d) { return d.model->fieldNames[size_t(d.model->requireField(""))]; })
      .def_property_readonly("default_opacity_scale", [](const Dataset& d) { return d.info.defaultOpacityScale; })
      .def_property_readonly(
          "opacity_reference_width",
          [](const Dataset& d) {
            const vec3d s = d.model->world.scale;
            return double(d.info.referenceWidth) * (s.x + s.y + s.z) / 3.0;
          },
          "World length opacity is given per: the finest cell width (averaged over the axes)")
      .def("info_json", &infoJson)
      .def("sample", &sample, py::arg("points"), py::arg("field") = "")
      .def("set_particles", &setParticles, py::arg("species"),
           "Gives the dataset particles (from_yt): a list of (name, position (N, 3), {attribute: (N,)})")
      .def(
          "adapt_transfer_function",
          [](const Dataset& d, const std::string& field, const std::string& tfJson, bool autoLog, bool autoOpacity) {
            const int f = d.model->requireField(field);
            const PartialData parts = d.streamed ? d.streamed->partialData() : PartialData();
            const DefaultChoices c =
                adaptTransferFunction(*d.model, d.info, f, parseTransferFunction(tfJson, "transfer function"), autoLog,
                                      autoOpacity, d.streamed ? &parts : nullptr);
            return py::make_tuple(transferFunctionJson(c.tf), c.notes);
          },
          py::arg("field"), py::arg("tf_json"), py::arg("auto_log") = true, py::arg("auto_opacity") = true)
      .def(
          "warnings",
          [](const Dataset& d, const std::string& sceneJson) {
            const SceneDocument doc = readSceneJson(sceneJson, "scene");
            return sceneWarnings(doc.scene, *d.model, d.info);
          },
          py::arg("scene_json"));
}

void bindMesh(py::module_& m) {
  py::class_<Mesh, std::shared_ptr<Mesh>>(m, "Mesh")
      .def(py::init(&makeMesh), py::arg("vertices"), py::arg("triangles"))
      .def_static(
          "read",
          [](const std::string& path) {
            auto x = std::make_shared<Mesh>();
            x->mesh = std::make_shared<TriangleMesh>(readMesh(path));
            x->source = path;
            return x;
          },
          py::arg("path"), "Reads an OBJ, PLY or .tris file")
      .def_property_readonly(
          "source", [](const Mesh& x) { return x.source; }, "The file the mesh was read from (empty: made from arrays)")
      .def_property_readonly(
          "vertices",
          [](const Mesh& x) {
            py::array_t<float> out({py::ssize_t(x.mesh->vertices.size()), py::ssize_t(3)});
            float* v = out.mutable_data();
            for (const vec3f& p : x.mesh->vertices)
              for (int k = 0; k < 3; ++k)
                *v++ = p[k];
            return out;
          },
          "The vertices, a (V, 3) float32 array (a copy)")
      .def_property_readonly(
          "triangles",
          [](const Mesh& x) {
            py::array_t<int64_t> out({py::ssize_t(x.mesh->triangles.size()), py::ssize_t(3)});
            int64_t* t = out.mutable_data();
            for (const vec3i& tri : x.mesh->triangles)
              for (int k = 0; k < 3; ++k)
                *t++ = tri[k];
            return out;
          },
          "The triangles' vertex indices, a (T, 3) int64 array (a copy)")
      .def_property_readonly("vertex_count", [](const Mesh& x) { return x.mesh->vertices.size(); })
      .def_property_readonly("triangle_count", [](const Mesh& x) { return x.mesh->triangles.size(); });
}

/// The functions that make datasets: load, from_cells, from_grids, and list_fields.
void bindDatasetFunctions(py::module_& m) {
  m.def("list_particles", &listParticleSpecies, py::arg("path"));
  m.def("read_particles", &readParticleSpecies, py::arg("path"), py::arg("species") = "");
  m.def("load", &load, py::arg("path"), py::arg("fields") = std::vector<std::string>(), py::arg("max_brick_width") = 32,
        py::arg("box") = std::vector<int>(), py::arg("nan_as_holes") = false, py::arg("memory_budget") = "");
  m.def("from_cells", &fromCells, py::arg("corners"), py::arg("levels"), py::arg("fields"), py::arg("origin"),
        py::arg("spacing"), py::arg("max_brick_width") = 32, py::arg("units") = std::vector<std::string>());
  m.def("from_grids", &fromGrids, py::arg("grids"), py::arg("names"), py::arg("origin"),
        py::arg("max_brick_width") = 32, py::arg("units") = std::vector<std::string>());
  m.def("list_fields", &listFields, py::arg("path"));
}

/// The command line's conventions for the Python package: framing, scene files, the scene
/// vocabulary, default fields, colour maps, PNG files and transfer-function files.
void bindSceneFunctions(py::module_& m) {
  m.def(
      "frame_camera",
      [](const std::vector<double>& lo, const std::vector<double>& hi, double azimuth, double elevation, double fov,
         bool orthographic) {
        if (lo.size() != 3 || hi.size() != 3) fail("bounds need three numbers per corner");
        const Camera c = Camera::frame(box3d(vec3d(lo[0], lo[1], lo[2]), vec3d(hi[0], hi[1], hi[2])), azimuth,
                                       elevation, fov, orthographic);
        py::dict d;
        d["position"] = py::make_tuple(c.position.x, c.position.y, c.position.z);
        d["look_at"] = py::make_tuple(c.lookAt.x, c.lookAt.y, c.lookAt.z);
        d["up"] = py::make_tuple(c.up.x, c.up.y, c.up.z);
        d["fov"] = c.fovy;
        d["orthographic"] = c.orthographic;
        d["ortho_height"] = c.orthoHeight;
        return d;
      },
      py::arg("lower"), py::arg("upper"), py::arg("azimuth"), py::arg("elevation"), py::arg("fov"),
      py::arg("orthographic"), "The command line's default framing of a world box");
  m.def(
      "scene_json",
      [](const std::string& text, const std::string& source) { return writeSceneJson(readSceneJson(text, source)); },
      py::arg("text"), py::arg("source"),
      "A scene file's JSON checked by the command line's reader (unknown keys and invalid settings are "
      "refused with its messages, naming `source`) and written back by its writer, with every setting");
  m.def("scene_structure", &sceneStructureJson,
        "Every structured key of a scene file (camera, layers, transfer functions, iso, meshes, clipping, camera "
        "path) and the device choice as JSON: key, type, kind, range, choices, default, example and help");
  m.def("scene_example", &sceneExampleJson, "A scene file that uses every structured key at its example value");
  m.def("scene_vocabulary", &sceneVocabularyJson,
        "Every described setting of a scene file as JSON: key, name, type, default, range, choices, kind and "
        "help");
  m.def("next_draft_divisor", &nextDraftDivisor, py::arg("divisor"), py::arg("width"), py::arg("height"),
        py::arg("draft_pixels"), py::arg("seconds"), py::arg("budget"), py::arg("max_divisor"),
        "The divisor of the resolution for the next draft (the library's progressive views' rule)");
  m.def(
      "default_field_index",
      [](const std::vector<std::string>& names) {
        Model model;
        model.fieldNames = names;
        return model.requireField("");
      },
      py::arg("names"), "Which of these field names the command line takes by default");
  m.def("colormap_names", &builtinColorMapNames);
  m.def(
      "read_png", [](const std::string& path) { return pymod::imageArray(readPng(path)); }, py::arg("path"),
      "An 8-bit PNG as an (H, W, 4) float32 array of linear, premultiplied RGBA");
}

} // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "exabricks: ExaBricks rendering of structured AMR data (C++ core)";
  m.attr("DEFAULT_DATASET_NAME") = kDefaultDatasetName;
  m.attr("EMBEDDED_INPUT") = kEmbeddedInput;
  m.attr("VERSION") = EXABRICKS_VERSION; // the command line's `exabricks --version`
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const std::bad_alloc&) {
      PyErr_SetString(PyExc_MemoryError, "out of memory");
    }
  });

  bindDataset(m);
  bindMesh(m);
  pymod::bindRenderer(m);
  bindDatasetFunctions(m);
  bindSceneFunctions(m);
  pymod::bindSeries(m);
  m.def(
      "transfer_function_json",
      [](const std::string& path) {
        bool preset = false;
        const TransferFunction tf = readTransferFunction(path, &preset);
        return py::make_tuple(transferFunctionJson(tf), preset);
      },
      py::arg("path"),
      "A transfer function file (exabricks JSON or ParaView preset) in exabricks JSON form, "
      "and whether it was a ParaView preset");
}
