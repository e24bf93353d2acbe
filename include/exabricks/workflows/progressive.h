// A view refined as the interactive front ends show one (the viewer's session, ParaView's
// representation): a draft first, at a fraction of the resolution and a lower sampling rate,
// its size adapted so that it renders within a time budget; then full-resolution passes up to
// the frame's samples per pixel, each added to the last (pass k uses frame index k, so the
// result equals an N-sample render of the frame). A new scene, frame, depth limit or device
// starts the refinement over, and the renderer rebuilds only what the change needs; a cancel flag
// ends a pass early. The device is chosen on the first scene (and on the first after the choice
// changes); where it cannot be used, or cannot draw a scene, the CPU draws that scene, and the
// next scene that differs tries the device again. A denoised frame (denoises()) renders its
// guide before its first pass, and shows the denoised picture of its passes once there is one.
#pragma once

#include "exabricks/core/error.h"
#include "exabricks/render/denoise.h"
#include "exabricks/render/frame_buffer.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/scene.h"

#include <optional>
#include <string>
#include <vector>

namespace exa {

/// How drafts are made.
struct DraftPolicy {
  double seconds = 0.035;  ///< the render time a draft aims at (its budget)
  float rateFactor = 0.5f; ///< a draft samples at the frame's rate times this
  int divisor = 4;         ///< the first draft's divisor of the resolution
  int maxDivisor = 16;     ///< the coarsest divisor
};

/// The divisor of the next draft of a `width` x `height` frame, after a draft of `draftPixels`
/// took `seconds` against a budget of `budget` seconds: as many pixels as the budget affords at
/// that time per pixel. The divisor stays while the time is within [0.5, 1.4] of the budget, so
/// that drafts do not flicker between two sizes.
int nextDraftDivisor(int divisor, int width, int height, double draftPixels, double seconds, double budget,
                     int maxDivisor);

/// What a view throws where its device, named other than "auto", cannot be used or cannot draw
/// the scene: the view then shows the scene on the CPU all the same (shown() holds it, passes go
/// on there), so that a caller may report the error and render on.
class DeviceFallbackError : public Error {
public:
  using Error::Error;
};

class ProgressiveView {
public:
  /// A view of `renderer` on `device` (one of deviceChoices(), as selectDevice takes it).
  ProgressiveView(Renderer& renderer, std::string device = "auto", DraftPolicy policy = {});
  ProgressiveView(const ProgressiveView&) = delete; ///< shown() refers to the view's own depth limit
  ProgressiveView& operator=(const ProgressiveView&) = delete;

  /// Shows `doc`: its scene on the renderer (what changed is rebuilt) and its frame. The
  /// refinement starts over when the scene, the frame or the renderer's device differs from the
  /// one shown; true then. Meshes are compared by their data; the frame's depth limit (if any) is
  /// copied, and its values count as part of the frame. Where the device cannot be used or cannot
  /// draw the scene, the renderer draws it on the CPU: under "auto" the log says why (once per
  /// reason); another choice throws DeviceFallbackError once the document is shown. A later scene
  /// that differs tries the device again.
  bool show(const SceneDocument& doc);
  /// Shows `scene` with the frame shown, as show() does; returns what the renderer rebuilt.
  SceneUpdate showScene(const Scene& scene);
  /// Shows `frame` with the scene shown, as show() does; true when the refinement starts over.
  bool showFrame(const Frame& frame);
  /// Starts the refinement over: the next pass is pass 0, and it clears buffer(), which holds
  /// the last passes until then (what a front end may keep showing).
  void restart();

  /// The draft frame of the view shown: the frame at the draft's divisor and rate, one sample.
  Frame draftFrame() const;
  /// Renders `draft` (a draftFrame(), perhaps with a depth limit) into `buffer` (resized) and
  /// adapts the next draft's divisor to `budget` seconds (the policy's when 0). False when
  /// cancelled.
  bool renderDraft(const Frame& draft, FrameBuffer& buffer, const PassControl& control, double budget = 0.0);
  /// Whether the last draft rendered shows the view shown now.
  bool draftIsCurrent() const { return !sceneKey_.empty() && !frameKey_.empty() && draftKey_ == key(); }

  /// Adds the next full-resolution pass to buffer(); false when cancelled (the pass is then not
  /// counted, and the refinement starts over) or when the view already holds its passes. With a
  /// noise target, the call that finds every tile at its passes adds none and returns true
  /// (complete() then holds).
  bool refine(const PassControl& control);
  /// Adds full-resolution passes until the view holds `passes`, which may go past
  /// targetPasses() (more samples of the same frame); false when cancelled, as refine(). A pass
  /// that throws starts the refinement over too.
  bool refineTo(int passes, const PassControl& control);
  /// The passes added up; after a restart, until the next pass, the passes from before it.
  const FrameBuffer& buffer() const { return buffer_; }
  /// The picture of the passes: their mean, or for a denoised frame the denoised picture (made at
  /// the end of each round to a noise target, and when the view is complete; until the first,
  /// the mean).
  void resolve(Image& out) const;
  /// Whether resolve() gives a denoised picture.
  bool showsDenoised() const { return guide_.has_value() && denoisedAt_ >= 0; }
  int passes() const { return passes_; }
  int targetPasses() const { return doc_.frame.samplesPerPixel; }
  /// Whether the view holds its passes: targetPasses(), or with a noise target
  /// (NoiseRounds::applies), every tile its own, at the target or at targetPasses(); passes()
  /// then counts the rounds of tiles added.
  bool complete() const;

  /// Moves the view to `device` with the next scene shown (show(), showScene()); the refinement
  /// starts over there where the renderer's device changes.
  void setDevice(std::string device);
  const std::string& device() const { return device_; }

  int draftDivisor() const { return divisor_; }
  const SceneDocument& shown() const { return doc_; }
  Renderer& renderer() { return renderer_; }

private:
  /// Shows `scene` (its update in `update`, unless null); true when the refinement starts over.
  /// Why the CPU draws it rather than the device chosen goes to `fallback` (empty otherwise).
  /// `frame` sizes spheres given in pixels (resolveParticleRadius).
  bool takeScene(const Scene& scene, const Frame& frame, SceneUpdate* update, std::string& fallback);
  /// Makes `scene` the renderer's on the device chosen, where it can draw it, its spheres sized
  /// for `frame`; `changed`: the scene differs from the one shown.
  SceneUpdate placeScene(const Scene& scene, const Frame& frame, bool changed, std::string& fallback);
  /// Says why the CPU draws the scene (`fallback`, unless empty), as show() describes.
  void reportFallback(const std::string& fallback);
  /// Holds `key` in `held`; true (and the refinement starts over) when it differs from the key held.
  bool changed(std::string& held, std::string key);
  std::string key() const { return deviceName(sceneDevice_) + sceneKey_ + frameKey_; }

  Renderer& renderer_;
  std::string device_;
  bool deviceChosen_ = false;        ///< the renderer was moved to device_ (else it is, with the next scene)
  bool deviceAwaitsScene_ = false;   ///< on the CPU for a scene device_ could not draw
  Device sceneDevice_ = Device::Cpu; ///< where the passes held were rendered
  std::string noted_;                ///< the last fallback the log told of
  DraftPolicy policy_;
  int divisor_;
  SceneDocument doc_;
  std::vector<float> depthLimit_;              ///< doc_.frame's depth limit, when it has one
  std::string sceneKey_, frameKey_, draftKey_; ///< the scene and frame shown, and those of the last draft
  float placedRadius_ = 0.f; ///< the particles' world radius the renderer holds (resolveParticleRadius)
  FrameBuffer buffer_;
  int passes_ = 0;
  NoiseRounds rounds_;                ///< with a noise target: the tiles that take the next pass
  bool noiseReached_ = false;         ///< every tile holds the passes its noise wants
  std::optional<DenoiseGuide> guide_; ///< a denoised frame's, from its first pass
  DenoiseMemo denoiseMemo_;           ///< the last filter of this refinement's buffer
  Image denoised_;                    ///< the last denoised picture of buffer_
  int denoisedAt_ = -1;               ///< passes_ when denoised_ was made (-1: none)
  bool cleared_ = false;              ///< buffer_ holds the passes counted (else it is cleared before the next)
};

} // namespace exa
