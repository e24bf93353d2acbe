// exabricks bench --device: the same frames on each device of a list, in one run: upload, a
// transfer-function change, full-quality frames, the viewer's drafts, an orbit, memory on the
// device, and the ratios to the first device of the list.
#include "bench.h"

#include "exabricks/core/log.h"
#include "exabricks/render/scene_vocabulary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>

namespace exa::cli::bench {
namespace {

/// One device of the list: its renderer and what was measured on it.
struct DeviceRun {
  std::string name, label;
  std::unique_ptr<Renderer> renderer;
  double sceneSeconds = 0, uploadSeconds = 0, changeSeconds = 0;
  uint64_t changeBytes = 0;
  std::vector<double> fullSeconds, draftSeconds;
  double orbitSeconds = 0;
  RenderStats fullStats;
  Image image;
};

std::vector<std::string> deviceNames(const std::string& list) {
  std::vector<std::string> names;
  std::istringstream in(list);
  for (std::string part; std::getline(in, part, ',');)
    if (!part.empty()) names.push_back(part);
  if (names.empty()) failUsage("--device names no device");
  return names;
}

/// A renderer on the device `name`: the scene set, moved to the device, the change to `changed`
/// timed, then back to `scene` and warmed up with a full frame and a draft.
DeviceRun prepareDevice(const Setup& s, const std::string& name, const Scene& scene, const Scene& changed,
                        const Frame& full, const Frame& draft) {
  logInfo(strCat("bench: device ", name));
  DeviceRun r;
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
  return r;
}

/// `frames` rounds of a full frame and a draft on every device, then an orbit of `views` full
/// frames on each.
void measureDevices(std::vector<DeviceRun>& runs, const Frame& full, const Frame& draft, int frames, int views,
                    const box3d& worldBox) {
  for (int f = 0; f < frames; ++f)
    for (DeviceRun& r : runs) {
      RenderStats st;
      r.image = r.renderer->render(full, &st);
      r.fullSeconds.push_back(st.seconds);
      r.fullStats = st;
      r.renderer->render(draft, &st);
      r.draftSeconds.push_back(st.seconds);
    }
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (DeviceRun& r : runs) {
    Frame view = full;
    Timer t;
    for (int i = 0; i < views; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / views;
      view.camera = Camera::frame(worldBox, std::fmod(i * golden, 2.0 * M_PI) * 180.0 / M_PI,
                                  std::asin(z) * 180.0 / M_PI, 40.0, false);
      r.renderer->render(view);
    }
    r.orbitSeconds = t.seconds();
  }
}

/// One device's entry of the JSON, with its ratios to the first device.
nlohmann::json deviceEntry(const DeviceRun& r, const DeviceRun& first, int views) {
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
  return d;
}

void printDevices(const BenchOptions& o, const nlohmann::json& j, const std::vector<DeviceRun>& runs, const Frame& full,
                  const Frame& draft, int views) {
  const nlohmann::json& list = j["devices"];
  const DeviceRun& first = runs.front();
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

} // namespace

/// The device study: the same frames on each device of the list, in one run: upload, a
/// transfer-function change, full-quality frames, the viewer's drafts (full resolution at its
/// draft rate), an orbit of full-quality frames, memory on the device, and the ratios to the
/// first device of the list.
void runDevices(const Setup& s, const BenchOptions& o) {
  const std::vector<std::string> names = deviceNames(o.devices);
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

  std::vector<DeviceRun> runs;
  for (const std::string& name : names)
    runs.push_back(prepareDevice(s, name, scene, changed, full, draft));
  measureDevices(runs, full, draft, o.frames, views, s.worldBox);

  nlohmann::json j = describe(s, o);
  j["frames"] = o.frames;
  j["orbit_views"] = views;
  j["draft_rate"] = draft.rate;
  nlohmann::json list = nlohmann::json::array();
  for (const DeviceRun& r : runs)
    list.push_back(deviceEntry(r, runs.front(), views));
  j["devices"] = list;
  j["memory"]["peak_rss_bytes"] = peakResidentBytes();
  if (o.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  printDevices(o, j, runs, full, draft, views);
}

} // namespace exa::cli::bench
