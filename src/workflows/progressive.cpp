#include "exabricks/workflows/progressive.h"

#include "exabricks/core/log.h"
#include "exabricks/render/scene_vocabulary.h"

#include <algorithm>
#include <cmath>

namespace exa {
namespace {

/// The key of a scene: its JSON without the meshes' data, which sameMeshData compares.
std::string sceneKeyOf(const Scene& scene) {
  SceneDocument d;
  d.scene = scene;
  for (SceneMesh& m : d.scene.meshes)
    m.mesh.reset();
  return exactSceneJson(d);
}

/// Whether the meshes of `a` and `b` hold the same data: the same meshes, or equal ones.
bool sameMeshData(const std::vector<SceneMesh>& a, const std::vector<SceneMesh>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    const TriangleMesh* x = a[i].mesh.get();
    const TriangleMesh* y = b[i].mesh.get();
    if (x == y) continue;
    if (!x || !y || x->vertices != y->vertices || x->triangles != y->triangles) return false;
  }
  return true;
}

/// Throws exa::Error, as resolveDevice does, where `device` is none of deviceChoices().
void checkDeviceChoice(const std::string& device) {
  const std::vector<std::string>& choices = deviceChoices();
  if (std::find(choices.begin(), choices.end(), device) == choices.end()) resolveDevice(device);
}

} // namespace

int nextDraftDivisor(int divisor, int width, int height, double draftPixels, double seconds, double budget,
                     int maxDivisor) {
  if (!(seconds > 0.0) || !(budget > 0.0)) return divisor;
  const double ratio = seconds / budget;
  if (ratio >= 0.5 && ratio <= 1.4) return divisor;
  const double affordable = draftPixels / ratio;
  const double next = std::sqrt(double(width) * double(height) / std::max(affordable, 1.0));
  return std::clamp(int(std::ceil(next)), 1, maxDivisor);
}

ProgressiveView::ProgressiveView(Renderer& renderer, std::string device, DraftPolicy policy)
    : renderer_(renderer), device_(std::move(device)), policy_(policy), divisor_(policy.divisor) {
  checkDeviceChoice(device_);
}

bool ProgressiveView::show(const SceneDocument& doc) {
  std::string fallback;
  // Spheres sized in pixels take the document's frame: showFrame then keeps them.
  const bool sceneChanged = takeScene(doc.scene, doc.frame, nullptr, fallback);
  doc_.input = doc.input;
  doc_.hasCamera = doc.hasCamera;
  doc_.path = doc.path;
  const bool frameChanged = showFrame(doc.frame);
  reportFallback(fallback);
  return sceneChanged || frameChanged;
}

SceneUpdate ProgressiveView::showScene(const Scene& scene) {
  SceneUpdate update;
  std::string fallback;
  takeScene(scene, doc_.frame, &update, fallback);
  reportFallback(fallback);
  return update;
}

void ProgressiveView::setDevice(std::string device) {
  if (device == device_) return;
  checkDeviceChoice(device);
  device_ = std::move(device);
  deviceChosen_ = false;
  deviceAwaitsScene_ = false;
}

bool ProgressiveView::takeScene(const Scene& scene, const Frame& frame, SceneUpdate* update, std::string& fallback) {
  std::string sceneKey = sceneKeyOf(scene);
  const bool same = sceneKey == sceneKey_ && sameMeshData(doc_.scene.meshes, scene.meshes);
  const SceneUpdate u = placeScene(scene, frame, !same, fallback);
  if (update) *update = u;
  doc_.scene = scene;
  const Device device = renderer_.device();
  if (same && device == sceneDevice_) return false;
  sceneKey_ = std::move(sceneKey);
  sceneDevice_ = device;
  restart();
  return true;
}

SceneUpdate ProgressiveView::placeScene(const Scene& given, const Frame& frame, bool changed, std::string& fallback) {
  Scene scene = given;
  resolveParticleRadius(scene, frame);
  placedRadius_ = scene.particles.radius;
  SceneUpdate u;
  try {
    u = renderer_.setScene(scene);
  } catch (const Error& e) {
    if (renderer_.device() == Device::Cpu) throw;
    // The device lacks what this scene needs: the CPU draws it, and where the device is the one
    // chosen, the next scene tries it again (else the choice follows).
    renderer_.setDevice(Device::Cpu);
    if (deviceChosen_) {
      deviceAwaitsScene_ = true;
      fallback = e.what();
      return renderer_.setScene(scene);
    }
    u = renderer_.setScene(scene);
  }
  if (deviceChosen_ && !(deviceAwaitsScene_ && changed)) return u;
  deviceChosen_ = true;
  deviceAwaitsScene_ = false;
  Device wanted = Device::Cpu;
  try {
    wanted = resolveDevice(device_);
    renderer_.setDevice(wanted);
    noted_.clear();
  } catch (const Error& e) {
    renderer_.setDevice(Device::Cpu);
    deviceAwaitsScene_ = wanted != Device::Cpu; // the device is there: the scene is why
    fallback = e.what();
  }
  return u;
}

void ProgressiveView::reportFallback(const std::string& fallback) {
  if (fallback.empty()) return;
  const std::string message = strCat("device ", device_, ": rendering on the CPU, since ", fallback);
  if (device_ != "auto") throw DeviceFallbackError(message);
  if (message != noted_) logNote(message);
  noted_ = message;
}

bool ProgressiveView::showFrame(const Frame& frame) {
  SceneDocument d;
  d.input = doc_.input;
  d.hasCamera = doc_.hasCamera;
  d.path = doc_.path;
  d.frame = frame;
  d.frame.depthLimit = nullptr;
  std::string key = exactSceneJson(d);
  if (frame.depthLimit) {
    if (frame.depthLimit != depthLimit_.data()) // not the copy shown() refers to
      depthLimit_.assign(frame.depthLimit, frame.depthLimit + size_t(frame.width) * size_t(frame.height));
    key += frame.depthLimitPlanar ? "planar depth limit " : "depth limit ";
    key.append(reinterpret_cast<const char*>(depthLimit_.data()), depthLimit_.size() * sizeof(float));
  } else {
    depthLimit_.clear();
  }
  doc_.frame = frame;
  doc_.frame.depthLimit = frame.depthLimit ? depthLimit_.data() : nullptr;
  if (doc_.scene.particles.show && doc_.scene.particles.radiusPixels > 0.f) {
    // Spheres sized in pixels follow the camera's distance to its look-at point.
    Scene placed = doc_.scene;
    resolveParticleRadius(placed, doc_.frame);
    if (placed.particles.radius != placedRadius_) {
      std::string fallback;
      placeScene(doc_.scene, doc_.frame, false, fallback);
      reportFallback(fallback);
    }
  }
  return changed(frameKey_, std::move(key));
}

bool ProgressiveView::changed(std::string& held, std::string key) {
  if (key == held) return false;
  held = std::move(key);
  restart();
  return true;
}

void ProgressiveView::restart() {
  passes_ = 0;
  cleared_ = false;
  rounds_ = NoiseRounds();
  noiseReached_ = false;
  guide_.reset();
  denoiseMemo_ = DenoiseMemo();
  denoisedAt_ = -1;
}

void ProgressiveView::resolve(Image& out) const {
  if (showsDenoised())
    out = denoised_;
  else
    buffer_.resolve(out);
}

bool ProgressiveView::complete() const {
  return NoiseRounds::applies(doc_.scene, doc_.frame) ? noiseReached_ : passes_ >= targetPasses();
}

Frame ProgressiveView::draftFrame() const {
  Frame draft = doc_.frame.preview(divisor_, doc_.frame.rate * policy_.rateFactor);
  draft.samplesPerPixel = 1;
  draft.frameIndex = 0;
  return draft;
}

bool ProgressiveView::renderDraft(const Frame& draft, FrameBuffer& buffer, const PassControl& control, double budget) {
  buffer.resize(draft.width, draft.height);
  if (!renderer_.renderPass(draft, buffer, control)) return false;
  draftKey_ = key();
  divisor_ = nextDraftDivisor(divisor_, doc_.frame.width, doc_.frame.height, double(draft.width) * draft.height,
                              buffer.stats().seconds, budget > 0.0 ? budget : policy_.seconds, policy_.maxDivisor);
  return true;
}

bool ProgressiveView::refine(const PassControl& control) {
  if (complete()) return false;
  return refineTo(passes_ + 1, control);
}

bool ProgressiveView::refineTo(int passes, const PassControl& control) {
  if (passes_ >= passes) return true;
  if (!cleared_) {
    buffer_.resize(doc_.frame.width, doc_.frame.height); // cleared
    cleared_ = true;
  }
  const vec3f background = doc_.scene.background;
  if (denoises(doc_.scene, doc_.frame) && !guide_) {
    try {
      guide_ = renderDenoiseGuide(renderer_, doc_.frame);
    } catch (...) {
      restart();
      throw;
    }
  }
  TileNoiseEstimate estimate; // the denoised picture's noise, keeping that picture
  estimate.measure = [&](const FrameBuffer& buffer, std::vector<float>& noise) {
    denoised_ = denoise(buffer, *guide_, background, &noise, {}, &denoiseMemo_);
    denoisedAt_ = passes_;
  };
  Frame pass = doc_.frame;
  const bool toNoise = NoiseRounds::applies(doc_.scene, doc_.frame);
  while (passes_ < passes && !(toNoise && noiseReached_)) {
    // With a noise target, a pass is the next round of the tiles that want more.
    PassControl some = control;
    pass.frameIndex = passes_;
    if (toNoise) {
      if (!rounds_.started()) rounds_.start(pass, buffer_, control);
      noiseReached_ = !rounds_.next(pass, buffer_, background, some, pass.frameIndex, guide_ ? &estimate : nullptr);
      if (noiseReached_) break;
    }
    bool rendered = false;
    try {
      const bool cancelled = control.cancel && control.cancel->load(std::memory_order_relaxed);
      rendered = !cancelled && renderer_.renderPass(pass, buffer_, some);
    } catch (...) {
      restart();
      throw;
    }
    if (!rendered) {
      // A cancelled pass leaves part of its tiles added: the refinement starts over.
      restart();
      return false;
    }
    ++passes_;
  }
  if (guide_ && complete() && denoisedAt_ != passes_) {
    denoised_ = denoise(buffer_, *guide_, background, nullptr, {}, &denoiseMemo_);
    denoisedAt_ = passes_;
  }
  return true;
}

} // namespace exa
