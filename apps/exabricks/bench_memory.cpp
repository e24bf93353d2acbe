// exabricks bench --memory-budget: a step held in parts under a budget. The plan, the pass that
// surveys every part (what a first picture needs), the framing (every part's renderer set up),
// the first converged frame, then the frames of an orbit (each drawn part by part, the parts that
// fit kept between frames, the others read back from disk), with the parts read and the peak
// resident memory after each phase; with --in-core, the whole step read afterwards and the first
// view drawn from it, compared (time ratio and image difference).
#include "bench.h"

#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/render/camera_path.h"
#include "exabricks/render/transfer_function.h"
#include "exabricks/workflows/streamed.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <unistd.h>

namespace exa::cli::bench {

namespace {

struct BudgetedFrame {
  double seconds = 0;
  uint64_t partsRead = 0;
  uint64_t peakBytes = 0;
};

/// difference() in steps of 1/255: mean, largest, and the share of channels within 2/255.
nlohmann::json imageAgreement(const Image& a, const Image& b) {
  const ImageDiff d = difference(a, b);
  return {{"mean_255", d.meanAbs * 255.0}, {"max_255", d.maxAbs * 255.0}, {"share_within_2_255", d.shareWithin}};
}

/// The whole step read after the budgeted frames (so that their peak was measured first), the
/// first view drawn from it and compared with the budgeted one.
nlohmann::json inCoreComparison(const BenchOptions& o, const LoadOptions& lo, const Scene& scene, const Frame& frame,
                                double budgetedSeconds, const Image& budgeted) {
  Timer load;
  const Model model = loadModel(o.in.input, lo);
  const double loadSeconds = load.seconds();
  Timer setUp; // the renderer's structures and smooth shading's gradients, as a part's frame has them
  Renderer renderer(model);
  renderer.setScene(scene);
  const double setUpSeconds = setUp.seconds();
  RenderStats st;
  const Image whole = renderer.render(frame, &st);
  return {{"load_seconds", loadSeconds},
          {"set_up_seconds", setUpSeconds},
          {"frame_seconds", st.seconds},
          {"first_picture_seconds", loadSeconds + setUpSeconds + st.seconds},
          {"peak_rss_bytes", peakResidentBytes()},
          // First frames both: the set-up (structures, gradients) and the frame.
          {"first_frame_ratio_budget_over_in_core", budgetedSeconds / std::max(1e-9, setUpSeconds + st.seconds)},
          {"difference", imageAgreement(budgeted, whole)}};
}

void printBudgeted(const nlohmann::json& j, const BenchOptions& o) {
  std::printf("%s, %llu cells, %dx%d, %d threads, budget %s: %d parts (largest about %s)\n", o.in.name().c_str(),
              (unsigned long long)j["cells"], int(j["width"]), int(j["height"]), int(j["threads"]),
              formatBytes(uint64_t(j["budget_bytes"])).c_str(), int(j["parts"]),
              formatBytes(uint64_t(j["largest_part_bytes_estimate"])).c_str());
  std::printf("plan %.3f s, survey of every part %.3f s, framing %.3f s, first frame %.3f s: first picture %.3f s\n",
              double(j["plan_seconds"]), double(j["survey_seconds"]), double(j["framing_seconds"]),
              double(j["first_frame_seconds"]), double(j["first_picture_seconds"]));
  std::printf("orbit: %zu views, median %.3f s per later view, parts read per view:", j["orbit"].size(),
              double(j["orbit_median_seconds"]));
  for (const nlohmann::json& f : j["orbit"])
    std::printf(" %llu", (unsigned long long)f["parts_read"]);
  std::printf("\npeak resident %s of a %s budget\n", formatBytes(uint64_t(j["peak_rss_bytes"])).c_str(),
              formatBytes(uint64_t(j["budget_bytes"])).c_str());
  if (!j.contains("in_core")) return;
  const nlohmann::json& c = j["in_core"];
  std::printf(
      "in core: load %.3f s, set-up %.3f s, frame %.3f s (first frame budgeted / in core %.2fx), peak %s; difference "
      "mean %.4f/255, max %.3f/255, %.4f%% of channels within 2/255\n",
      double(c["load_seconds"]), double(c["set_up_seconds"]), double(c["frame_seconds"]),
      double(c["first_frame_ratio_budget_over_in_core"]), formatBytes(uint64_t(c["peak_rss_bytes"])).c_str(),
      double(c["difference"]["mean_255"]), double(c["difference"]["max_255"]),
      100.0 * double(c["difference"]["share_within_2_255"]));
}

} // namespace

void runBudgeted(const BenchOptions& o, uint64_t budget) {
  Frame frame;
  parseSize(o.size, frame.width, frame.height);
  const int views = o.orbitStudy ? o.orbit : 8;
  if (views < 1 || views > 10000) failUsage("--orbit must be in 1..10000");
  const double loadAtStart = loadAverage();
  const LoadOptions lo = o.in.loadOptions(true);
  Timer total;
  const MemoryPlan plan = planWithin(o.in.input, lo, budget, streamedFrameBytes(frame.width, frame.height, 1));
  const double planSeconds = total.seconds();
  StreamedStep step(o.in.input, lo, plan);
  Timer surveyTimer;
  const StepSurvey& survey = step.survey();
  const double surveySeconds = surveyTimer.seconds();
  const uint64_t peakAfterSurvey = peakResidentBytes();

  const Model& skeleton = step.skeleton();
  Scene scene;
  const std::string field = skeleton.fieldNames[size_t(skeleton.requireField(o.in.field))];
  scene.layers = {VolumeLayer{field, defaultTransferFunction()}};
  const RendererOptions options;
  Timer framing; // every part's renderer set up (structures, gradients) for the visible bounds
  box3d target = step.visibleBounds(scene, options);
  if (target.empty()) target = skeleton.world.toWorld(survey.cellBounds);
  const double framingSeconds = framing.seconds();

  const bool onTerminal = logLevel() >= LogLevel::Warning && isatty(STDERR_FILENO) && !o.json;
  std::vector<BudgetedFrame> frames; // the first is the first picture's frame
  Image first;
  for (int i = 0; i < views; ++i) {
    frame.camera = orbitCamera(target, 30.0, 25.0, 40.0, false, i, views);
    FrameBuffer buffer(frame.width, frame.height);
    const uint64_t readBefore = step.partsRead();
    Timer t;
    renderStreamed(step, scene, options, frame, buffer);
    frames.push_back({t.seconds(), step.partsRead() - readBefore, peakResidentBytes()});
    if (i == 0) first = buffer.resolve();
    if (onTerminal) std::fprintf(stderr, "\rbudget: view %d of %d", i + 1, views);
  }
  if (onTerminal) std::fprintf(stderr, "\n");

  nlohmann::json j;
  j["dataset"] = o.in.name();
  j["field"] = field;
  j["cells"] = survey.cells;
  j["width"] = frame.width;
  j["height"] = frame.height;
  j["threads"] = tbbThreads();
  j["load_average_at_start"] = loadAtStart;
  j["budget_bytes"] = budget;
  j["parts"] = step.parts();
  j["largest_part_bytes_estimate"] = plan.largestPartBytes();
  j["plan_seconds"] = planSeconds;
  j["survey_seconds"] = surveySeconds;
  j["framing_seconds"] = framingSeconds;
  j["peak_rss_after_survey_bytes"] = peakAfterSurvey;
  j["first_frame_seconds"] = frames[0].seconds;
  j["first_picture_seconds"] = planSeconds + surveySeconds + framingSeconds + frames[0].seconds;
  std::vector<double> later;
  nlohmann::json rows = nlohmann::json::array();
  for (size_t i = 0; i < frames.size(); ++i) {
    rows.push_back(
        {{"seconds", frames[i].seconds}, {"parts_read", frames[i].partsRead}, {"peak_rss_bytes", frames[i].peakBytes}});
    if (i > 0) later.push_back(frames[i].seconds);
  }
  j["orbit"] = rows;
  j["orbit_median_seconds"] = later.empty() ? frames[0].seconds : median(later);
  const uint64_t peak = peakResidentBytes(); // before --in-core reads the whole step
  j["peak_rss_bytes"] = peak;
  j["load_average_at_end"] = loadAverage();

  if (o.inCore) {
    frame.camera = orbitCamera(target, 30.0, 25.0, 40.0, false, 0, views);
    j["in_core"] = inCoreComparison(o, lo, scene, frame, frames[0].seconds, first);
  }
  if (o.json)
    std::cout << j.dump(2) << "\n";
  else
    printBudgeted(j, o);
}

} // namespace exa::cli::bench
