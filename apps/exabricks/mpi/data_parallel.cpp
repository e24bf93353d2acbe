#include "data_parallel.h"

#include "processes.h"

#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <algorithm>
#include <limits>

namespace exa::mpi {

box3d DataPart::worldBox() const { return model.world.toWorld(box); }

uint64_t DataPart::ownedCells() const {
  uint64_t n = 0;
  for (const Brick& b : model.bricks)
    forCellsCentredIn(b, box, [&](uint32_t) { ++n; });
  return n;
}

std::vector<int> DataPart::order(const Camera& camera) const {
  if (camera.orthographic) return partition.orderAlong((camera.lookAt - camera.position) / model.world.scale);
  return partition.orderFrom(model.world.toLattice(camera.position));
}

DataPart loadDataPart(const std::string& input, const LoadOptions& options) {
  const Processes& procs = processes();
  DataPart part;
  // The census and the partition: on the first process, sent to all.
  std::vector<int64_t> encoded;
  std::string error;
  if (procs.root()) {
    try {
      Timer t;
      const Census census = loadCensus(input, options);
      part.partition = KdPartition::balance(census, procs.size);
      encoded = part.partition.encode();
      encoded.push_back(census.coarsestLevel);
      logInfo(strCat("split ", census.cells(), " cells into ", procs.size, " parts in ", t.seconds(), " s"));
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  agreeOrFail(error, "read the input");
  broadcast(encoded);
  part.coarsestLevel = int(encoded.back());
  encoded.pop_back();
  part.partition = KdPartition::decode(encoded);
  part.box = part.partition.box(procs.rank);

  std::optional<Model> loaded;
  try {
    loaded = loadModelPart(input, options, part.box, part.coarsestLevel);
    if (!loaded)
      error = strCat("process ", procs.rank, ": its part of ", input.empty() ? kDefaultDatasetName : input,
                     " holds no cells (more processes than the data can be split into; use fewer)");
  } catch (const std::exception& e) {
    error = e.what();
  }
  agreeOrFail(error, "read its part of the input");
  part.model = std::move(*loaded);
  const Model& m = part.model;

  // The whole dataset's values: finest level, cell bounds, value ranges and levels agreed.
  const DatasetInfo local = DatasetInfo::of(m);
  const box3i cb = m.cellBounds();
  const size_t fields = local.valueRanges.size();
  std::vector<double> low{std::log2(double(local.referenceWidth)), double(cb.lower.x), double(cb.lower.y),
                          double(cb.lower.z)};
  std::vector<double> high{double(cb.upper.x), double(cb.upper.y), double(cb.upper.z)};
  for (const range1f& r : local.valueRanges) {
    low.push_back(r.empty() ? std::numeric_limits<double>::infinity() : double(r.lower));
    high.push_back(r.empty() ? -std::numeric_limits<double>::infinity() : double(r.upper));
  }
  std::vector<bool> levelHere(kMaxLevel + 1, false);
  for (const Brick& b : m.bricks)
    levelHere[size_t(b.level)] = true;
  for (int l = 0; l <= kMaxLevel; ++l)
    high.push_back(levelHere[size_t(l)] ? 1.0 : 0.0);
  std::vector<double> counts{double(fields)};
  allReduce(counts, Reduce::Max);
  if (counts[0] != double(fields)) fail("the processes' parts hold different fields");
  allReduce(low, Reduce::Min);
  allReduce(high, Reduce::Max);
  part.whole.cellBounds =
      box3i(vec3i(int(low[1]), int(low[2]), int(low[3])), vec3i(int(high[0]), int(high[1]), int(high[2])));
  std::vector<range1f> ranges(fields);
  for (size_t f = 0; f < fields; ++f)
    if (low[4 + f] <= high[3 + f]) ranges[f] = range1f{float(low[4 + f]), float(high[3 + f])};
  part.dataset = DatasetInfo::from(int(low[0]), part.whole.cellBounds, m.world.scale, std::move(ranges));
  for (int l = 0; l <= kMaxLevel; ++l)
    if (high[3 + fields + size_t(l)] > 0.0) part.whole.levels.push_back(l);
  part.whole.histogram.owned = part.box;
  part.whole.histogram.bounds = part.whole.cellBounds;
  part.whole.histogram.sumOverParts = [](std::vector<double>& h) { allReduce(h, Reduce::Sum); };
  return part;
}

box3d agreedVisibleBounds(const Renderer& renderer, const DataPart& part) {
  // The three boxes of each process's extent within its part, united over the processes.
  const VisibleExtent mine = renderer.visibleExtent().within(part.box);
  std::vector<double> low, high;
  for (const box3f* b : {&mine.volume, &mine.opaque, &mine.iso})
    for (int a = 0; a < 3; ++a) {
      low.push_back(b->empty() ? std::numeric_limits<double>::infinity() : double(b->lower[a]));
      high.push_back(b->empty() ? -std::numeric_limits<double>::infinity() : double(b->upper[a]));
    }
  allReduce(low, Reduce::Min);
  allReduce(high, Reduce::Max);
  VisibleExtent all;
  box3f* boxes[] = {&all.volume, &all.opaque, &all.iso};
  for (size_t k = 0; k < 3; ++k)
    if (low[3 * k] <= high[3 * k] && low[3 * k + 1] <= high[3 * k + 1] && low[3 * k + 2] <= high[3 * k + 2])
      *boxes[k] = box3f(vec3f(float(low[3 * k]), float(low[3 * k + 1]), float(low[3 * k + 2])),
                        vec3f(float(high[3 * k]), float(high[3 * k + 1]), float(high[3 * k + 2])));
  const box3f framed = all.framed();
  return framed.empty() ? box3d() : part.model.world.toWorld(framed);
}

} // namespace exa::mpi
