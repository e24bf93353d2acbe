// exabricks bench: renderer variants measured in one run on one dataset (frame times, samples,
// regions, the ratios between variants and the image differences), build times and memory;
// with --orbit, the orbit study: frame time against samples and regions over many viewpoints;
// with --progressive, the progressive passes after a transfer-function change; with --device,
// the same frames on several devices; with --memory-budget, a step held in parts
// (bench_memory.cpp). Here: the options, the dataset and what the studies share.
#include "bench.h"
#include "commands.h"
#include "common.h"

#include "exabricks/core/log.h"
#include "exabricks/workflows/streamed.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>

namespace exa::cli {
namespace bench {

int tbbThreads() { return tbb::this_task_arena::max_concurrency(); }

double loadAverage() {
  std::ifstream in("/proc/loadavg");
  double l = -1;
  if (!(in >> l)) return -1;
  return l;
}

ImageDiff difference(const Image& a, const Image& b) {
  ImageDiff d;
  double sum = 0, sumAbs = 0;
  size_t within = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const vec4f& p = a.pixels[i];
    const vec4f& q = b.pixels[i];
    for (const double e : {double(p.x) - q.x, double(p.y) - q.y, double(p.z) - q.z, double(p.w) - q.w}) {
      sum += e * e;
      sumAbs += std::abs(e);
      within += std::abs(e) * 255.0 <= 2.0 ? 1 : 0;
      d.maxAbs = std::max(d.maxAbs, std::abs(e));
    }
  }
  const double n = 4.0 * double(a.pixels.size());
  d.rmse = a.pixels.empty() ? 0.0 : std::sqrt(sum / n);
  d.meanAbs = a.pixels.empty() ? 0.0 : sumAbs / n;
  d.shareWithin = a.pixels.empty() ? 1.0 : double(within) / n;
  return d;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

nlohmann::json describe(const Setup& s, const BenchOptions& o) {
  const ModelSummary sum = summarize(s.model);
  nlohmann::json j;
  j["dataset"] = o.in.name();
  j["field"] = s.model.fieldNames[size_t(s.field)];
  j["cells"] = sum.cells;
  j["bricks"] = sum.bricks;
  j["regions"] = sum.regions;
  nlohmann::json levels = nlohmann::json::array();
  for (const ModelSummary::Level& l : sum.levels)
    levels.push_back({{"cell_width", uint64_t(1) << l.level}, {"cells", l.cells}, {"bricks", l.bricks}});
  j["levels"] = levels;
  j["width"] = s.frame.width;
  j["height"] = s.frame.height;
  j["threads"] = tbbThreads();
  j["load_average_at_start"] = s.loadAtStart;
  j["load_average_at_end"] = loadAverage();
  j["build"] = {{"load_seconds", s.loadSeconds},
                {"bricks_seconds", s.model.stats.brickSeconds},
                {"regions_seconds", s.model.stats.regionSeconds},
                {"value_ranges_seconds", s.model.stats.rangeSeconds}};
  j["memory"] = {{"peak_rss_after_load_bytes", s.peakAfterLoad},
                 {"model_bytes", sum.brickBytes + sum.valueBytes + sum.regionBytes},
                 {"brick_bytes", sum.brickBytes},
                 {"value_bytes", sum.valueBytes},
                 {"region_bytes", sum.regionBytes}};
  return j;
}

} // namespace bench

namespace {

using bench::BenchOptions;

void run(const BenchOptions& o) {
  bench::Setup s;
  parseSize(o.size, s.frame.width, s.frame.height);
  if (o.frames < 1 || o.frames > 1000) failUsage("--frames must be in 1..1000");
  s.base.integration.earlyTermination = false;
  s.base.integration.autoTraversal = false;
  s.base.integration.traversal = TraversalKind::KdTree;
  // A step too large for the memory available, or any step under --memory-budget: the budget
  // study, since the others hold the whole step.
  const LoadOptions lo = o.in.loadOptions(true);
  const uint64_t frameBytes = streamedFrameBytes(s.frame.width, s.frame.height, 1);
  const bool budgetGiven = !o.in.memoryBudget.empty();
  if (o.inCore && !budgetGiven) failUsage("--in-core compares with a step held under --memory-budget");
  if (const std::optional<uint64_t> budget = memoryBudgetFor(o.in, o.in.input, lo, frameBytes, false);
      budget && (budgetGiven || planWithin(o.in.input, lo, *budget, frameBytes).streamed())) {
    if (o.progressive > 0 || !o.devices.empty())
      failUsage("--progressive and --device hold the whole step; under --memory-budget, bench measures the step "
                "held in parts (plan, survey, first frame, --orbit views)");
    return bench::runBudgeted(o, *budget);
  }
  s.loadAtStart = bench::loadAverage();
  Timer loadTimer;
  s.model = loadModel(o.in.input, lo);
  s.loadSeconds = loadTimer.seconds();
  s.peakAfterLoad = peakResidentBytes();
  s.field = s.model.requireField(o.in.field);
  s.base.layers = {VolumeLayer{s.model.fieldNames[size_t(s.field)], defaultTransferFunction()}};
  s.worldBox = s.model.worldBounds();
  if (o.progressive > 0)
    bench::runProgressive(s, o); // on the one device --device names, if any
  else if (!o.devices.empty())
    bench::runDevices(s, o);
  else if (o.orbitStudy)
    bench::runOrbit(s, o);
  else
    bench::runCases(s, o);
}

} // namespace

void addBench(CLI::App& app) {
  auto o = std::make_shared<BenchOptions>();
  CLI::App* cmd = app.add_subcommand("bench", "Measure renderer variants, or frame time over an orbit of views");
  o->in.add(*cmd);
  o->in.addMemoryBudget(*cmd);
  cmd->add_option("--size", o->size, "Image size WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--frames", o->frames, "Rounds of one frame per variant, interleaved (median, after a warm-up)")
      ->capture_default_str();
  cmd->add_option("--cases", o->cases,
                  "all, or a comma list of: reconstruction, sampling, skipping, traversal, shading")
      ->capture_default_str();
  CLI::Option* orbit = cmd->add_option("--orbit", o->orbit,
                                       "Orbit study instead of the cases: N views on the bounding sphere (default 50)")
                           ->expected(0, 1)
                           ->default_str("50");
  cmd->add_option("--progressive", o->progressive,
                  "Progressive study instead of the cases: N preview passes after a transfer-function change");
  cmd->add_option("--preview-divisor", o->previewDivisor, "Progressive study: preview resolution divisor")
      ->capture_default_str();
  cmd->add_option("--preview-rate", o->previewRate, "Progressive study: preview sampling rate")->capture_default_str();
  cmd->add_option("--csv", o->csv, "Orbit study: CSV file to write")->capture_default_str();
  cmd->add_option("--plot", o->plot, "Orbit study: PNG plot to write")->capture_default_str();
  cmd->add_flag("--in-core", o->inCore,
                "With --memory-budget: then read the whole step and draw the first view from it, compared");
  cmd->add_flag("--json", o->json, "Print the results as one JSON object on stdout");
  cmd->add_option("--device", o->devices,
                  "Device study instead of the cases: a comma list of cpu, cuda, auto, portable (for example "
                  "cpu,cuda): full-quality frames, drafts at --preview-rate, an orbit (--orbit views, default 36), "
                  "upload and memory, ratios to the first");
  cmd->callback([o, orbit] {
    o->orbitStudy = orbit->count() > 0;
    run(*o);
  });
}

} // namespace exa::cli
