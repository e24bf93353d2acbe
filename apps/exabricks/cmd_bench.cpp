// exabricks bench: renderer variants measured in one run on one dataset (frame times, samples,
// regions, the ratios between variants and the image differences), build times and memory;
// with --orbit, the orbit study: frame time against samples and regions over many viewpoints.
#include "bench_plot.h"
#include "commands.h"
#include "common.h"

#include "exabricks/amr/cell_locator.h"
#include "exabricks/core/log.h"
#include "exabricks/documents/image.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/scene_vocabulary.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <unistd.h>

namespace exa::cli {
namespace {

struct BenchOptions {
  InputOptions in;
  std::string size = "512x512";
  int frames = 3;
  std::string cases = "all";
  int orbit = 50;
  bool orbitStudy = false; ///< --orbit was given
  int progressive = 0;     ///< progressive study: preview passes after a transfer-function change
  int previewDivisor = 2;
  float previewRate = 0.5f;
  std::string csv = "exabricks-orbit.csv";
  std::string plot = "exabricks-orbit.png";
  bool json = false;
  std::string devices; ///< device study: a comma list of cpu, cuda, portable, auto
};

int tbbThreads() { return tbb::this_task_arena::max_concurrency(); }

const std::vector<std::string> kCaseNames = {"reconstruction", "sampling", "skipping", "traversal", "shading"};

/// The machine's load average over the last minute (/proc/loadavg), or -1 where unknown: the
/// figures are only as quiet as the machine was.
double loadAverage() {
  std::ifstream in("/proc/loadavg");
  double l = -1;
  if (!(in >> l)) return -1;
  return l;
}

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

struct ImageDiff {
  double rmse = 0, maxAbs = 0;
};

/// Over every channel of every pixel (linear, premultiplied).
ImageDiff difference(const Image& a, const Image& b) {
  ImageDiff d;
  double sum = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const vec4f& p = a.pixels[i];
    const vec4f& q = b.pixels[i];
    for (const double e : {double(p.x) - q.x, double(p.y) - q.y, double(p.z) - q.z, double(p.w) - q.w}) {
      sum += e * e;
      d.maxAbs = std::max(d.maxAbs, std::abs(e));
    }
  }
  d.rmse = a.pixels.empty() ? 0.0 : std::sqrt(sum / (4.0 * double(a.pixels.size())));
  return d;
}

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

/// Least squares fit y = a x1 + b x2 + c (normal equations); false when singular.
bool fitTwo(const std::vector<double>& x1, const std::vector<double>& x2, const std::vector<double>& y, double& a,
            double& b, double& c) {
  double m[3][4] = {};
  for (size_t i = 0; i < y.size(); ++i) {
    const double row[3] = {x1[i], x2[i], 1.0};
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k)
        m[r][k] += row[r] * row[k];
      m[r][3] += row[r] * y[i];
    }
  }
  for (int col = 0; col < 3; ++col) {
    int pivot = col;
    for (int r = col + 1; r < 3; ++r)
      if (std::abs(m[r][col]) > std::abs(m[pivot][col])) pivot = r;
    if (std::abs(m[pivot][col]) < 1e-300) return false;
    std::swap(m[col], m[pivot]);
    for (int r = 0; r < 3; ++r) {
      if (r == col) continue;
      const double f = m[r][col] / m[col][col];
      for (int k = col; k < 4; ++k)
        m[r][k] -= f * m[col][k];
    }
  }
  a = m[0][3] / m[0][0];
  b = m[1][3] / m[1][1];
  c = m[2][3] / m[2][2];
  return std::isfinite(a) && std::isfinite(b) && std::isfinite(c);
}

double correlation(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = double(x.size());
  double mx = 0, my = 0;
  for (size_t i = 0; i < x.size(); ++i)
    mx += x[i], my += y[i];
  mx /= n, my /= n;
  double sxy = 0, sxx = 0, syy = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  return sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : 0.0;
}

struct Setup {
  Model model;
  int field = 0;
  double loadSeconds = 0;
  uint64_t peakAfterLoad = 0;
  double loadAtStart = -1;
  Scene base; ///< the field with the default transfer function, k-d traversal, no early termination
  Frame frame;
  box3d worldBox;
};

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

void runCases(const Setup& s, const BenchOptions& o) {
  const std::vector<std::string> cases = parseCases(o.cases);
  auto has = [&](const char* c) { return std::find(cases.begin(), cases.end(), c) != cases.end(); };
  Frame frame = s.frame;
  frame.camera = Camera::frame(s.worldBox, 30.0, 25.0, 40.0, false);

  // The cell locator's own build, timed apart from the renderer.
  double locatorSeconds = 0;
  size_t locatorNodes = 0;
  if (has("reconstruction")) {
    Timer t;
    const CellLocator locator(s.model);
    locatorSeconds = t.seconds();
    locatorNodes = locator.nodeCount();
  }

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
  const std::vector<VariantResult> results = measureInterleaved(variants, s.model, frame, o.frames);
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

  nlohmann::json j = describe(s, o);
  j["frames"] = o.frames;
  j["build"]["cell_locator_seconds"] = locatorSeconds;
  j["build"]["cell_locator_nodes"] = locatorNodes;
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
  j["memory"]["peak_rss_bytes"] = peakRssBytes();
  j["memory"]["cell_locator_bytes"] = locatorNodes * 16 + s.model.bricks.size() * 4;

  if (o.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("dataset %s: %llu cells, %llu bricks, %llu regions; %dx%d, %d threads, median of %d interleaved "
              "rounds after a warm-up, early termination off\n",
              o.in.name().c_str(), (unsigned long long)j["cells"].get<uint64_t>(),
              (unsigned long long)j["bricks"].get<uint64_t>(), (unsigned long long)j["regions"].get<uint64_t>(),
              s.frame.width, s.frame.height, tbbThreads(), o.frames);
  std::printf("build: load %.3f s (bricks %.3f s, regions %.3f s, value ranges %.3f s), cell locator %.3f s\n",
              s.loadSeconds, s.model.stats.brickSeconds, s.model.stats.regionSeconds, s.model.stats.rangeSeconds,
              locatorSeconds);
  std::printf("memory: model %.1f MiB, peak RSS %.1f MiB (%.1f MiB after load)\n",
              double(j["memory"]["model_bytes"].get<uint64_t>()) / 1048576.0, double(peakRssBytes()) / 1048576.0,
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

void writeCsv(const std::string& path, const std::vector<std::array<double, 6>>& rows) {
  std::ofstream out(path);
  if (!out) fail("cannot write ", path);
  out << "view,azimuth_deg,elevation_deg,frame_seconds,samples,regions_visited\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%zu,%.4f,%.4f,%.6f,%.0f,%.0f\n", i, rows[i][0], rows[i][1], rows[i][2], rows[i][3],
                  rows[i][4]);
    out << buf;
  }
  if (!out) fail("cannot write ", path);
}

void runOrbit(const Setup& s, const BenchOptions& o) {
  if (o.orbit < 1 || o.orbit > 100000) failUsage("--orbit must be in 1..100000");
  Renderer renderer(s.model);
  renderer.setScene(s.base);
  Frame frame = s.frame;
  // Viewpoints on the bounding sphere: a Fibonacci sphere, evenly spread, never at a pole.
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  std::vector<std::array<double, 6>> rows; // azimuth, elevation, seconds, samples, regions, rays
  std::vector<double> t, samples, regions;
  const bool onTerminal = logLevel() >= LogLevel::Warning && isatty(STDERR_FILENO) && !o.json;
  for (int i = 0; i < o.orbit; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / o.orbit;
    const double azimuth = std::fmod(i * golden, 2.0 * M_PI) * 180.0 / M_PI;
    const double elevation = std::asin(z) * 180.0 / M_PI;
    frame.camera = Camera::frame(s.worldBox, azimuth, elevation, 40.0, false);
    RenderStats st;
    if (i == 0) renderer.render(frame, &st); // warm-up, not counted
    renderer.render(frame, &st);
    rows.push_back({azimuth, elevation, st.seconds, double(st.samples), double(st.regionsVisited), double(st.rays)});
    t.push_back(st.seconds);
    samples.push_back(double(st.samples));
    regions.push_back(double(st.regionsVisited));
    if (onTerminal) std::fprintf(stderr, "\rorbit: view %d of %d", i + 1, o.orbit);
  }
  if (onTerminal) std::fprintf(stderr, "\n");
  writeCsv(o.csv, rows);

  double a = 0, b = 0, c = 0;
  const bool fitted = fitTwo(samples, regions, t, a, b, c);
  auto stats = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    double mean = 0;
    for (double x : v)
      mean += x;
    return nlohmann::json{
        {"min", v.front()}, {"median", v[v.size() / 2]}, {"max", v.back()}, {"mean", mean / double(v.size())}};
  };

  // Plot: time against samples and against regions visited, in millions.
  const double maxSamples = *std::max_element(samples.begin(), samples.end());
  const double maxRegions = *std::max_element(regions.begin(), regions.end());
  auto scaled = [](const std::vector<double>& v, double maxValue, std::string& unit) {
    double div = 1.0;
    unit = "";
    if (maxValue >= 1e6)
      div = 1e6, unit = " (M)";
    else if (maxValue >= 1e3)
      div = 1e3, unit = " (k)";
    std::vector<double> out;
    for (double x : v)
      out.push_back(x / div);
    return out;
  };
  std::string su, ru;
  ScatterPanel ps{"frame time vs samples", "", "frame time (s)", scaled(samples, maxSamples, su), t};
  ps.xLabel = "samples" + su;
  ScatterPanel pr{"frame time vs regions visited", "", "frame time (s)", scaled(regions, maxRegions, ru), t};
  pr.xLabel = "regions visited" + ru;
  writePng(o.plot, drawScatterPanels({ps, pr}, 640, 480), false);

  nlohmann::json j = describe(s, o);
  j["views"] = o.orbit;
  j["csv"] = o.csv;
  j["plot"] = o.plot;
  j["frame_seconds"] = stats(t);
  j["samples"] = stats(samples);
  j["regions_visited"] = stats(regions);
  j["correlation_time_samples"] = correlation(samples, t);
  j["correlation_time_regions"] = correlation(regions, t);
  if (fitted)
    j["fit"] = {
        {"seconds_per_million_samples", a * 1e6}, {"seconds_per_million_regions", b * 1e6}, {"seconds_constant", c}};
  j["memory"]["peak_rss_bytes"] = peakRssBytes();
  if (o.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("orbit of %d views around %s (%dx%d, %d threads, early termination off)\n", o.orbit, o.in.name().c_str(),
              s.frame.width, s.frame.height, tbbThreads());
  std::printf("load average (1 min): %.2f at the start, %.2f at the end\n", j["load_average_at_start"].get<double>(),
              j["load_average_at_end"].get<double>());
  for (const char* key : {"frame_seconds", "samples", "regions_visited"})
    std::printf("%-16s min %.4g  median %.4g  max %.4g  mean %.4g\n", key, j[key]["min"].get<double>(),
                j[key]["median"].get<double>(), j[key]["max"].get<double>(), j[key]["mean"].get<double>());
  std::printf("correlation of frame time with samples %.3f, with regions visited %.3f\n",
              j["correlation_time_samples"].get<double>(), j["correlation_time_regions"].get<double>());
  if (fitted) std::printf("fit: time = %.4f s per M samples + %.4f s per M regions + %.4f s\n", a * 1e6, b * 1e6, c);
  std::printf("wrote %s and %s\n", o.csv.c_str(), o.plot.c_str());
}

/// Median of a list of seconds.
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

/// The interactive loop: a transfer-function change, then preview passes (a fraction of the
/// resolution, a lower rate) accumulated progressively; and the same change followed by one
/// full-quality pass. The scene is the render command's default (early termination on,
/// automatic traversal).
void runProgressive(const Setup& s, const BenchOptions& o) {
  if (o.progressive < 1 || o.progressive > 100000) failUsage("--progressive must be in 1..100000");
  if (o.previewDivisor < 1 || o.previewDivisor > 64) failUsage("--preview-divisor must be in 1..64");
  Scene a;
  a.layers = s.base.layers;
  Scene b = a; // the change: another colour map and an opacity that hides the lower half
  b.layers[0].tf.colorMap = builtinColorMap("inferno");
  b.layers[0].tf.opacity = {{0.f, 0.f}, {0.5f, 0.f}, {1.f, 1.f}};
  Frame full = s.frame;
  full.camera = Camera::frame(s.worldBox, 30.0, 25.0, 40.0, false);
  Frame preview = full.preview(o.previewDivisor, o.previewRate);
  preview.samplesPerPixel = o.progressive; // the target: passes are jittered
  Renderer renderer(s.model);
  FrameBuffer previewBuffer(preview.width, preview.height), fullBuffer(full.width, full.height);

  // Warm-up with the first scene, then time the change and the passes after it.
  renderer.setScene(a);
  if (!o.devices.empty()) selectDevice(renderer, o.devices);
  renderer.renderPass(preview, previewBuffer);
  renderer.renderPass(full, fullBuffer);
  const int rounds = std::max(3, o.frames);
  std::vector<double> changeSeconds, firstPreview, passSeconds, fullSeconds, fullChange;
  uint64_t previewSamples = 0;
  for (int round = 0; round < rounds; ++round) {
    renderer.setScene(a);
    Timer change;
    const SceneUpdate u = renderer.setScene(b);
    changeSeconds.push_back(u.seconds());
    previewBuffer.clear();
    for (int i = 0; i < o.progressive; ++i) {
      preview.frameIndex = i;
      Timer pass;
      renderer.renderPass(preview, previewBuffer);
      passSeconds.push_back(pass.seconds());
      if (i == 0) firstPreview.push_back(change.seconds());
    }
    previewSamples = previewBuffer.stats().samples;
    renderer.setScene(a);
    Timer fullChangeTimer;
    renderer.setScene(b);
    fullBuffer.clear();
    Timer fullPass;
    renderer.renderPass(full, fullBuffer);
    fullSeconds.push_back(fullPass.seconds());
    fullChange.push_back(fullChangeTimer.seconds());
  }
  nlohmann::json j = describe(s, o);
  j["preview_width"] = preview.width;
  j["preview_height"] = preview.height;
  j["preview_rate"] = preview.rate;
  j["passes"] = o.progressive;
  j["rounds"] = rounds;
  j["change_seconds"] = median(changeSeconds);
  j["first_preview_after_change_seconds"] = median(firstPreview);
  j["preview_pass_seconds"] = median(passSeconds);
  j["preview_samples_per_pass"] = double(previewSamples) / double(o.progressive);
  j["full_pass_seconds"] = median(fullSeconds);
  j["full_frame_after_change_seconds"] = median(fullChange);
  j["traversal"] = nameOf(renderer.traversalInUse());
  j["visible_regions"] = renderer.visibleRegions();
  j["device"] = deviceJson(renderer);
  if (o.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("progressive passes on %s (%s): preview %dx%d at rate %.2f, full %dx%d (%d threads, median of %d "
              "rounds)\n",
              o.in.name().c_str(), deviceName(renderer.device()), preview.width, preview.height, double(preview.rate),
              full.width, full.height, tbbThreads(), rounds);
  std::printf("load average (1 min): %.2f at the start, %.2f at the end\n", j["load_average_at_start"].get<double>(),
              j["load_average_at_end"].get<double>());
  std::printf("transfer-function change          %8.2f ms (%zu of %zu regions visible, %s traversal)\n",
              1e3 * median(changeSeconds), renderer.visibleRegions(), s.model.regions.regions.size(),
              j["traversal"].get<std::string>().c_str());
  std::printf("first preview after the change     %8.2f ms\n", 1e3 * median(firstPreview));
  std::printf("preview pass (of %d)               %8.2f ms, %.0f samples\n", o.progressive, 1e3 * median(passSeconds),
              double(previewSamples) / double(o.progressive));
  std::printf("full-quality pass                  %8.2f ms\n", 1e3 * median(fullSeconds));
  std::printf("full frame after the change        %8.2f ms (%.1fx the first preview)\n", 1e3 * median(fullChange),
              median(fullChange) / std::max(1e-9, median(firstPreview)));
}

/// The device study: the same frames on each device of the list, in one run: upload, a
/// transfer-function change, full-quality frames, the viewer's drafts (full resolution at its
/// draft rate), an orbit of full-quality frames, memory on the device, and the ratios to the
/// first device of the list.
void runDevices(const Setup& s, const BenchOptions& o) {
  std::vector<std::string> names;
  std::istringstream in(o.devices);
  for (std::string part; std::getline(in, part, ',');)
    if (!part.empty()) names.push_back(part);
  if (names.empty()) failUsage("--device names no device");
  Scene scene = s.base;
  scene.integration = Integration(); // as users render: early termination, automatic traversal
  Scene changed = scene;
  changed.layers[0].tf.colorMap = builtinColorMap("inferno");
  changed.layers[0].tf.opacity = {{0.f, 0.f}, {0.5f, 0.f}, {1.f, 1.f}};
  Frame full = s.frame;
  full.camera = Camera::frame(s.worldBox, 30.0, 25.0, 40.0, false);
  Frame draft = full;
  draft.rate = o.previewRate;
  const int views = o.orbitStudy ? o.orbit : 36;
  if (views < 1 || views > 100000) failUsage("--orbit must be in 1..100000");

  struct Run {
    std::string name, label;
    std::unique_ptr<Renderer> renderer;
    double sceneSeconds = 0, uploadSeconds = 0, changeSeconds = 0;
    uint64_t changeBytes = 0;
    std::vector<double> fullSeconds, draftSeconds;
    double orbitSeconds = 0;
    RenderStats fullStats;
    Image image;
  };
  std::vector<Run> runs;
  for (const std::string& name : names) {
    logInfo(strCat("bench: device ", name));
    Run r;
    r.name = name;
    r.renderer = std::make_unique<Renderer>(s.model);
    Timer t;
    r.renderer->setScene(scene);
    r.sceneSeconds = t.seconds();
    Timer u;
    selectDevice(*r.renderer, name);
    r.uploadSeconds = u.seconds();
    r.label = deviceName(r.renderer->device());
    if (r.renderer->device() == Device::Cuda) r.label += " (" + cudaStatus().name + ")";
    const SceneUpdate change = r.renderer->setScene(changed);
    r.changeSeconds = change.seconds();
    r.changeBytes = change.deviceBytes;
    r.renderer->setScene(scene);
    r.renderer->render(full); // warm-up
    r.renderer->render(draft);
    runs.push_back(std::move(r));
  }
  for (int f = 0; f < o.frames; ++f)
    for (Run& r : runs) {
      RenderStats st;
      r.image = r.renderer->render(full, &st);
      r.fullSeconds.push_back(st.seconds);
      r.fullStats = st;
      r.renderer->render(draft, &st);
      r.draftSeconds.push_back(st.seconds);
    }
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (Run& r : runs) {
    Frame view = full;
    Timer t;
    for (int i = 0; i < views; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / views;
      view.camera = Camera::frame(s.worldBox, std::fmod(i * golden, 2.0 * M_PI) * 180.0 / M_PI,
                                  std::asin(z) * 180.0 / M_PI, 40.0, false);
      r.renderer->render(view);
    }
    r.orbitSeconds = t.seconds();
  }

  nlohmann::json j = describe(s, o);
  j["frames"] = o.frames;
  j["orbit_views"] = views;
  j["draft_rate"] = draft.rate;
  nlohmann::json list = nlohmann::json::array();
  const Run& first = runs.front();
  for (const Run& r : runs) {
    const double fullS = median(r.fullSeconds), draftS = median(r.draftSeconds);
    nlohmann::json d;
    d["device"] = r.name;
    d["in_use"] = r.label;
    d["full_frame_seconds"] = fullS;
    d["draft_frame_seconds"] = draftS;
    d["draft_frames_per_second"] = 1.0 / std::max(draftS, 1e-9);
    d["orbit_frames_per_second"] = views / std::max(r.orbitSeconds, 1e-9);
    d["samples"] = r.fullStats.samples;
    d["full_frame_kernel_seconds"] = r.fullStats.deviceSeconds; // the last round's, on a GPU
    d["scene_seconds"] = r.sceneSeconds;
    d["upload_seconds"] = r.uploadSeconds;
    d["transfer_function_change_seconds"] = r.changeSeconds;
    d["transfer_function_change_bytes"] = r.changeBytes;
    d["device_memory"] = deviceJson(*r.renderer);
    d["full_speedup_over_first"] = median(first.fullSeconds) / std::max(fullS, 1e-9);
    d["draft_speedup_over_first"] = median(first.draftSeconds) / std::max(draftS, 1e-9);
    const ImageDiff diff = difference(r.image, first.image);
    d["image_vs_first"] = {{"rmse", diff.rmse}, {"max_abs", diff.maxAbs}};
    list.push_back(d);
  }
  j["devices"] = list;
  j["memory"]["peak_rss_bytes"] = peakRssBytes();
  if (o.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("devices on %s: %llu cells, %llu bricks, %llu regions; %dx%d at 1 sample per pixel, draft at rate "
              "%.2f, %d CPU threads, median of %d rounds, orbit of %d views\n",
              o.in.name().c_str(), (unsigned long long)j["cells"].get<uint64_t>(),
              (unsigned long long)j["bricks"].get<uint64_t>(), (unsigned long long)j["regions"].get<uint64_t>(),
              full.width, full.height, double(draft.rate), tbbThreads(), o.frames, views);
  std::printf("%-34s %10s %10s %9s %9s %10s %10s %10s\n", "device", "full ms", "draft ms", "draft fps", "orbit fps",
              "upload s", "tf change", "memory MiB");
  for (size_t i = 0; i < runs.size(); ++i) {
    const nlohmann::json& d = list[i];
    const nlohmann::json& mem = d["device_memory"];
    std::printf("%-34s %10.2f %10.2f %9.1f %9.1f %10.3f %7.1f ms %10.1f\n", runs[i].label.c_str(),
                1e3 * d["full_frame_seconds"].get<double>(), 1e3 * d["draft_frame_seconds"].get<double>(),
                d["draft_frames_per_second"].get<double>(), d["orbit_frames_per_second"].get<double>(),
                d["upload_seconds"].get<double>(), 1e3 * d["transfer_function_change_seconds"].get<double>(),
                mem.contains("memory_bytes") ? double(mem["memory_bytes"].get<uint64_t>()) / 1048576.0 : 0.0);
  }
  for (size_t i = 1; i < runs.size(); ++i)
    std::printf("%s / %s: full frames %.1fx faster, drafts %.1fx; image difference rmse %.2e, max %.2e\n",
                runs[i].label.c_str(), first.label.c_str(), list[i]["full_speedup_over_first"].get<double>(),
                list[i]["draft_speedup_over_first"].get<double>(), list[i]["image_vs_first"]["rmse"].get<double>(),
                list[i]["image_vs_first"]["max_abs"].get<double>());
}

void run(const BenchOptions& o) {
  Setup s;
  parseSize(o.size, s.frame.width, s.frame.height);
  if (o.frames < 1 || o.frames > 1000) failUsage("--frames must be in 1..1000");
  s.base.integration.earlyTermination = false;
  s.base.integration.autoTraversal = false;
  s.base.integration.traversal = TraversalKind::KdTree;
  s.loadAtStart = loadAverage();
  Timer loadTimer;
  s.model = loadModel(o.in.input, o.in.loadOptions(true));
  s.loadSeconds = loadTimer.seconds();
  s.peakAfterLoad = peakRssBytes();
  s.field = s.model.requireField(o.in.field);
  s.base.layers = {VolumeLayer{s.model.fieldNames[size_t(s.field)], defaultTransferFunction()}};
  s.worldBox = s.model.worldBounds();
  if (o.progressive > 0)
    runProgressive(s, o); // on the one device --device names, if any
  else if (!o.devices.empty())
    runDevices(s, o);
  else if (o.orbitStudy)
    runOrbit(s, o);
  else
    runCases(s, o);
}

} // namespace

void addBench(CLI::App& app) {
  auto o = std::make_shared<BenchOptions>();
  CLI::App* cmd = app.add_subcommand("bench", "Measure renderer variants, or frame time over an orbit of views");
  o->in.add(*cmd);
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
