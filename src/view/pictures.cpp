#include "pictures.h"

#include "exabricks/io/particles.h"

#include "exabricks/core/error.h"

#include <atomic>
#include <cctype>
#include <filesystem>
#include <thread>
#include <unistd.h>

namespace exa::view {

namespace fs = std::filesystem;
using json = nlohmann::json;

struct PictureMaker::PictureJob : Job {
  int passes = 1;
  std::atomic<uint64_t> tilesDone{0}, tilesAll{1};
};

namespace {

std::string fileWord(const std::string& text) {
  std::string out;
  for (char c : text)
    out += std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_' ? c : '_';
  const size_t b = out.find_first_not_of("._"), e = out.find_last_not_of("._");
  return b == std::string::npos ? std::string() : out.substr(b, e - b + 1);
}

} // namespace

std::string pictureName(const std::string& dataset, const std::string& field, int width, int height,
                        ImageFormat format) {
  std::string stem = fs::path(dataset).filename().string();
  if (stem.empty()) stem = fs::path(dataset).parent_path().filename().string(); // "run/plt00100/"
  stem = fileWord(fs::path(stem).stem().string());
  const char* ext = format == ImageFormat::Exr ? ".exr" : format == ImageFormat::Pfm ? ".pfm" : ".png";
  const std::string f = fileWord(field);
  return strCat(stem.empty() ? "exabricks" : stem, f.empty() ? "" : "-", f, "-", width, "x", height, ext);
}

PictureMaker::PictureMaker() {
  folder_ =
      (fs::temp_directory_path() / ("exabricks-pictures-" + std::to_string(::getpid()) + "-" + randomHex(24))).string();
}

PictureMaker::~PictureMaker() {
  jobs_.stopAll();
  std::error_code ec;
  fs::remove_all(folder_, ec);
}

bool PictureMaker::busy() const {
  return jobs_.any([](const std::string& s) { return s == "rendering"; });
}

std::string PictureMaker::start(PictureInput input) {
  if (busy()) fail("a picture is already being rendered: wait for it or cancel it");
  auto job = std::make_shared<PictureJob>();
  job->name = input.name;
  job->passes = input.doc.frame.samplesPerPixel;
  const fs::path dir = fs::path(folder_) / job->id;
  fs::create_directories(dir);
  job->path = (dir / input.name).string();
  jobs_.add(job);
  PictureJob* j = job.get();
  job->thread = std::thread([this, j, in = std::move(input)] { run(*j, in); });
  return job->id;
}

void PictureMaker::run(PictureJob& job, const PictureInput& in) {
  std::error_code ec;
  try {
    Renderer renderer(*in.step.model, in.step.dataset);
    renderer.setOptions(in.renderer);
    if (in.doc.scene.particles.show)
      renderer.setParticles(readParticlesIfAny(in.step.input, in.doc.scene.particles.species));
    const Frame& frame = in.doc.frame;
    Scene scene = in.doc.scene;
    resolveParticleRadius(scene, frame);
    renderer.setScene(scene);
    FrameBuffer buffer(frame.width, frame.height);
    job.tilesAll = uint64_t(buffer.tileCount()) * uint64_t(frame.samplesPerPixel);
    PassControl control;
    control.cancel = &job.cancel;
    control.progress = [&](uint64_t, uint64_t) { ++job.tilesDone; };
    if (!renderer.renderPasses(frame, buffer, frame.samplesPerPixel, control)) {
      fs::remove_all(fs::path(job.path).parent_path(), ec);
      job.set("cancelled");
      return;
    }
    Image image = buffer.resolve();
    drawLegends(in.doc.scene, frame, *in.step.model, in.step.dataset, in.legends, image);
    writeImage(job.path, image, in.format, in.doc.scene.keepAlpha, in.doc.scene.background);
    job.set("done");
  } catch (const std::exception& e) {
    fs::remove_all(fs::path(job.path).parent_path(), ec);
    job.set("failed", e.what());
  }
}

json PictureMaker::status(const std::string& id) const {
  const std::shared_ptr<PictureJob> job = jobs_.find(id);
  if (!job) return nullptr;
  json j = job->describe("picture");
  j["name"] = job->name;
  j["passes"] = job->passes;
  j["tiles"] = job->tilesAll.load();
  j["done"] = job->tilesDone.load();
  return j;
}

bool PictureMaker::cancel(const std::string& id) { return jobs_.cancel(id); }

std::pair<std::string, std::string> PictureMaker::file(const std::string& id) const { return jobs_.finishedFile(id); }

} // namespace exa::view
