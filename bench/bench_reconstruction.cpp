// Per-sample cost of the two reconstructions the renderer offers, on the same points: the
// bricks listed by the sample's active brick region (the method) against locating every
// contributing cell by a top-down search of a k-d tree over the bricks (the paper's Table 2
// baseline). Single thread, value and analytic gradient. Not a test: run by hand, e.g.
//   build-bench/bench/exabricks_bench_reconstruction --benchmark_counters_tabular=true
#include "exabricks/amr/cell_locator.h"
#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"

#include <benchmark/benchmark.h>

#include <map>
#include <random>

using namespace exa;

namespace {

const Model& model(const std::string& name, uint64_t cells) {
  static std::map<std::pair<std::string, uint64_t>, Model> cache;
  auto it = cache.find({name, cells});
  if (it == cache.end())
    it = cache.emplace(std::make_pair(name, cells), buildModel(generateScene({name, cells, 1, 4}))).first;
  return it->second;
}

const CellLocator& locator(const std::string& name, uint64_t cells) {
  static std::map<std::pair<std::string, uint64_t>, std::unique_ptr<CellLocator>> cache;
  auto& l = cache[{name, cells}];
  if (!l) l = std::make_unique<CellLocator>(model(name, cells));
  return *l;
}

/// Points along random rays through the bounds, half a finest cell apart (as a ray marcher
/// places them), or random points in the bounds.
std::vector<vec3f> points(const Model& m, bool coherent) {
  const box3f b = m.regions.bounds;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<vec3f> out(1 << 18);
  for (size_t i = 0; i < out.size();) {
    const vec3f p0(b.lower.x + u(rng) * (b.upper.x - b.lower.x), b.lower.y + u(rng) * (b.upper.y - b.lower.y),
                   b.lower.z + u(rng) * (b.upper.z - b.lower.z));
    if (!coherent) {
      out[i++] = p0;
      continue;
    }
    const vec3f dir = normalize(vec3f(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f));
    for (int k = 0; k < 256 && i < out.size(); ++k)
      out[i++] = p0 + dir * (0.5f * float(k));
  }
  return out;
}

void BM_Reconstruct(benchmark::State& state, const std::string& scene, bool cells, bool coherent) {
  const uint64_t count = uint64_t(state.range(0));
  const Model& m = model(scene, count);
  const FieldView view = m.view(0);
  const CellLocator* loc = cells ? &locator(scene, count) : nullptr;
  const std::vector<vec3f> ps = points(m, coherent);
  size_t valid = 0;
  for (auto _ : state) {
    for (const vec3f& p : ps) {
      float v;
      vec3f g;
      valid += cells ? loc->sample(0, p, v, &g) : sampleField(view, p, v, &g);
    }
  }
  benchmark::DoNotOptimize(valid);
  state.counters["samples/s"] = benchmark::Counter(double(ps.size()), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["ns/sample"] = benchmark::Counter(double(ps.size()), benchmark::Counter::kIsIterationInvariantRate |
                                                                          benchmark::Counter::kInvert);
}

void BM_BuildCellLocator(benchmark::State& state, const std::string& scene) {
  const Model& m = model(scene, uint64_t(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(CellLocator(m).nodeCount());
  state.counters["bricks"] = double(m.bricks.size());
}

} // namespace

BENCHMARK_CAPTURE(BM_BuildCellLocator, blobs, "blobs")->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Reconstruct, blobs_regions_coherent, "blobs", false, true)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Reconstruct, blobs_cells_coherent, "blobs", true, true)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Reconstruct, blobs_regions_random, "blobs", false, false)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Reconstruct, blobs_cells_random, "blobs", true, false)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Reconstruct, shells_regions_coherent, "shells", false, true)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Reconstruct, shells_cells_coherent, "shells", true, true)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
