// exabricks bench, the cases: renderer variants (cell location, fixed-step sampling, space
// skipping, Embree traversal, shading) against the base variant, interleaved in one run, with
// the ratios of their frame times and the differences of their images.
#include "bench.h"

#include "exabricks/amr/cell_locator.h"
#include "exabricks/core/log.h"
#include "exabricks/render/scene_vocabulary.h"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>

namespace exa::cli::bench {
namespace {

const std::vector<std::string> kCaseNames = {"reconstruction", "sampling", "skipping", "traversal", "shading"};

/// The same colours, transparent over the lower 80 % of the value range.
TransferFunction hiding80(TransferFunction tf) {
  tf.opacity = {{0.f, 0.f}, {0.8f, 0.f}, {0.9f, 0.5f}, {1.f, 1.f}};
  return tf;
}

struct VariantResult {
  std::string name;
  RenderStats stats; ///< seconds: median frame time
  size_t visibleRegions = 0;
  double updateSeconds = 0;
  std::string traversal;
  Image image;
};

struct Variant {
  std::string name;
  Scene scene;
};

/// Renders every variant once as a warm-up, then `frames` rounds of one frame per variant, so
/// that a change of the machine's load during the run touches every variant alike; the frame
/// time of a variant is its median over the rounds.
std::vector<VariantResult> measureInterleaved(const std::vector<Variant>& variants, const Model& model,
                                              const Frame& frame, int frames) {
  std::vector<std::unique_ptr<Renderer>> renderers;
  std::vector<VariantResult> results(variants.size());
  for (size_t v = 0; v < variants.size(); ++v) {
    logInfo(strCat("bench: ", variants[v].name));
    renderers.push_back(std::make_unique<Renderer>(model));
    VariantResult& r = results[v];
    r.name = variants[v].name;
    r.updateSeconds = renderers[v]->setScene(variants[v].scene).seconds();
    r.visibleRegions = renderers[v]->visibleRegions();
    r.traversal = nameOf(renderers[v]->traversalInUse());
    RenderStats warm;
    renderers[v]->render(frame, &warm); // warm-up, not counted
  }
  std::vector<std::vector<double>> seconds(variants.size());
  for (int f = 0; f < frames; ++f)
    for (size_t v = 0; v < variants.size(); ++v) {
      results[v].image = renderers[v]->render(frame, &results[v].stats);
      seconds[v].push_back(results[v].stats.seconds);
    }
  for (size_t v = 0; v < variants.size(); ++v) {
    std::sort(seconds[v].begin(), seconds[v].end());
    results[v].stats.seconds = seconds[v][seconds[v].size() / 2];
  }
  return results;
}

std::vector<std::string> parseCases(const std::string& s) {
  if (s == "all") return kCaseNames;
  std::vector<std::string> out;
  std::istringstream in(s);
  for (std::string part; std::getline(in, part, ',');) {
    if (std::find(kCaseNames.begin(), kCaseNames.end(), part) == kCaseNames.end())
      fail("unknown case '", part, "' (choose from: all, reconstruction, sampling, skipping, traversal, shading)");
    if (std::find(out.begin(), out.end(), part) == out.end()) out.push_back(part);
  }
  if (out.empty()) failUsage("--cases names no case");
  return out;
}

/// The cell locator's own build, timed apart from the renderer.
struct LocatorBuild {
  double seconds = 0;
  size_t nodes = 0;
};

LocatorBuild buildLocator(const Model& model) {
  LocatorBuild b;
  Timer t;
  const CellLocator locator(model);
  b.seconds = t.seconds();
  b.nodes = locator.nodeCount();
  return b;
}

/// The base variant and the variants of the chosen cases.
template <typename Has> std::vector<Variant> caseVariants(const Setup& s, const Has& has) {
  auto with = [&](auto change) {
    Scene scene = s.base;
    change(scene);
    return scene;
  };
  auto hide80 = [](Scene& sc) { sc.layers[0].tf = hiding80(sc.layers[0].tf); };
  std::vector<Variant> variants = {{"regions, kd, adaptive", s.base}};
  if (has("reconstruction"))
    variants.push_back(
        {"cell location", with([](Scene& r) { r.integration.reconstruction = Reconstruction::CellLocation; })});
  if (has("sampling"))
    variants.push_back({"fixed-step sampling", with([](Scene& r) { r.integration.sampling = Sampling::Fixed; })});
  if (has("skipping")) {
    variants.push_back({"hide 80%, skipping on", with(hide80)});
    variants.push_back({"hide 80%, skipping off", with([&](Scene& r) {
                          hide80(r);
                          r.integration.spaceSkipping = false;
                        })});
  }
  if (has("traversal"))
    variants.push_back({"embree traversal", with([](Scene& r) { r.integration.traversal = TraversalKind::Embree; })});
  if (has("shading")) {
    variants.push_back({"analytic shading", with([](Scene& r) { r.shading = Shading::Analytic; })});
    variants.push_back({"no shading", with([](Scene& r) { r.shading = Shading::None; })});
  }
  return variants;
}

/// The variants' frame times, samples and images against the base variant's.
template <typename Has> nlohmann::json caseRatios(const std::vector<VariantResult>& results, const Has& has) {
  auto result = [&](const char* name) -> const VariantResult& {
    for (const VariantResult& r : results)
      if (r.name == name) return r;
    fail("internal: no variant ", name);
  };

  nlohmann::json ratios;
  auto diffJson = [](const ImageDiff& d) { return nlohmann::json{{"rmse", d.rmse}, {"max_abs", d.maxAbs}}; };
  const VariantResult& base = result("regions, kd, adaptive");
  if (has("reconstruction")) {
    const VariantResult& cells = result("cell location");
    ratios["cells_over_regions_time"] = cells.stats.seconds / base.stats.seconds;
    ratios["cells_vs_regions_image"] = diffJson(difference(cells.image, base.image));
  }
  if (has("sampling")) {
    const VariantResult& fixed = result("fixed-step sampling");
    ratios["fixed_over_adaptive_samples"] =
        double(fixed.stats.samples) / double(std::max<uint64_t>(base.stats.samples, 1));
    ratios["fixed_over_adaptive_time"] = fixed.stats.seconds / base.stats.seconds;
    ratios["adaptive_vs_fixed_image"] = diffJson(difference(base.image, fixed.image));
  }
  if (has("skipping")) {
    const VariantResult& on = result("hide 80%, skipping on");
    const VariantResult& off = result("hide 80%, skipping off");
    ratios["skip_off_over_on_time"] = off.stats.seconds / on.stats.seconds;
    ratios["skip_on_vs_off_image"] = diffJson(difference(on.image, off.image));
  }
  if (has("shading")) {
    // The base variant shades with the scene's shading (smooth by default).
    ratios["base_over_analytic_shading_time"] = base.stats.seconds / result("analytic shading").stats.seconds;
    ratios["base_over_no_shading_time"] = base.stats.seconds / result("no shading").stats.seconds;
  }
  if (has("traversal")) {
    const VariantResult& embree = result("embree traversal");
    ratios["embree_over_kd_time"] = embree.stats.seconds / base.stats.seconds;
    ratios["embree_vs_kd_image"] = diffJson(difference(embree.image, base.image));
  }
  return ratios;
}

nlohmann::json casesJson(const Setup& s, const BenchOptions& o, const std::vector<VariantResult>& results,
                         const nlohmann::json& ratios, const LocatorBuild& locator) {
  nlohmann::json j = describe(s, o);
  j["frames"] = o.frames;
  j["build"]["cell_locator_seconds"] = locator.seconds;
  j["build"]["cell_locator_nodes"] = locator.nodes;
  nlohmann::json variantsJson = nlohmann::json::array();
  for (const VariantResult& r : results)
    variantsJson.push_back({{"name", r.name},
                            {"frame_seconds", r.stats.seconds},
                            {"rays", r.stats.rays},
                            {"samples", r.stats.samples},
                            {"regions_visited", r.stats.regionsVisited},
                            {"samples_per_second", r.stats.samplesPerSecond()},
                            {"visible_regions", r.visibleRegions},
                            {"traversal", r.traversal},
                            {"transfer_function_update_seconds", r.updateSeconds}});
  j["variants"] = variantsJson;
  j["ratios"] = ratios;
  j["memory"]["peak_rss_bytes"] = peakResidentBytes();
  j["memory"]["cell_locator_bytes"] = locator.nodes * 16 + s.model.bricks.size() * 4;
  return j;
}

void printCases(const Setup& s, const BenchOptions& o, const nlohmann::json& j,
                const std::vector<VariantResult>& results, double locatorSeconds) {
  const nlohmann::json& ratios = j["ratios"];
  std::printf("dataset %s: %llu cells, %llu bricks, %llu regions; %dx%d, %d threads, median of %d interleaved "
              "rounds after a warm-up, early termination off\n",
              o.in.name().c_str(), (unsigned long long)j["cells"].get<uint64_t>(),
              (unsigned long long)j["bricks"].get<uint64_t>(), (unsigned long long)j["regions"].get<uint64_t>(),
              s.frame.width, s.frame.height, tbbThreads(), o.frames);
  std::printf("build: load %.3f s (bricks %.3f s, regions %.3f s, value ranges %.3f s), cell locator %.3f s\n",
              s.loadSeconds, s.model.stats.brickSeconds, s.model.stats.regionSeconds, s.model.stats.rangeSeconds,
              locatorSeconds);
  std::printf("memory: model %.1f MiB, peak RSS %.1f MiB (%.1f MiB after load)\n",
              double(j["memory"]["model_bytes"].get<uint64_t>()) / 1048576.0, double(peakResidentBytes()) / 1048576.0,
              double(s.peakAfterLoad) / 1048576.0);
  std::printf("load average (1 min): %.2f at the start, %.2f at the end\n\n", j["load_average_at_start"].get<double>(),
              j["load_average_at_end"].get<double>());
  std::printf("%-26s %9s %13s %12s %11s %9s\n", "variant", "frame s", "samples", "regions", "Msamples/s", "visible");
  for (const VariantResult& r : results)
    std::printf("%-26s %9.3f %13llu %12llu %11.2f %9zu\n", r.name.c_str(), r.stats.seconds,
                (unsigned long long)r.stats.samples, (unsigned long long)r.stats.regionsVisited,
                r.stats.samplesPerSecond() / 1e6, r.visibleRegions);
  std::printf("\n");
  auto line = [&](const char* label, const char* key, const char* diffKey) {
    if (!ratios.contains(key)) return;
    std::printf("%-40s %8.2fx", label, ratios[key].get<double>());
    if (diffKey && ratios.contains(diffKey))
      std::printf("   image difference: rmse %.2e, max %.2e", ratios[diffKey]["rmse"].get<double>(),
                  ratios[diffKey]["max_abs"].get<double>());
    std::printf("\n");
  };
  line("cell location / regions, frame time", "cells_over_regions_time", "cells_vs_regions_image");
  line("fixed / adaptive sampling, samples", "fixed_over_adaptive_samples", "adaptive_vs_fixed_image");
  line("fixed / adaptive sampling, frame time", "fixed_over_adaptive_time", nullptr);
  line("skipping off / on (hide 80%), frame time", "skip_off_over_on_time", "skip_on_vs_off_image");
  line("embree / kd traversal, frame time", "embree_over_kd_time", "embree_vs_kd_image");
  line("scene's / analytic shading, frame time", "base_over_analytic_shading_time", nullptr);
  line("scene's / no shading, frame time", "base_over_no_shading_time", nullptr);
}

} // namespace

void runCases(const Setup& s, const BenchOptions& o) {
  const std::vector<std::string> cases = parseCases(o.cases);
  auto has = [&](const char* c) { return std::find(cases.begin(), cases.end(), c) != cases.end(); };
  Frame frame = s.frame;
  frame.camera = Camera::frame(s.worldBox, 30.0, 25.0, 40.0, false);
  const LocatorBuild locator = has("reconstruction") ? buildLocator(s.model) : LocatorBuild{};
  const std::vector<VariantResult> results = measureInterleaved(caseVariants(s, has), s.model, frame, o.frames);
  const nlohmann::json j = casesJson(s, o, results, caseRatios(results, has), locator);
  if (o.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  printCases(s, o, j, results, locator.seconds);
}

} // namespace exa::cli::bench
