// A frame's passes (Renderer::renderSampled): a fixed count, or each tile's passes until the
// noise they estimate reaches the frame's target.
#include "exabricks/render/renderer.h"

#include "exabricks/core/error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace exa {

void PassControl::selected(int tileCount, std::vector<int>& tiles) const {
  tiles.clear();
  const int end = tileEnd < 0 ? tileCount : std::min(tileEnd, tileCount);
  for (int tile = std::max(0, tileBegin); tile < end; tile += std::max(1, tileStride))
    if (!tileMask || (*tileMask)[size_t(tile)]) tiles.push_back(tile);
}

bool NoiseRounds::applies(const Scene& scene, const Frame& frame) {
  return frame.noiseTarget > 0.f && frame.samplesPerPixel > 1 &&
         scene.integration.integrator == Integrator::PathTrace && scene.debug == DebugView::None;
}

void NoiseRounds::start(const Frame& frame, const FrameBuffer& buffer, const PassControl& control) {
  const int tiles = buffer.tileCount();
  goal_.assign(size_t(tiles), 0);
  mask_.assign(size_t(tiles), 0);
  std::vector<int> selected;
  control.selected(tiles, selected);
  for (int t : selected)
    goal_[size_t(t)] =
        uint32_t(std::min(frame.samplesPerPixel, frame.denoise ? kDenoisedFirstPasses : kNoiseFirstPasses));
  tellPlanned(control);
}

void NoiseRounds::tellPlanned(const PassControl& control) const {
  if (!control.planned) return;
  uint64_t sum = 0;
  for (uint32_t g : goal_)
    sum += g;
  control.planned(sum);
}

bool denoises(const Scene& scene, const Frame& frame) {
  return frame.denoise && scene.integration.integrator == Integrator::PathTrace && scene.debug == DebugView::None;
}

bool NoiseRounds::next(const Frame& frame, const FrameBuffer& buffer, const vec3f& background, PassControl& control,
                       int& frameIndex, const TileNoiseEstimate* estimate) {
  const int tiles = int(goal_.size());
  const uint32_t most = uint32_t(frame.samplesPerPixel), none = std::numeric_limits<uint32_t>::max();
  for (;;) {
    // Pass m for the tiles that hold m passes and want more, the fewest first.
    uint32_t fewest = none;
    for (int t = 0; t < tiles; ++t)
      if (buffer.tilePasses(t) < goal_[size_t(t)]) fewest = std::min(fewest, buffer.tilePasses(t));
    if (fewest != none) {
      for (int t = 0; t < tiles; ++t)
        mask_[size_t(t)] = buffer.tilePasses(t) == fewest && fewest < goal_[size_t(t)];
      control.tileMask = &mask_;
      frameIndex = int(fewest);
      return true;
    }
    // Every tile holds its passes. Those above the target: the passes their noise, falling as
    // 1/sqrt(n), predicts with 5 % to spare, between a sixteenth more and twice as many (the
    // estimate is noisy too: a tile far above the target is estimated again on the way).
    bool more = false;
    if (estimate) {
      estimate->measure(buffer, noise_);
      if (int(noise_.size()) != tiles) fail("a noise estimate gave ", noise_.size(), " tiles of ", tiles);
    }
    uint64_t added = 0;
    for (int t = 0; t < tiles; ++t) {
      const uint32_t n = buffer.tilePasses(t);
      if (goal_[size_t(t)] == 0 || n >= most) continue;
      const float noise = estimate ? noise_[size_t(t)] : buffer.tileNoise(t, background);
      if (noise <= frame.noiseTarget) continue;
      const double ratio = double(noise) / double(frame.noiseTarget);
      const double predicted = std::ceil(1.05 * double(n) * ratio * ratio);
      const double next = std::clamp(predicted, double(n + std::max(1u, n / 16)), 2.0 * double(n));
      goal_[size_t(t)] = uint32_t(std::min(double(most), next));
      added += goal_[size_t(t)] - n;
      more = true;
    }
    // A denoised estimate filters the whole frame however few tiles it measures again: where the
    // passes planned come to less than an eighth of one pass over the frame, the tiles that want
    // more take four times their passes (their noise halves), so that fewer rounds (and filters)
    // follow.
    if (estimate && more && added * 8 < uint64_t(tiles))
      for (int t = 0; t < tiles; ++t)
        if (goal_[size_t(t)] > buffer.tilePasses(t))
          goal_[size_t(t)] = std::min(most, std::max(goal_[size_t(t)], 4 * buffer.tilePasses(t)));
    if (estimate && estimate->agree) more = estimate->agree(more); // another round for all, or none
    if (!more) return false;
    tellPlanned(control);
  }
}

bool Renderer::renderSampled(const Frame& frame, FrameBuffer& buffer, const PassControl& control,
                             const TileNoiseEstimate* estimate) const {
  Frame pass = frame;
  if (!NoiseRounds::applies(scene(), frame)) {
    for (int k = 0; k < frame.samplesPerPixel; ++k) {
      pass.frameIndex = k;
      if (!renderPass(pass, buffer, control)) return false;
    }
    return true;
  }
  NoiseRounds rounds;
  rounds.start(frame, buffer, control);
  PassControl some = control;
  while (rounds.next(frame, buffer, scene().background, some, pass.frameIndex, estimate))
    if (!renderPass(pass, buffer, some)) return false;
  return true;
}

} // namespace exa
