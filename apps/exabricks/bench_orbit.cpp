// exabricks bench --orbit: frame time against samples and regions visited over many viewpoints
// on the bounding sphere, as a CSV file, a scatter plot, correlations and a linear fit.
#include "bench.h"
#include "bench_plot.h"

#include "exabricks/core/log.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <unistd.h>

namespace exa::cli::bench {
namespace {

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

/// The frame time, samples and regions visited of every view of the orbit.
struct OrbitViews {
  std::vector<std::array<double, 6>> rows; // azimuth, elevation, seconds, samples, regions, rays
  std::vector<double> t, samples, regions;
};

OrbitViews renderOrbit(const Setup& s, const BenchOptions& o) {
  Renderer renderer(s.model);
  renderer.setScene(s.base);
  Frame frame = s.frame;
  // Viewpoints on the bounding sphere: a Fibonacci sphere, evenly spread, never at a pole.
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  OrbitViews v;
  const bool onTerminal = logLevel() >= LogLevel::Warning && isatty(STDERR_FILENO) && !o.json;
  for (int i = 0; i < o.orbit; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / o.orbit;
    const double azimuth = std::fmod(i * golden, 2.0 * M_PI) * 180.0 / M_PI;
    const double elevation = std::asin(z) * 180.0 / M_PI;
    frame.camera = Camera::frame(s.worldBox, azimuth, elevation, 40.0, false);
    RenderStats st;
    if (i == 0) renderer.render(frame, &st); // warm-up, not counted
    renderer.render(frame, &st);
    v.rows.push_back({azimuth, elevation, st.seconds, double(st.samples), double(st.regionsVisited), double(st.rays)});
    v.t.push_back(st.seconds);
    v.samples.push_back(double(st.samples));
    v.regions.push_back(double(st.regionsVisited));
    if (onTerminal) std::fprintf(stderr, "\rorbit: view %d of %d", i + 1, o.orbit);
  }
  if (onTerminal) std::fprintf(stderr, "\n");
  return v;
}

/// Plot: time against samples and against regions visited, in millions.
void writePlot(const std::string& path, const OrbitViews& v) {
  const double maxSamples = *std::max_element(v.samples.begin(), v.samples.end());
  const double maxRegions = *std::max_element(v.regions.begin(), v.regions.end());
  auto scaled = [](const std::vector<double>& values, double maxValue, std::string& unit) {
    double div = 1.0;
    unit = "";
    if (maxValue >= 1e6)
      div = 1e6, unit = " (M)";
    else if (maxValue >= 1e3)
      div = 1e3, unit = " (k)";
    std::vector<double> out;
    for (double x : values)
      out.push_back(x / div);
    return out;
  };
  std::string su, ru;
  ScatterPanel ps{"frame time vs samples", "", "frame time (s)", scaled(v.samples, maxSamples, su), v.t};
  ps.xLabel = "samples" + su;
  ScatterPanel pr{"frame time vs regions visited", "", "frame time (s)", scaled(v.regions, maxRegions, ru), v.t};
  pr.xLabel = "regions visited" + ru;
  writePng(path, drawScatterPanels({ps, pr}, 640, 480), false);
}

/// Minimum, median, maximum and mean.
nlohmann::json spread(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  double mean = 0;
  for (double x : v)
    mean += x;
  return nlohmann::json{
      {"min", v.front()}, {"median", v[v.size() / 2]}, {"max", v.back()}, {"mean", mean / double(v.size())}};
}

void printOrbit(const Setup& s, const BenchOptions& o, const nlohmann::json& j) {
  std::printf("orbit of %d views around %s (%dx%d, %d threads, early termination off)\n", o.orbit, o.in.name().c_str(),
              s.frame.width, s.frame.height, tbbThreads());
  std::printf("load average (1 min): %.2f at the start, %.2f at the end\n", j["load_average_at_start"].get<double>(),
              j["load_average_at_end"].get<double>());
  for (const char* key : {"frame_seconds", "samples", "regions_visited"})
    std::printf("%-16s min %.4g  median %.4g  max %.4g  mean %.4g\n", key, j[key]["min"].get<double>(),
                j[key]["median"].get<double>(), j[key]["max"].get<double>(), j[key]["mean"].get<double>());
  std::printf("correlation of frame time with samples %.3f, with regions visited %.3f\n",
              j["correlation_time_samples"].get<double>(), j["correlation_time_regions"].get<double>());
}

} // namespace

void runOrbit(const Setup& s, const BenchOptions& o) {
  if (o.orbit < 1 || o.orbit > 100000) failUsage("--orbit must be in 1..100000");
  const OrbitViews v = renderOrbit(s, o);
  writeCsv(o.csv, v.rows);

  double a = 0, b = 0, c = 0;
  const bool fitted = fitTwo(v.samples, v.regions, v.t, a, b, c);
  writePlot(o.plot, v);

  nlohmann::json j = describe(s, o);
  j["views"] = o.orbit;
  j["csv"] = o.csv;
  j["plot"] = o.plot;
  j["frame_seconds"] = spread(v.t);
  j["samples"] = spread(v.samples);
  j["regions_visited"] = spread(v.regions);
  j["correlation_time_samples"] = correlation(v.samples, v.t);
  j["correlation_time_regions"] = correlation(v.regions, v.t);
  if (fitted)
    j["fit"] = {
        {"seconds_per_million_samples", a * 1e6}, {"seconds_per_million_regions", b * 1e6}, {"seconds_constant", c}};
  j["memory"]["peak_rss_bytes"] = peakResidentBytes();
  if (o.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  printOrbit(s, o, j);
  if (fitted) std::printf("fit: time = %.4f s per M samples + %.4f s per M regions + %.4f s\n", a * 1e6, b * 1e6, c);
  std::printf("wrote %s and %s\n", o.csv.c_str(), o.plot.c_str());
}

} // namespace exa::cli::bench
