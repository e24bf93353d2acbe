#include "movie.h"

#include "exabricks/core/error.h"
#include "exabricks/documents/image.h"
#include "exabricks/render/camera_path.h"
#include "exabricks/render/legends.h"
#include "exabricks/workflows/encode.h"
#include "exabricks/workflows/frame_plan.h"

#include <cmath>
#include <filesystem>
#include <numeric>
#include <random>
#include <unistd.h>

namespace exa::view {

namespace fs = std::filesystem;
using json = nlohmann::json;

struct MovieMaker::Job {
  std::string id, dir, output;
  int frames = 0;
  std::atomic<int> done{0};
  std::atomic<bool> cancel{false};
  mutable std::mutex mutex;
  std::string state = "rendering"; ///< rendering, encoding, done, failed, cancelled
  std::string error;
  std::thread thread;

  void set(const std::string& s, const std::string& why = {}) {
    std::lock_guard<std::mutex> lock(mutex);
    state = s;
    error = why;
  }
  std::string get() const {
    std::lock_guard<std::mutex> lock(mutex);
    return state;
  }
};

namespace {

struct Cancelled {};

std::string randomId() {
  std::random_device device;
  std::string id;
  static const char* hex = "0123456789abcdef";
  for (int i = 0; i < 24; ++i)
    id += hex[device() & 15u];
  return id;
}

/// An orbit around the camera's look-at point at its distance: the box Camera::frame frames that
/// way, and the camera's azimuth and elevation as the start.
OrbitView orbitOf(const Camera& c) {
  const vec3d d = c.position - c.lookAt;
  const double distance = std::max(length(d), 1e-30);
  const double deg = 180.0 / M_PI;
  OrbitView o;
  o.azimuth = std::atan2(d.y, d.x) * deg;
  o.elevation = std::asin(std::clamp(d.z / distance, -1.0, 1.0)) * deg;
  o.fov = c.fovy;
  o.orthographic = c.orthographic;
  const double radius = c.orthographic ? 0.5 * c.orthoHeight : distance * std::sin(0.5 * c.fovy / deg);
  const vec3d half(radius / std::sqrt(3.0));
  o.target = box3d(c.lookAt - half, c.lookAt + half);
  return o;
}

} // namespace

MovieMaker::MovieMaker() {
  folder_ = (fs::temp_directory_path() / ("exabricks-view-" + std::to_string(::getpid()) + "-" + randomId())).string();
}

MovieMaker::~MovieMaker() {
  std::map<std::string, std::shared_ptr<Job>> jobs;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs.swap(jobs_);
  }
  for (auto& [id, job] : jobs) {
    job->cancel = true;
    if (job->thread.joinable()) job->thread.join();
  }
  std::error_code ec;
  fs::remove_all(folder_, ec);
}

bool MovieMaker::canEncode() { return !findProgram("ffmpeg").empty(); }

bool MovieMaker::busy() const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& [id, job] : jobs_) {
    const std::string s = job->get();
    if (s == "rendering" || s == "encoding") return true;
  }
  return false;
}

std::string MovieMaker::start(MovieInput input) {
  if (!canEncode())
    fail("ffmpeg is not installed on the machine the viewer runs on, so it cannot encode movies; install ffmpeg "
         "(or use `exabricks movie` with a folder for the frames)");
  if (busy()) fail("a movie is already being made: wait for it or cancel it");
  auto job = std::make_shared<Job>();
  job->id = randomId();
  job->dir = (fs::path(folder_) / job->id).string();
  job->output = (fs::path(job->dir) / "movie.mp4").string();
  job->frames = input.steps.size() > 1 ? int(input.steps.size()) : std::max(1, input.orbitFrames);
  fs::create_directories(fs::path(job->dir) / "frames");
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_[job->id] = job;
  }
  Job* j = job.get();
  job->thread = std::thread([this, j, in = std::move(input)] { run(*j, in); });
  return job->id;
}

void MovieMaker::run(Job& job, const MovieInput& in) {
  const std::string framesDir = (fs::path(job.dir) / "frames").string();
  // Each frame with the legends its scene asks for, labelled with the dataset it shows.
  auto write = [&](int i, const Scene& scene, const Frame& frame, const Model& model, const DatasetInfo& info,
                   const std::string& input, Image& image) {
    if (job.cancel) throw Cancelled{};
    LegendText text;
    text.dataset = legendDatasetLabel(input);
    drawLegends(scene, frame, model, info, text, image);
    writePng(framePath(framesDir, i), image, scene.keepAlpha, scene.background);
    ++job.done;
  };
  std::error_code ec;
  try {
    if (in.steps.size() > 1) {
      SeriesRenderer series(in.steps, in.series);
      const FramePlan plan = FramePlan::perStep(int(in.steps.size()));
      std::vector<int> frames(size_t(plan.frames));
      std::iota(frames.begin(), frames.end(), 0);
      series.renderFrames(plan, in.doc.scene, in.doc.frame, frames,
                          [&](int i, const SeriesStep& step, const Scene& s, const Frame& f, Image& image) {
                            write(i, s, f, *step.model, step.info, in.steps[size_t(step.index)], image);
                          });
    } else {
      FramePlan plan;
      plan.frames = job.frames;
      plan.orbit = orbitOf(in.doc.frame.camera);
      Renderer renderer(*in.current.model, in.current.dataset);
      renderer.setOptions(in.series.renderer);
      for (int i = 0; i < plan.frames; ++i) {
        if (job.cancel) throw Cancelled{};
        Scene s = in.doc.scene;
        Frame f = in.doc.frame;
        plan.view(i, s, f);
        renderer.setScene(s);
        Image image = renderer.render(f);
        write(i, s, f, *in.current.model, in.current.dataset, in.current.input, image);
      }
    }
    if (job.cancel) throw Cancelled{};
    job.set("encoding");
    MovieEncoding e;
    e.framesDir = framesDir;
    e.fps = in.fps;
    e.output = job.output;
    if (!encodeFrames(e)) fail("ffmpeg is not installed on the machine the viewer runs on: install it to make movies");
    fs::remove_all(framesDir, ec);
    job.set("done");
  } catch (const Cancelled&) {
    fs::remove_all(job.dir, ec);
    job.set("cancelled");
  } catch (const std::exception& e) {
    fs::remove_all(job.dir, ec);
    job.set("failed", e.what());
  }
}

json MovieMaker::status(const std::string& id) const {
  std::shared_ptr<Job> job;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = jobs_.find(id);
    if (it == jobs_.end()) return nullptr;
    job = it->second;
  }
  std::lock_guard<std::mutex> lock(job->mutex);
  json j{{"id", job->id}, {"state", job->state}, {"frames", job->frames}, {"done", job->done.load()}};
  if (!job->error.empty()) j["error"] = job->error;
  if (job->state == "done") {
    std::error_code ec;
    j["bytes"] = fs::file_size(job->output, ec);
    j["file"] = "/api/movie/file?id=" + job->id;
  }
  return j;
}

bool MovieMaker::cancel(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = jobs_.find(id);
  if (it == jobs_.end()) return false;
  it->second->cancel = true;
  return true;
}

std::string MovieMaker::file(const std::string& id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = jobs_.find(id);
  if (it == jobs_.end() || it->second->get() != "done") return {};
  return it->second->output;
}

} // namespace exa::view
