// The render side of the viewer: one render thread, one request in flight, the newest request
// wins. Independent of HTTP.
#pragma once

#include "exabricks/core/image.h"
#include "exabricks/render/legends.h"
#include "exabricks/render/renderer.h"
#include "exabricks/workflows/progressive.h"
#include "exabricks/workflows/streamed.h"
#include "server.h"

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace exa::view {

/// A frame ready to send: its statistics and JPEG bytes, or an error message for the request.
struct PublishedFrame {
  FrameInfo info;
  std::string jpeg;
  std::string error;
};

class Session {
public:
  /// `legends`: what the scene's legends write of the dataset (they are drawn into every frame).
  /// `parts`: the whole step held in parts (ViewContent::parts), from which every still view's
  /// last frame is drawn; `budget` is said with it.
  Session(std::shared_ptr<const Model> model, const DatasetInfo& dataset, const ServerOptions& options,
          LegendText legends = {}, std::shared_ptr<StreamedStep> parts = nullptr, uint64_t budget = 0);
  ~Session();

  /// Renders another dataset (a series' step) from the next request on; the request in flight is
  /// cancelled.
  void setModel(std::shared_ptr<const Model> model, const DatasetInfo& dataset, LegendText legends = {});
  /// Where the particles of the dataset shown come from (its input; empty: none). They are read
  /// when a scene first shows them, and again after this changes.
  void setParticleInput(std::string input);
  /// What the frames say of the data they show ("coarse levels ..."; empty: all of it).
  void setDataNote(std::string note);
  /// Accepts a validated scene document; returns its request number. Cancels the request in
  /// flight: from now on no frame of an older request is published.
  uint64_t submit(const SceneDocument& doc, bool interactive);
  /// Waits until a frame newer than `afterSequence` is published, or `timeoutMs` passes, or the
  /// session stops; null when none.
  std::shared_ptr<const PublishedFrame> waitFrame(uint64_t afterSequence, int timeoutMs);
  /// The latest refined (full-resolution) image, the request it belongs to and its passes.
  struct Snapshot {
    std::shared_ptr<const Image> image;
    uint64_t request = 0;
    int passes = 0, targetPasses = 0;
    bool final = false; ///< the request's last frame (a noise target may end it below targetPasses)
    vec3f background{0.f};
    bool keepAlpha = false;
  };
  Snapshot snapshot() const;
  /// Waits until request `id` has its full-resolution image refined to the frame's samples per
  /// pixel (what Save PNG saves: the view on screen once refined), or `timeoutMs` passes.
  enum class Wait { Ready, Superseded, Draft, Failed, Unknown, TimedOut, Stopped };
  Wait waitSnapshot(uint64_t id, int timeoutMs, Snapshot& out) const;
  /// The document of the newest request (empty before the first).
  std::optional<SceneDocument> current() const;
  void stop();

private:
  struct Request {
    uint64_t id = 0;
    SceneDocument doc;
    bool interactive = false;
    std::chrono::steady_clock::time_point accepted;
  };
  void loop();
  void serve(const Request& request);
  bool superseded(uint64_t id) const;
  void publish(const Request& request, const Image& image, FrameInfo info, bool keepImage, int quality);
  void publishError(const Request& request, const std::string& message);
  /// The view's last frame from every level, drawn part by part (parts_).
  void serveParts(const Request& request, FrameInfo info, PassControl& control);

  std::shared_ptr<const Model> model_;
  DatasetInfo dataset_;
  LegendText legends_;
  std::unique_ptr<Renderer> renderer_;
  std::unique_ptr<ProgressiveView> view_;     ///< drafts and refinement of renderer_'s frames
  std::shared_ptr<const Model> pendingModel_; ///< the dataset of the next request (setModel)
  DatasetInfo pendingDataset_;
  LegendText pendingLegends_;
  std::string dataNote_;                         ///< FrameInfo::data of the frames (guarded by mutex_)
  std::string particleInput_;                    ///< guarded by mutex_
  bool particlesRead_ = false;                   ///< particles_ came from particleInput_ (guarded by mutex_)
  std::shared_ptr<const ParticleSet> particles_; ///< the render thread's
  /// The particles a request's scene shows, read once per input, handed to the renderers.
  void provideParticles(const Scene& scene);
  ServerOptions options_;
  mutable std::mutex mutex_;
  mutable std::condition_variable requestReady_, frameReady_;
  std::optional<Request> pending_; ///< newest request not yet taken by the render thread
  uint64_t newest_ = 0;            ///< number of the newest accepted request
  bool newestInteractive_ = false; ///< it asked for a draft only (the user is dragging)
  uint64_t failed_ = 0;            ///< the newest request that ended in an error
  std::optional<SceneDocument> currentDoc_;
  std::atomic<bool> cancel_{false};
  bool stopping_ = false;
  uint64_t sequence_ = 0;
  std::shared_ptr<const PublishedFrame> latest_;
  Snapshot snapshot_;
  FrameBuffer draftBuffer_;
  std::shared_ptr<StreamedStep> parts_; ///< used by the render thread only
  uint64_t budget_ = 0;
  std::thread thread_;
};

} // namespace exa::view
