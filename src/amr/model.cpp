#include "exabricks/amr/model.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <algorithm>
#include <cmath>

namespace exa {

ValueArray::ValueArray(std::vector<float>&& values) {
  auto owned = std::make_shared<const std::vector<float>>(std::move(values));
  data_ = owned->data();
  size_ = owned->size();
  keep_ = std::move(owned);
}

bool operator==(const ValueArray& a, const ValueArray& b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin());
}

uint64_t Model::cellCount() const {
  uint64_t n = 0;
  for (const Brick& b : bricks)
    n += b.cellCount();
  return n;
}

int Model::fieldIndex(const std::string& name) const {
  for (size_t i = 0; i < fieldNames.size(); ++i)
    if (fieldNames[i] == name) return int(i);
  return -1;
}

std::string Model::unitsOf(int field) const {
  return field >= 0 && size_t(field) < fieldUnits.size() ? fieldUnits[size_t(field)] : std::string();
}

int Model::requireField(const std::string& name) const {
  if (fieldNames.empty()) fail("the data has no fields");
  if (name.empty()) {
    // The principal field where the data names one: the native default, then the density of
    // Enzo, FLASH and most codes; otherwise the first in file order.
    for (const char* principal : {"scalar", "Density", "density", "dens", "rho"})
      if (const int i = fieldIndex(principal); i >= 0) return i;
    return 0;
  }
  const int i = fieldIndex(name);
  if (i < 0) {
    std::string known;
    for (const std::string& n : fieldNames)
      known += (known.empty() ? "" : ", ") + n;
    fail("unknown field '", name, "' (fields: ", known, ")");
  }
  return i;
}

FieldView Model::view(int field) const {
  FieldView v;
  v.bricks = bricks.data();
  v.values = fieldValues.at(size_t(field)).data();
  v.regions = regions.regions.data();
  v.brickIds = regions.brickIds.data();
  v.nodes = regions.nodes.empty() ? nullptr : regions.nodes.data();
  v.bounds = regions.bounds;
  return v;
}

box3i Model::cellBounds() const {
  box3i b;
  for (const Brick& br : bricks)
    b.extend(br.bounds());
  return b;
}

ModelSummary summarize(const Model& m) {
  ModelSummary s;
  s.bricks = m.bricks.size();
  s.regions = m.regions.regions.size();
  std::vector<ModelSummary::Level> levels(kMaxLevel + 1);
  for (const Brick& b : m.bricks) {
    levels[size_t(b.level)].cells += b.cellCount();
    levels[size_t(b.level)].bricks += 1;
    s.cells += b.cellCount();
    s.singleCellBricks += b.cellCount() == 1;
  }
  for (int l = 0; l <= kMaxLevel; ++l)
    if (levels[size_t(l)].cells > 0) {
      levels[size_t(l)].level = l;
      s.levels.push_back(levels[size_t(l)]);
    }
  double volume = 0, weighted = 0;
  for (const Region& r : m.regions.regions) {
    const vec3d size = vec3d(r.halfBounds.size()) * 0.5;
    const double v = size.x * size.y * size.z;
    volume += v;
    weighted += v * r.brickCount;
    s.maxBricksPerRegion = std::max<uint64_t>(s.maxBricksPerRegion, r.brickCount);
  }
  if (s.regions > 0) {
    s.bricksPerRegionByCount = double(m.regions.brickIds.size()) / double(s.regions);
    s.bricksPerRegionByVolume = weighted / volume;
  }
  for (const auto& values : m.fieldValues) {
    range1f r;
    for (float v : values)
      r.extend(v);
    s.fieldRanges.push_back(r);
  }
  s.brickBytes = m.bricks.size() * sizeof(Brick);
  for (const auto& values : m.fieldValues)
    s.valueBytes += values.size() * sizeof(float);
  s.regionBytes = m.regions.memoryBytes();
  return s;
}

void buildRegionsOf(Model& model, const RegionBuildOptions& options) {
  Timer timer;
  model.regions = buildRegions(model.bricks, options);
  model.stats.regionSeconds = timer.seconds();
  timer.reset();
  model.regions.valueRanges.clear();
  for (const auto& values : model.fieldValues)
    model.regions.valueRanges.push_back(computeValueRanges(model.regions, model.bricks, values.data()));
  model.stats.rangeSeconds = timer.seconds();
}

namespace {

/// The regions of a model whose bricks and values are set, timed and logged.
void finishBuild(Model& model, const BuildOptions& options, Progress& progress) {
  logInfo(strCat("built ", model.bricks.size(), " bricks in ", model.stats.brickSeconds, " s"));
  progress.advance(1);
  buildRegionsOf(model, options.regions);
  progress.finish();
  logInfo(strCat("built ", model.regions.regions.size(), " regions in ",
                 model.stats.regionSeconds + model.stats.rangeSeconds, " s"));
}

Model buildWith(CellSet&& cells, const BuildOptions& options, ModelStructure* keep) {
  Model model;
  model.world = cells.world;
  model.simulation = cells.simulation;
  Timer timer;
  Progress progress("building bricks and regions", 3);
  if (keep) {
    // A kept structure needs the cells in input order and their slots for the next values.
    BrickBuild bricks = buildBricks(cells.cells, options.bricks);
    progress.advance(1);
    keep->cells = std::move(cells.cells);
    keep->world = cells.world;
    keep->bricks = options.bricks;
    model.bricks = std::move(bricks.bricks);
    for (Field& f : cells.fields) {
      model.fieldNames.push_back(f.name);
      model.fieldUnits.push_back(f.units);
      model.fieldValues.push_back(toBrickOrder(f.values, bricks.cellOfSlot));
      std::vector<float>().swap(f.values);
    }
    keep->cellOfSlot = std::move(bricks.cellOfSlot);
  } else {
    // Otherwise the cells and values are permuted in place: no memory beyond them.
    std::vector<std::vector<float>*> values;
    for (Field& f : cells.fields)
      values.push_back(&f.values);
    model.bricks = buildBricksReordering(cells.cells, values, options.bricks);
    progress.advance(1);
    std::vector<Cell>().swap(cells.cells);
    for (Field& f : cells.fields) {
      model.fieldNames.push_back(f.name);
      model.fieldUnits.push_back(f.units);
      model.fieldValues.push_back(std::move(f.values));
    }
  }
  model.stats.brickSeconds = timer.seconds();
  finishBuild(model, options, progress);
  return model;
}

} // namespace

Model buildModel(CellSet&& cells, const BuildOptions& options) { return buildWith(std::move(cells), options, nullptr); }

Model buildModelValuesAfter(CellSet&& cells, const std::function<std::vector<float>(size_t field)>& valuesOf,
                            const BuildOptions& options) {
  Model model;
  model.world = cells.world;
  model.simulation = cells.simulation;
  Timer timer;
  // Stages weighted by their usual share of the time: the bricks 8, each field's values 1, the
  // value ranges and regions 2.
  Progress progress("building bricks, placing values, building regions", 10 + cells.fields.size());
  BrickBuild bricks = buildBricksInPlace(cells.cells, options.bricks);
  std::vector<Cell>().swap(cells.cells);
  model.bricks = std::move(bricks.bricks);
  progress.advance(8);
  for (size_t f = 0; f < cells.fields.size(); ++f) {
    model.fieldNames.push_back(cells.fields[f].name);
    model.fieldUnits.push_back(cells.fields[f].units);
    const std::vector<float> values = valuesOf(f);
    if (values.size() != bricks.cellOfSlot.size())
      fail("field '", cells.fields[f].name, "' has ", values.size(), " values for ", bricks.cellOfSlot.size(),
           " cells");
    model.fieldValues.push_back(toBrickOrder(values, bricks.cellOfSlot));
    progress.advance(1);
  }
  model.stats.brickSeconds = timer.seconds();
  std::vector<uint32_t>().swap(bricks.cellOfSlot);
  finishBuild(model, options, progress);
  return model;
}

Model buildModel(CellSet&& cells, const BuildOptions& options, ModelStructure& structure) {
  return buildWith(std::move(cells), options, &structure);
}

bool ModelStructure::matches(const CellSet& other, const BuildOptions& options) const {
  return other.world == world && options.bricks.maxBrickWidth == bricks.maxBrickWidth &&
         other.cells.size() == cells.size() && std::equal(other.cells.begin(), other.cells.end(), cells.begin());
}

Model rebuildValues(const Model& like, const ModelStructure& structure, CellSet&& cells) {
  if (!structure.matches(cells, BuildOptions{structure.bricks}))
    fail("rebuilding values: the cells differ from the structure's (another hierarchy)");
  Timer timer;
  Model model;
  model.world = cells.world;
  model.simulation = cells.simulation;
  model.bricks = like.bricks;
  for (Field& f : cells.fields) {
    model.fieldNames.push_back(f.name);
    model.fieldUnits.push_back(f.units);
    model.fieldValues.push_back(toBrickOrder(f.values, structure.cellOfSlot));
    std::vector<float>().swap(f.values);
  }
  model.stats.brickSeconds = timer.seconds();
  timer.reset();
  RegionSet& regions = model.regions;
  regions = like.regions;
  regions.valueRanges.clear();
  model.stats.regionSeconds = timer.seconds();
  timer.reset();
  for (const auto& values : model.fieldValues)
    regions.valueRanges.push_back(computeValueRanges(regions, model.bricks, values.data()));
  model.stats.rangeSeconds = timer.seconds();
  return model;
}

bool Model::sampleWorld(int field, const vec3d& position, double& value, vec3d& gradient) const {
  const vec3d p = world.toLattice(position);
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  vec3d g;
  if (!sampleField(view(field), p, value, &g)) return false;
  gradient = g / world.scale; // per world unit
  return true;
}

} // namespace exa
