#include "exabricks/workflows/streamed.h"

#include "part_cache.h"

#include "exabricks/amr/scenes.h"
#include "exabricks/core/files.h"
#include "exabricks/core/kept.h"
#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/io/model_info.h"
#include "exabricks/render/composite.h"
#include "exabricks/render/defaults.h"

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <malloc.h>
#include <tuple>

namespace exa {

namespace {

uint64_t statusKiB(const char* file, const std::string& key) {
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(key, 0) == 0) return uint64_t(std::strtoull(line.c_str() + key.size(), nullptr, 10)) * 1024u;
  return 0;
}

/// Room the process keeps beyond its measured size: thread stacks and pools of the workers,
/// Embree's and the allocator's slack.
constexpr uint64_t kProcessSlack = uint64_t(24) << 20;
/// The per-pass composites a streamed frame keeps at once (passes beyond are drawn in rounds).
constexpr uint64_t kCompositeBytes = uint64_t(32) << 20;

int passesPerRound(size_t pixels, int samplesPerPixel) {
  const uint64_t perPass = uint64_t(pixels) * kCompositeChannels * sizeof(float);
  return int(std::clamp<uint64_t>(kCompositeBytes / std::max<uint64_t>(perPass, 1), 1, uint64_t(samplesPerPixel)));
}

size_t loadedFields(const std::string& input, const LoadOptions& options) {
  return options.fields.empty() ? std::max<size_t>(listFields(input).size(), 1) : options.fields.size();
}

} // namespace

namespace {
std::string smallestSaid(uint64_t smallest, const std::string& why) {
  return strCat("; the smallest budget that works is ", formatBytes(smallest), " (--memory-budget ", smallest >> 20,
                "M)", why.empty() ? "" : ", ", why);
}
} // namespace

BudgetTooSmall::BudgetTooSmall(std::string what, uint64_t smallestBudget, uint64_t fixed, uint64_t partBytes,
                               uint64_t perCell, const std::string& why)
    : Error(what + smallestSaid(smallestBudget, why)), situation(std::move(what)), smallest(smallestBudget),
      fixedBytes(fixed), smallestPartBytes(partBytes), bytesPerCell(perCell) {}

uint64_t residentBytesNow() { return statusKiB("/proc/self/status", "VmRSS:"); }
uint64_t peakResidentBytes() { return statusKiB("/proc/self/status", "VmHWM:"); }
uint64_t availableMemoryBytes() { return statusKiB("/proc/meminfo", "MemAvailable:"); }

uint64_t bytesPerResidentCell(size_t fields, bool fromBoxes) {
  // Per loaded field: 4 bytes of values, and 8 of smooth shading's packed gradient fields (each
  // beside a copy of its cell's value), which the renderer builds for the shaded field; the
  // build's records and slot index, bricks, regions and the renderer's tables come to about 24
  // bytes per cell more, 8 without records (a build from boxes: bricks, regions and tables alone).
  return (fromBoxes ? 8 : 24) + 4 * uint64_t(fields) + 8;
}

uint64_t MemoryPlan::partBytes(int part) const {
  return uint64_t(std::ceil(partCells.at(size_t(part)))) * bytesPerCell;
}

uint64_t MemoryPlan::largestPartBytes() const {
  uint64_t most = 0;
  for (int p = 0; p < int(partCells.size()); ++p)
    most = std::max(most, partBytes(p));
  return most;
}

namespace {
/// The census balanced into `parts` parts with the cells each reads (its halo's included), kept
/// for the process: a viewer plans its step more than once (for the budget's refusal, beside its
/// coarse levels, and for the parts it draws), and each plan tries the same part counts.
std::pair<KdPartition, std::vector<double>> balancedParts(const std::string& input, const Census& census, int parts,
                                                          int64_t grain) {
  static KeptResults<std::pair<KdPartition, std::vector<double>>> kept(32);
  const std::string key = strCat(input, "|", census.boxes.size(), "|", census.cells(), "|", census.bounds().lower.x,
                                 ",", census.bounds().upper.x, "|", parts, "|", grain);
  if (auto balanced = kept.find(key)) return *balanced;
  KdPartition partition = KdPartition::balance(census, parts, grain);
  std::vector<double> cells = cellsReadByParts(census, partition);
  return *kept.keep(key, std::make_pair(std::move(partition), std::move(cells)));
}
} // namespace

namespace {
MemoryPlan sizedPlan(const std::string& input, const LoadOptions& options, uint64_t budget, uint64_t frameBytes,
                     const Census& census, uint64_t fixedBefore) {
  MemoryPlan plan;
  plan.budget = budget;
  plan.bytesPerCell = bytesPerResidentCell(loadedFields(input, options), buildsFromBoxes(input, options));
  plan.fixedBytes = std::max(fixedBefore, residentBytesNow() + kProcessSlack + frameBytes);
  plan.cells = census.cells();
  plan.coarsestLevel = census.coarsestLevel;
  plan.cellBounds = census.cellBounds;
  plan.levelCells = census.levelCells;
  plan.partCells = {plan.cells};
  return plan;
}
} // namespace

bool MemoryPlan::fitsWhole() const {
  return fixedBytes + uint64_t(std::ceil(cells)) * bytesPerCell <= budget || cells < 1;
}

MemoryPlan sizeMemory(const std::string& input, const LoadOptions& options, uint64_t budget, uint64_t frameBytes) {
  const uint64_t fixedBefore = residentBytesNow() + kProcessSlack + frameBytes;
  return sizedPlan(input, options, budget, frameBytes, loadCensus(input, options), fixedBefore);
}

MemoryPlan planMemory(const std::string& input, const LoadOptions& options, uint64_t budget, uint64_t frameBytes) {
  const uint64_t fixedBefore = residentBytesNow() + kProcessSlack + frameBytes;
  const Census census = loadCensus(input, options);
  const Timer timer;
  MemoryPlan plan = sizedPlan(input, options, budget, frameBytes, census, fixedBefore);
  const uint64_t whole = plan.fixedBytes + uint64_t(std::ceil(plan.cells)) * plan.bytesPerCell;
  if (plan.fitsWhole()) return plan;

  // The fewest parts whose largest part fits, trying 2, 3, 4, 6, 8, 12, ... parts (the same
  // counts for any budget, so the smallest budget named below is one that works). Halos stop
  // shrinking the largest part beyond some count.
  // Counts whose parts could not fit even without halos are not balanced where some count up to
  // 256 might (every cell belongs to a part, so the largest holds at least plan.cells / parts).
  // Where none can (a budget far too small), every count is tried as before, for the smallest
  // budget the refusal names.
  const int64_t grain = int64_t(1) << census.coarsestLevel;
  const double room = budget > plan.fixedBytes ? double(budget - plan.fixedBytes) / double(plan.bytesPerCell) : 0.0;
  const bool skipSmall = plan.cells <= 256.0 * room;
  double bestLargest = std::numeric_limits<double>::infinity();
  int worse = 0;
  for (int parts = 2; parts <= 65536 && worse < 3; parts = parts % 3 == 0 ? parts / 3 * 4 : parts / 2 * 3) {
    if (skipSmall && plan.cells > double(parts) * room) continue;
    auto [partition, cells] = balancedParts(input, census, parts, grain);
    const double largest = *std::max_element(cells.begin(), cells.end());
    if (plan.fixedBytes + uint64_t(std::ceil(largest)) * plan.bytesPerCell <= budget) {
      plan.partition = std::move(partition);
      plan.partCells = std::move(cells);
      logInfo(strCat("memory plan: ", parts, " parts within ", formatBytes(budget), " in ", timer.seconds(), " s"));
      return plan;
    }
    worse = largest < 0.97 * bestLargest ? 0 : worse + 1;
    bestLargest = std::min(bestLargest, largest);
  }
  // Named with a few MiB to spare: the process's own size varies a little from run to run.
  const uint64_t smallest =
      wholeMebibytes(plan.fixedBytes + uint64_t(std::ceil(bestLargest)) * plan.bytesPerCell + (uint64_t(4) << 20));
  throw BudgetTooSmall(strCat("a memory budget of ", formatBytes(budget), " cannot hold ",
                              input.empty() ? std::string(kDefaultDatasetName) : input, " (", std::llround(plan.cells),
                              " cells): this process needs ", formatBytes(plan.fixedBytes),
                              " without data, the whole step about ", formatBytes(whole - plan.fixedBytes),
                              " more (held whole: --memory-budget ", wholeMebibytes(whole) >> 20,
                              "M) and its smallest part about ", formatBytes(smallest - plan.fixedBytes)),
                       smallest, plan.fixedBytes, smallest - plan.fixedBytes, plan.bytesPerCell);
}

std::optional<uint64_t> budgetForLargeStep(const std::string& input, const LoadOptions& options, uint64_t frameBytes) {
  if (input.empty()) return std::nullopt;
  const InputKind kind = detectInput(input);
  const FormatReader* reader = findReader(input);
  // Counted only by reading; a model file, from its brick table.
  if (kind != InputKind::Model && (!reader || !reader->census)) return std::nullopt;
  const uint64_t available = availableMemoryBytes();
  if (available == 0) return std::nullopt;
  const uint64_t budget = available / 4 * 3;
  const double perCell = double(bytesPerResidentCell(loadedFields(input, options), buildsFromBoxes(input, options)));
  const double fixed = double(residentBytesNow() + kProcessSlack + frameBytes);
  // An upper bound from sizes alone first (the records of NAME.cells, a model's bytes at 4 per cell
  // (a field's value), the cells in the boxes of a patch-based file): a step that fits by it is
  // read as before, without a census.
  const double most = kind == InputKind::Native  ? double(fileSize(input) / sizeof(Cell))
                      : kind == InputKind::Model ? double(fileSize(input) / sizeof(float))
                                                 : coarseFirstLevel(input, std::numeric_limits<double>::max()).cells;
  if (fixed + most * perCell <= double(budget)) return std::nullopt;
  const Census census = loadCensus(input, options);
  const double need = fixed + census.cells() * perCell;
  if (need <= double(budget)) return std::nullopt;
  logWarning(strCat(input, " holds ", std::llround(census.cells()), " cells, about ", formatBytes(uint64_t(need)),
                    " held whole, more than three quarters of the memory available (", formatBytes(available),
                    "): reading it in parts within a budget of ", formatBytes(budget), " (--memory-budget to choose)"));
  return budget;
}

uint64_t streamedFrameBytes(int width, int height, int samplesPerPixel) {
  const size_t pixels = size_t(width) * size_t(height);
  const uint64_t buffer = uint64_t(pixels) * (sizeof(vec4f) + sizeof(float)); // a FrameBuffer's sums
  const uint64_t perPass = uint64_t(pixels) * kCompositeChannels * sizeof(float);
  const uint64_t image = uint64_t(pixels) * 4 * sizeof(float) * 2; // resolved and written
  return 2 * buffer + perPass * uint64_t(1 + passesPerRound(pixels, samplesPerPixel)) + image;
}

namespace {

/// Every file of an input with its size and time of last change: the input itself, the files of
/// a directory (an AMReX plotfile), or NAME.cells with its NAME[.FIELD].scalars.
std::vector<std::tuple<std::string, uintmax_t, std::filesystem::file_time_type>> snapshotOf(const std::string& input) {
  namespace fs = std::filesystem;
  std::vector<std::tuple<std::string, uintmax_t, fs::file_time_type>> files;
  if (input.empty()) return files;
  std::error_code ec;
  auto add = [&](const fs::path& p) {
    if (fs::is_regular_file(p, ec)) files.emplace_back(p.string(), fs::file_size(p, ec), fs::last_write_time(p, ec));
  };
  const fs::path path(input);
  if (fs::is_directory(path, ec)) {
    for (fs::recursive_directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec))
      add(it->path());
  } else {
    add(path);
    const std::string stem = path.stem().string();
    const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
      if (const std::string name = it->path().filename().string();
          it->path() != path && name.rfind(stem + ".", 0) == 0 && it->path().extension() == ".scalars")
        add(it->path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

} // namespace

struct StreamedStep::Snapshot {
  std::vector<std::tuple<std::string, uintmax_t, std::filesystem::file_time_type>> files;
};

struct StreamedStep::Resident {
  int part = 0;
  std::unique_ptr<Model> model; ///< null: the part holds no cells
  std::unique_ptr<Renderer> renderer;
  bool outlined = false; ///< the renderer was built with the step's outline (no value ranges)
  uint64_t bytes = 0;
};

StreamedStep::StreamedStep(std::string input, LoadOptions options, MemoryPlan plan, const Model* like)
    : input_(std::move(input)), options_(std::move(options)), plan_(std::move(plan)),
      snapshot_(std::make_unique<Snapshot>(Snapshot{snapshotOf(input_)})) {
  options_.partCells = 0; // the parts are this step's own
  options_.box = box3i();
  gathered_.assign(size_t(parts()), false);
  uint64_t partsBytes = 0;
  for (int p = 0; p < parts(); ++p)
    partsBytes += plan_.partBytes(p);
  cache_ = std::make_unique<PartCache>(parts(), parts() > 1 ? partsBytes : 0);
  // The skeleton: the step's world, fields and simulation from a part that holds cells.
  for (int p = 0; p < parts(); ++p) {
    const Model* m = like;
    if (!m) {
      Resident& r = bring(p);
      if (!r.model) continue;
      m = r.model.get();
    }
    skeleton_.world = m->world;
    skeleton_.simulation = m->simulation;
    skeleton_.fieldNames = m->fieldNames;
    skeleton_.fieldUnits = m->fieldUnits;
    skeleton_.fieldValues.assign(m->fieldNames.size(), ValueArray());
    outline_ = outlineOf(plan_, options_, skeleton_);
    return;
  }
  fail(input_.empty() ? std::string(kDefaultDatasetName) : input_, ": no part holds any cells");
}

StreamedStep::~StreamedStep() = default;

uint64_t StreamedStep::partsFromDisk() const { return cache_->hits(); }

uint64_t StreamedStep::gradientsFromDisk() const { return cache_->gradientHits(); }

uint64_t StreamedStep::residentBytes() const {
  uint64_t n = 0;
  for (const Resident& r : resident_)
    n += r.bytes;
  return n;
}

StreamedStep::Resident& StreamedStep::bring(int part) {
  for (auto it = resident_.begin(); it != resident_.end(); ++it)
    if (it->part == part) {
      resident_.splice(resident_.begin(), resident_, it);
      return resident_.front();
    }
  const uint64_t need = plan_.partBytes(part);
  bool dropped = false;
  while (!resident_.empty() && plan_.fixedBytes + residentBytes() + need > plan_.budget) {
    resident_.pop_back();
    dropped = true;
  }
  if (dropped) malloc_trim(0); // give the freed part back before the next is read
  checkUnchanged();
  Resident r;
  r.part = part;
  r.bytes = need;
  std::optional<Model> m = cache_->read(part);
  if (!m) {
    m = loadModelPart(input_, options_, partBox(part), plan_.coarsestLevel, plan_.partCells.at(size_t(part)));
    if (m && parts() > 1) cache_->write(part, *m);
  }
  if (m) r.model = std::make_unique<Model>(std::move(*m));
  gather(part, r.model.get());
  ++reads_;
  resident_.push_front(std::move(r));
  return resident_.front();
}

void StreamedStep::checkUnchanged() const {
  const auto now = snapshotOf(input_);
  if (now == snapshot_->files) return;
  std::string what = "files were added or removed";
  for (size_t i = 0; i < std::min(now.size(), snapshot_->files.size()); ++i)
    if (now[i] != snapshot_->files[i]) {
      what = std::get<0>(now[i]) == std::get<0>(snapshot_->files[i])
                 ? strCat(std::get<0>(now[i]), " changed (", std::get<1>(snapshot_->files[i]), " bytes, now ",
                          std::get<1>(now[i]), ")")
                 : "files were added or removed";
      break;
    }
  fail(input_, ": changed while its parts were being read (", what,
       "): a step that a running simulation is still writing? Read it once it is complete");
}

const Model* StreamedStep::part(int part) { return bring(part).model.get(); }

bool StreamedStep::needsSurvey(const Scene& scene) const {
  // A layer without a range of its own maps the data's.
  return !outline_ || std::any_of(scene.layers.begin(), scene.layers.end(),
                                  [](const VolumeLayer& l) { return l.tf.valueRange.empty(); });
}

std::optional<StepSurvey> StreamedStep::outlineOf(const MemoryPlan& plan, const LoadOptions& options,
                                                  const Model& skeleton) {
  // Cells that turn into holes as they are read, and levels finer than those read, are still in
  // the census.
  if (plan.levelCells.empty() || plan.cellBounds.empty() || options.nonFinite != NonFinite::Refuse ||
      options.finestLevel != 0)
    return {};
  StepSurvey s;
  int finest = -1;
  s.levelCells.assign(kMaxLevel + 1, 0);
  for (int l = 0; l <= kMaxLevel && l < int(plan.levelCells.size()); ++l) {
    s.levelCells[size_t(l)] = uint64_t(std::llround(plan.levelCells[size_t(l)]));
    if (s.levelCells[size_t(l)] == 0) continue;
    s.levels.push_back(l);
    s.cells += s.levelCells[size_t(l)];
    if (finest < 0) finest = l;
  }
  if (finest < 0) return {};
  s.cellBounds = box3i(vec3i(plan.cellBounds.lower), vec3i(plan.cellBounds.upper));
  s.dataset = DatasetInfo::from(finest, s.cellBounds, skeleton.world.scale,
                                std::vector<range1f>(skeleton.fieldNames.size(), range1f()));
  return s;
}

void StreamedStep::gather(int part, const Model* m) {
  if (survey_ || gathered_.at(size_t(part))) return;
  gathered_[size_t(part)] = true;
  Gathering& g = gathering_;
  if (m) {
    g.levelCells.resize(kMaxLevel + 1, 0);
    for (const Brick& b : m->bricks) {
      g.finest = std::min(g.finest, b.level);
      g.levelCells[size_t(b.level)] += cellsCentredIn(b, partBox(part));
    }
    g.cellBounds.extend(m->cellBounds());
    g.bricks += m->bricks.size();
    g.regions += m->regions.regions.size();
    g.ranges.resize(std::max(g.ranges.size(), m->regions.valueRanges.size()));
    for (size_t f = 0; f < m->regions.valueRanges.size(); ++f)
      for (const range1f& r : m->regions.valueRanges[f])
        g.ranges[f].extend(r);
  }
  finishSurvey();
}

void StreamedStep::finishSurvey() {
  if (survey_ || std::find(gathered_.begin(), gathered_.end(), false) != gathered_.end() ||
      skeleton_.fieldNames.empty())
    return;
  Gathering& g = gathering_;
  StepSurvey s;
  s.levelCells = g.levelCells;
  s.levelCells.resize(kMaxLevel + 1, 0);
  for (int l = 0; l <= kMaxLevel; ++l)
    if (s.levelCells[size_t(l)] > 0) s.levels.push_back(l);
  for (uint64_t n : s.levelCells)
    s.cells += n;
  s.cellBounds = g.cellBounds;
  s.bricks = g.bricks;
  s.regions = g.regions;
  g.ranges.resize(skeleton_.fieldNames.size());
  s.dataset = DatasetInfo::from(g.finest, s.cellBounds, skeleton_.world.scale, std::move(g.ranges));
  survey_ = std::move(s);
  gathering_ = Gathering();
}

Renderer* StreamedStep::renderer(int part, const Scene& scene, const RendererOptions& options) {
  // The step's survey may read every part: before this one is brought. A scene that gives every
  // layer its range needs only the step's outline, which the census knows.
  const bool ranges = needsSurvey(scene);
  const bool outlined = !ranges && !survey_;
  const DatasetInfo& dataset = outlined ? outline_->dataset : survey().dataset;
  Resident& r = bring(part);
  if (!r.model) return nullptr;
  if (r.renderer && ranges && r.outlined) r.renderer.reset(); // built without the ranges it now needs
  if (!r.renderer) {
    r.outlined = outlined;
    r.renderer = std::make_unique<Renderer>(*r.model, dataset);
    r.renderer->setDomain(partWorldBox(part));
    r.renderer->setParticles(particles_);
    for (int f = 0; f < int(r.model->fieldNames.size()); ++f)
      if (auto g = cache_->readGradients(part, f, r.model->fieldValues[size_t(f)].size(), r.model->bricks.size()))
        r.renderer->adoptGradients(f, std::move(*g));
  }
  r.renderer->setOptions(options);
  r.renderer->setScene(scene);
  // Smooth shading's gradients, built once per brick, part and field: kept with the part on disk.
  for (int f = 0; f < int(r.model->fieldNames.size()); ++f)
    if (const GradientFields* g = r.renderer->gradients(f); g && cache_->on() && cache_->buildsMore(part, f, *g))
      cache_->writeGradients(part, f, *g);
  return r.renderer.get();
}

std::vector<int> StreamedStep::residentFirst() const {
  std::vector<int> order;
  for (const Resident& r : resident_)
    order.push_back(r.part);
  for (int p = 0; p < parts(); ++p)
    if (std::find(order.begin(), order.end(), p) == order.end()) order.push_back(p);
  return order;
}

void StreamedStep::forEachPart(const std::function<void(const Model&, const box3l&)>& visit) {
  for (int p : residentFirst())
    if (const Model* m = part(p)) visit(*m, partBox(p));
}

const StepSurvey& StreamedStep::survey() {
  // Parts read before (for a frame, or resident) were gathered as they came.
  for (int p : residentFirst())
    if (!survey_ && !gathered_[size_t(p)]) bring(p);
  finishSurvey(); // where every part was read before the skeleton's fields were known
  return *survey_;
}

PartialData StreamedStep::partialData() {
  PartialData d;
  d.bounds = outline_ ? outline_->cellBounds : survey().cellBounds;
  d.eachPart = [this](const std::function<void(const Model&, const box3l&)>& visit) { forEachPart(visit); };
  return d;
}

std::vector<int> StreamedStep::order(const Camera& camera) const {
  if (camera.orthographic) return plan_.partition.orderAlong((camera.lookAt - camera.position) / skeleton_.world.scale);
  return plan_.partition.orderFrom(skeleton_.world.toLattice(camera.position));
}

box3d StreamedStep::visibleBounds(const Scene& scene, const RendererOptions& options) {
  VisibleExtent all;
  const Scene framing = framingScene(scene); // no gradients: the frame's own set-up adds them
  for (int p : residentFirst())
    if (const Renderer* r = renderer(p, framing, options)) all.extend(r->visibleExtent().within(partBox(p)));
  const box3f framed = all.framed();
  return framed.empty() ? box3d() : skeleton_.world.toWorld(framed);
}

void StreamedStep::sample(int field, const std::vector<vec3d>& points, std::vector<double>& values,
                          std::vector<vec3d>& gradients, std::vector<bool>& found) {
  values.assign(points.size(), 0.0);
  gradients.assign(points.size(), vec3d(0.0));
  found.assign(points.size(), false);
  std::vector<std::vector<size_t>> ofPart(static_cast<size_t>(this->parts()));
  for (size_t i = 0; i < points.size(); ++i)
    if (const int p = plan_.partition.partAt(skeleton_.world.toLattice(points[i])); p >= 0)
      ofPart[size_t(p)].push_back(i);
  for (int p = 0; p < parts(); ++p) {
    if (ofPart[size_t(p)].empty()) continue;
    const Model* m = part(p);
    if (!m) continue;
    for (size_t i : ofPart[size_t(p)])
      found[i] = m->sampleWorld(field, points[i], values[i], gradients[i]);
  }
}

std::string StreamedStep::infoJson(const std::string& name, double seconds) {
  const StepSurvey& s = survey();
  nlohmann::json j =
      nlohmann::json::parse(datasetInfoJson(skeleton_, name, s.cells, s.cellBounds, s.dataset.valueRanges));
  nlohmann::json levels = nlohmann::json::array();
  for (auto l = s.levels.begin(); l != s.levels.end(); ++l)
    levels.push_back({{"level", *l}, {"cell_width", 1 << *l}, {"cells", s.levelCells[size_t(*l)]}});
  j["levels"] = levels;
  j["memory"] = {{"budget_bytes", plan_.budget},
                 {"parts", parts()},
                 {"largest_part_bytes", plan_.largestPartBytes()},
                 {"fixed_bytes", plan_.fixedBytes},
                 {"parts_read", reads_},
                 {"resident_parts", residentParts()},
                 {"bricks_over_parts", s.bricks},
                 {"regions_over_parts", s.regions},
                 {"peak_rss_bytes", peakResidentBytes()}};
  j["build_seconds"] = {{"load_total", seconds}};
  return j.dump(2);
}

bool renderStreamed(StreamedStep& step, const Scene& sceneIn, const RendererOptions& options, const Frame& frame,
                    FrameBuffer& buffer, const PassControl& control,
                    const std::function<void(const FrameBuffer&, int passes)>& afterRound) {
  Scene scene = sceneIn;
  resolveParticleRadius(scene, frame);
  if (scene.integration.integrator == Integrator::PathTrace)
    fail("a step drawn in parts is ray-marched: path tracing scatters light between the parts and needs the whole "
         "step (a larger --memory-budget)");
  // Rays continue from the opacity in front (the march); debug views composite part over part.
  const bool continued = scene.debug == DebugView::None;
  const size_t pixels = size_t(frame.width) * size_t(frame.height);
  const int round = passesPerRound(pixels, frame.samplesPerPixel);
  buffer.resize(frame.width, frame.height);
  FrameBuffer pass(frame.width, frame.height);
  std::vector<float> local(pixels * kCompositeChannels), composites(size_t(round) * pixels * kCompositeChannels),
      front(size_t(round) * pixels);
  std::vector<int> order = step.order(frame.camera);
  RenderStats stats;
  bool complete = true;
  Frame f = frame;
  for (int first = 0, count = 0; first < frame.samplesPerPixel && complete; first += count) {
    count = std::min(afterRound && first == 0 ? 1 : round, frame.samplesPerPixel - first);
    if (first > 0 && afterRound) afterRound(buffer, first);
    std::fill(composites.begin(), composites.end(), 0.f);
    std::fill(front.begin(), front.end(), 0.f);
    // Resident parts are taken where they come in the order; the others are read in it.
    for (int p : order) {
      const Renderer* r = step.renderer(p, scene, options);
      if (!r) continue;
      for (int k = 0; k < count && complete; ++k) {
        f.frameIndex = first + k; // as Renderer::renderPasses numbers the passes
        // The rays continue from the opacity the parts in front gathered: the part adds its
        // light dimmed by them and returns the total opacity.
        float* alpha = front.data() + size_t(k) * pixels;
        f.frontOpacity = continued ? alpha : nullptr;
        pass.clear();
        complete = r->renderPass(f, pass, control);
        const FrameBuffer::Sums s = pass.sums();
        stats += *s.stats;
        packForCompositing(s, pixels, local.data());
        float* acc = composites.data() + size_t(k) * pixels * kCompositeChannels;
        for (size_t px = 0; px < pixels; ++px) {
          const float* c = local.data() + px * kCompositeChannels;
          float* a = acc + px * kCompositeChannels;
          const float t = continued ? 1.f : 1.f - a[3]; // debug views: the part over what is behind
          a[0] += t * c[0], a[1] += t * c[1], a[2] += t * c[2], a[4] += c[4];
          a[3] = alpha[px] = continued ? std::clamp(c[3], 0.f, 1.f) : a[3] + t * c[3];
        }
      }
    }
    for (int k = 0; k < count && complete; ++k)
      addComposited(composites.data() + size_t(k) * pixels * kCompositeChannels, pixels, buffer);
  }
  *buffer.sums().stats = stats;
  *buffer.sums().stepsView = *pass.sums().stepsView;
  return complete;
}

} // namespace exa
