// The studies of `exabricks bench` (cmd_bench.cpp parses the options and picks one): the renderer
// variants (bench_cases.cpp), the orbit (bench_orbit.cpp), progressive passes
// (bench_progressive.cpp), devices (bench_devices.cpp) and a step held in parts under a memory
// budget (bench_memory.cpp), and what they share.
#pragma once

#include "common.h"

#include "exabricks/amr/model.h"
#include "exabricks/documents/image.h"
#include "exabricks/render/renderer.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace exa::cli::bench {

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
  bool inCore = false; ///< budget study: the whole step read afterwards and compared
};

/// The loaded dataset and what every study starts from.
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

int tbbThreads();

/// The machine's load average over the last minute (/proc/loadavg), or -1 where unknown: the
/// figures are only as quiet as the machine was.
double loadAverage();

struct ImageDiff {
  double rmse = 0, maxAbs = 0;
  double meanAbs = 0;     ///< mean absolute difference
  double shareWithin = 1; ///< share of the channels within 2/255
};

/// Over every channel of every pixel (linear, premultiplied).
ImageDiff difference(const Image& a, const Image& b);

/// Median of a list of seconds.
double median(std::vector<double> v);

/// The dataset, the model's build, the frame, the threads, the load and the memory, as every
/// study's JSON begins.
nlohmann::json describe(const Setup& s, const BenchOptions& o);

void runCases(const Setup& s, const BenchOptions& o);
void runOrbit(const Setup& s, const BenchOptions& o);
void runProgressive(const Setup& s, const BenchOptions& o);
void runDevices(const Setup& s, const BenchOptions& o);
/// The step held in parts under `budget` (bench_memory.cpp): plan, survey, first frame, an orbit.
void runBudgeted(const BenchOptions& o, uint64_t budget);

} // namespace exa::cli::bench
