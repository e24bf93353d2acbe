#include "movie.h"

#include "exabricks/io/particles.h"

#include "exabricks/core/error.h"
#include "exabricks/documents/image.h"
#include "exabricks/render/camera_path.h"
#include "exabricks/render/legends.h"
#include "exabricks/workflows/encode.h"
#include "exabricks/workflows/frame_plan.h"

#include <cmath>
#include <filesystem>
#include <numeric>
#include <unistd.h>

namespace exa::view {

namespace fs = std::filesystem;
using json = nlohmann::json;

struct MovieMaker::MovieJob : Job {
  std::string dir;
  int frames = 0;
  std::atomic<int> done{0};
};

namespace {

struct Cancelled {};

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
  folder_ =
      (fs::temp_directory_path() / ("exabricks-view-" + std::to_string(::getpid()) + "-" + randomHex(24))).string();
}

MovieMaker::~MovieMaker() {
  jobs_.stopAll();
  std::error_code ec;
  fs::remove_all(folder_, ec);
}

int heldFrames(int steps, double fps) {
  const int hold = int(std::ceil(4.0 * fps / double(std::max(steps, 1))));
  return std::clamp(hold, 1, std::max(1, int(std::ceil(fps))));
}

bool MovieMaker::canEncode() { return !findProgram("ffmpeg").empty(); }

bool MovieMaker::busy() const {
  return jobs_.any([](const std::string& s) { return s == "rendering" || s == "encoding"; });
}

std::string MovieMaker::start(MovieInput input) {
  if (!canEncode())
    fail("ffmpeg is not installed on the machine the viewer runs on, so it cannot encode movies; install ffmpeg "
         "(or use `exabricks movie` with a folder for the frames)");
  if (busy()) fail("a movie is already being made: wait for it or cancel it");
  auto job = std::make_shared<MovieJob>();
  job->dir = (fs::path(folder_) / job->id).string();
  job->path = (fs::path(job->dir) / "movie.mp4").string();
  job->name = "exabricks.mp4";
  job->frames = input.steps.size() > 1 ? int(input.steps.size()) : std::max(1, input.orbitFrames);
  fs::create_directories(fs::path(job->dir) / "frames");
  jobs_.add(job);
  MovieJob* j = job.get();
  job->thread = std::thread([this, j, in = std::move(input)] { run(*j, in); });
  return job->id;
}

void MovieMaker::run(MovieJob& job, const MovieInput& in) {
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
      // Each step rendered once and held for several frames, so that a short series plays for a
      // visible time.
      SeriesOptions so = in.series;
      if (in.doc.scene.particles.show) so.particles = in.doc.scene.particles.species;
      SeriesRenderer series(in.steps, so);
      const FramePlan plan = FramePlan::perStep(int(in.steps.size()));
      const int hold = heldFrames(plan.steps, in.fps);
      std::vector<int> frames(size_t(plan.frames));
      std::iota(frames.begin(), frames.end(), 0);
      series.renderFrames(plan, in.doc.scene, in.doc.frame, frames,
                          [&](int i, const SeriesStep& step, const Scene& s, const Frame& f, Image& image) {
                            write(i * hold, s, f, *step.model, step.info, in.steps[size_t(step.index)], image);
                            for (int k = 1; k < hold; ++k)
                              fs::copy_file(framePath(framesDir, i * hold), framePath(framesDir, i * hold + k),
                                            fs::copy_options::overwrite_existing);
                          });
    } else {
      FramePlan plan;
      plan.frames = job.frames;
      plan.orbit = orbitOf(in.doc.frame.camera);
      Renderer renderer(*in.current.model, in.current.dataset);
      renderer.setOptions(in.series.renderer);
      if (in.doc.scene.particles.show)
        renderer.setParticles(readParticlesIfAny(in.current.input, in.doc.scene.particles.species));
      for (int i = 0; i < plan.frames; ++i) {
        if (job.cancel) throw Cancelled{};
        Scene s = in.doc.scene;
        Frame f = in.doc.frame;
        plan.view(i, s, f);
        Scene placed = s;
        resolveParticleRadius(placed, f);
        renderer.setScene(placed);
        Image image = renderer.render(f);
        write(i, s, f, *in.current.model, in.current.dataset, in.current.input, image);
      }
    }
    if (job.cancel) throw Cancelled{};
    job.set("encoding");
    MovieEncoding e;
    e.framesDir = framesDir;
    e.fps = in.fps;
    e.output = job.path;
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
  const std::shared_ptr<MovieJob> job = jobs_.find(id);
  if (!job) return nullptr;
  json j = job->describe("movie");
  j["frames"] = job->frames;
  j["done"] = job->done.load();
  return j;
}

bool MovieMaker::cancel(const std::string& id) { return jobs_.cancel(id); }

std::pair<std::string, std::string> MovieMaker::file(const std::string& id) const { return jobs_.finishedFile(id); }

} // namespace exa::view
