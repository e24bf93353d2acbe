// exabricks bench --progressive: the interactive loop, a transfer-function change followed by
// preview passes accumulated progressively, against the same change followed by one
// full-quality pass, both through the progressive view the interactive front ends use.
#include "bench.h"

#include "exabricks/core/log.h"
#include "exabricks/render/scene_vocabulary.h"
#include "exabricks/workflows/progressive.h"

#include <algorithm>
#include <cstdio>
#include <iostream>

namespace exa::cli::bench {
namespace {

/// The times of every round, and the samples of the last round's preview passes.
struct ProgressiveTimes {
  std::vector<double> changeSeconds, firstPreview, passSeconds, fullSeconds, fullChange;
  uint64_t previewSamples = 0;
};

/// `rounds` rounds of: the change from `a` to `b` in a view of the preview frame, then its
/// `passes` passes; and the same change in a view of the full frame, then its first pass. The
/// view shows `a` on entry.
ProgressiveTimes measureProgressive(ProgressiveView& view, const Scene& a, const Scene& b, const Frame& preview,
                                    const Frame& full, int passes, int rounds) {
  // Warm-up with the first scene, then time the change and the passes after it.
  view.showFrame(preview);
  view.refine(PassControl());
  view.showFrame(full);
  view.refine(PassControl());
  ProgressiveTimes p;
  for (int round = 0; round < rounds; ++round) {
    view.show({"", a, preview});
    Timer change;
    const SceneUpdate u = view.showScene(b);
    p.changeSeconds.push_back(u.seconds());
    for (int i = 0; i < passes; ++i) {
      Timer pass;
      view.refine(PassControl());
      p.passSeconds.push_back(pass.seconds());
      if (i == 0) p.firstPreview.push_back(change.seconds());
    }
    p.previewSamples = view.buffer().stats().samples;
    view.show({"", a, full});
    Timer fullChangeTimer;
    view.showScene(b);
    Timer fullPass;
    view.refine(PassControl());
    p.fullSeconds.push_back(fullPass.seconds());
    p.fullChange.push_back(fullChangeTimer.seconds());
  }
  return p;
}

void printProgressive(const Setup& s, const BenchOptions& o, const nlohmann::json& j, const Renderer& renderer,
                      const Frame& preview, const Frame& full, int rounds, const ProgressiveTimes& p) {
  std::printf("progressive passes on %s (%s): preview %dx%d at rate %.2f, full %dx%d (%d threads, median of %d "
              "rounds)\n",
              o.in.name().c_str(), deviceName(renderer.device()), preview.width, preview.height, double(preview.rate),
              full.width, full.height, tbbThreads(), rounds);
  std::printf("load average (1 min): %.2f at the start, %.2f at the end\n", j["load_average_at_start"].get<double>(),
              j["load_average_at_end"].get<double>());
  std::printf("transfer-function change          %8.2f ms (%zu of %zu regions visible, %s traversal)\n",
              1e3 * median(p.changeSeconds), renderer.visibleRegions(), s.model.regions.regions.size(),
              j["traversal"].get<std::string>().c_str());
  std::printf("first preview after the change     %8.2f ms\n", 1e3 * median(p.firstPreview));
  std::printf("preview pass (of %d)               %8.2f ms, %.0f samples\n", o.progressive, 1e3 * median(p.passSeconds),
              double(p.previewSamples) / double(o.progressive));
  std::printf("full-quality pass                  %8.2f ms\n", 1e3 * median(p.fullSeconds));
  std::printf("full frame after the change        %8.2f ms (%.1fx the first preview)\n", 1e3 * median(p.fullChange),
              median(p.fullChange) / std::max(1e-9, median(p.firstPreview)));
}

} // namespace

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
  ProgressiveView view(renderer, o.devices.empty() ? "cpu" : o.devices);
  view.showScene(a);
  const int rounds = std::max(3, o.frames);
  const ProgressiveTimes p = measureProgressive(view, a, b, preview, full, o.progressive, rounds);
  nlohmann::json j = describe(s, o);
  j["preview_width"] = preview.width;
  j["preview_height"] = preview.height;
  j["preview_rate"] = preview.rate;
  j["passes"] = o.progressive;
  j["rounds"] = rounds;
  j["change_seconds"] = median(p.changeSeconds);
  j["first_preview_after_change_seconds"] = median(p.firstPreview);
  j["preview_pass_seconds"] = median(p.passSeconds);
  j["preview_samples_per_pass"] = double(p.previewSamples) / double(o.progressive);
  j["full_pass_seconds"] = median(p.fullSeconds);
  j["full_frame_after_change_seconds"] = median(p.fullChange);
  j["traversal"] = nameOf(renderer.traversalInUse());
  j["visible_regions"] = renderer.visibleRegions();
  j["device"] = deviceJson(renderer);
  if (o.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  printProgressive(s, o, j, renderer, preview, full, rounds, p);
}

} // namespace exa::cli::bench
