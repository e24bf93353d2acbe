// Build and sampling throughput on the generator's scenes. Not a test: run by hand, e.g.
//   build-bench/bench/exabricks_bench_core --benchmark_counters_tabular=true
#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"

#include <benchmark/benchmark.h>

#include <map>
#include <random>

using namespace exa;

namespace {

const CellSet& scene(const std::string& name, uint64_t cells) {
  static std::map<std::pair<std::string, uint64_t>, CellSet> cache;
  auto& s = cache[{name, cells}];
  if (s.cells.empty()) s = generateScene({name, cells, 1, 4});
  return s;
}

const Model& model(const std::string& name, uint64_t cells) {
  static std::map<std::pair<std::string, uint64_t>, Model> cache;
  auto it = cache.find({name, cells});
  if (it == cache.end()) {
    CellSet copy = scene(name, cells);
    it = cache.emplace(std::make_pair(name, cells), buildModel(std::move(copy))).first;
  }
  return it->second;
}

void BM_BuildBricks(benchmark::State& state, const std::string& name) {
  const CellSet& s = scene(name, uint64_t(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(buildBricks(s.cells).bricks.size());
  state.counters["cells"] = double(s.size());
  state.counters["cells/s"] = benchmark::Counter(double(s.size()), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_BuildRegions(benchmark::State& state, const std::string& name) {
  const Model& m = model(name, uint64_t(state.range(0)));
  for (auto _ : state) {
    const RegionSet r = buildRegions(m.bricks);
    benchmark::DoNotOptimize(computeValueRanges(r, m.bricks, m.fieldValues[0].data()).size());
  }
  const ModelSummary sum = summarize(m);
  state.counters["cells/s"] = benchmark::Counter(double(sum.cells), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["regions"] = double(sum.regions);
  state.counters["bytes/cell"] = double(sum.brickBytes + sum.regionBytes) / double(sum.cells);
}

void BM_BuildModel(benchmark::State& state, const std::string& name) {
  const CellSet& s = scene(name, uint64_t(state.range(0)));
  for (auto _ : state) {
    state.PauseTiming();
    CellSet copy = s;
    state.ResumeTiming();
    benchmark::DoNotOptimize(buildModel(std::move(copy)).bricks.size());
  }
  state.counters["cells/s"] = benchmark::Counter(double(s.size()), benchmark::Counter::kIsIterationInvariantRate);
}

/// Random points inside the data's bounds (incoherent), or points along random rays with
/// a step of half a finest cell (coherent, like ray marching).
template <typename Real> void BM_Sample(benchmark::State& state, bool coherent, bool gradient) {
  const Model& m = model("blobs", uint64_t(state.range(0)));
  const FieldView view = m.view(0);
  const box3f b = m.regions.bounds;
  std::mt19937 rng(1);
  std::vector<vec3<Real>> points(1 << 20);
  std::uniform_real_distribution<Real> u(0, 1);
  for (size_t i = 0; i < points.size();) {
    const vec3<Real> p0(b.lower.x + u(rng) * (b.upper.x - b.lower.x), b.lower.y + u(rng) * (b.upper.y - b.lower.y),
                        b.lower.z + u(rng) * (b.upper.z - b.lower.z));
    if (!coherent) {
      points[i++] = p0;
      continue;
    }
    const vec3<Real> dir = normalize(vec3<Real>(u(rng) - Real(0.5), u(rng) - Real(0.5), u(rng) - Real(0.5)));
    for (int k = 0; k < 256 && i < points.size(); ++k)
      points[i++] = p0 + dir * (Real(0.5) * Real(k));
  }
  size_t valid = 0;
  for (auto _ : state) {
    for (const auto& p : points) {
      Real v;
      vec3<Real> g;
      valid += sampleField(view, p, v, gradient ? &g : nullptr);
    }
  }
  benchmark::DoNotOptimize(valid);
  state.counters["samples/s"] =
      benchmark::Counter(double(points.size()), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_SampleFloat(benchmark::State& state, bool coherent, bool gradient) {
  BM_Sample<float>(state, coherent, gradient);
}
void BM_SampleDouble(benchmark::State& state, bool coherent, bool gradient) {
  BM_Sample<double>(state, coherent, gradient);
}

} // namespace

BENCHMARK_CAPTURE(BM_BuildBricks, blobs, "blobs")
    ->Arg(1000000)
    ->Arg(10000000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_BuildBricks, shells, "shells")
    ->Arg(1000000)
    ->Arg(10000000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_BuildRegions, blobs, "blobs")
    ->Arg(1000000)
    ->Arg(10000000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_BuildRegions, shells, "shells")
    ->Arg(1000000)
    ->Arg(10000000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_BuildModel, blobs, "blobs")
    ->Arg(10000000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);
BENCHMARK_CAPTURE(BM_SampleFloat, random_value, false, false)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SampleFloat, random_gradient, false, true)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SampleFloat, coherent_value, true, false)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SampleFloat, coherent_gradient, true, true)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SampleDouble, coherent_gradient, true, true)->Arg(1000000)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
