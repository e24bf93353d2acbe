#include "exabricks/workflows/progressive.h"

#include <algorithm>
#include <cmath>

namespace exa {

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
    : renderer_(renderer), device_(std::move(device)), policy_(policy), divisor_(policy.divisor) {}

bool ProgressiveView::show(const SceneDocument& doc) {
  setSceneOnDevice(renderer_, doc.scene, device_, deviceChosen_);
  std::string key = writeSceneJson(doc);
  doc_ = doc;
  if (key == key_) return false;
  key_ = std::move(key);
  restart();
  return true;
}

void ProgressiveView::restart() {
  passes_ = 0;
  buffer_.resize(doc_.frame.width, doc_.frame.height);
  buffer_.clear();
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
  draftKey_ = key_;
  divisor_ = nextDraftDivisor(divisor_, doc_.frame.width, doc_.frame.height, double(draft.width) * draft.height,
                              buffer.stats().seconds, budget > 0.0 ? budget : policy_.seconds, policy_.maxDivisor);
  return true;
}

bool ProgressiveView::refine(const PassControl& control) {
  if (complete()) return false;
  Frame pass = doc_.frame;
  pass.frameIndex = passes_;
  if (!renderer_.renderPass(pass, buffer_, control)) {
    // A cancelled pass leaves part of its tiles added: the refinement starts over.
    restart();
    return false;
  }
  ++passes_;
  return true;
}

} // namespace exa
