#include "session.h"

#include "exabricks/io/particles.h"

#include "exabricks/amr/model.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/documents/image.h"

#include <turbojpeg.h>

#include <algorithm>
#include <cmath>

namespace exa::view {

namespace {

double secondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

std::string encodeJpeg(const Image& image, const vec3f& background, int quality, bool fullChroma) {
  const std::vector<unsigned char> rgb = toSrgb8(image, background);
  tjhandle handle = tjInitCompress();
  if (!handle) fail("JPEG encoder: cannot initialise libturbojpeg");
  unsigned char* out = nullptr;
  unsigned long size = 0;
  const int rc = tjCompress2(handle, rgb.data(), image.width, 0, image.height, TJPF_RGB, &out, &size,
                             fullChroma ? TJSAMP_444 : TJSAMP_420, quality, TJFLAG_FASTDCT);
  std::string bytes;
  if (rc == 0) bytes.assign(reinterpret_cast<const char*>(out), size);
  const std::string message = rc == 0 ? std::string() : std::string(tjGetErrorStr2(handle));
  tjFree(out);
  tjDestroy(handle);
  if (rc != 0) fail("JPEG encoding failed: ", message);
  return bytes;
}

} // namespace

Session::Session(std::shared_ptr<const Model> model, const DatasetInfo& dataset, const ServerOptions& options,
                 LegendText legends, std::shared_ptr<StreamedStep> parts, uint64_t budget)
    : model_(std::move(model)), dataset_(dataset), legends_(std::move(legends)),
      renderer_(std::make_unique<Renderer>(*model_, dataset_)), options_(options), parts_(std::move(parts)),
      budget_(budget) {
  // Drafts aim at 35 ms, so that one reaches the screen within about 100 ms.
  view_ = std::make_unique<ProgressiveView>(*renderer_, options_.device, DraftPolicy{});
  thread_ = std::thread([this] { loop(); });
}

Session::~Session() { stop(); }

void Session::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    cancel_ = true;
  }
  requestReady_.notify_all();
  frameReady_.notify_all();
  if (thread_.joinable() && thread_.get_id() != std::this_thread::get_id()) thread_.join();
}

void Session::setModel(std::shared_ptr<const Model> model, const DatasetInfo& dataset, LegendText legends) {
  std::lock_guard<std::mutex> lock(mutex_);
  pendingModel_ = std::move(model);
  pendingDataset_ = dataset;
  pendingLegends_ = std::move(legends);
  cancel_ = true;
}

void Session::setParticleInput(std::string input) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (input == particleInput_) return;
  particleInput_ = std::move(input);
  particlesRead_ = false;
}

void Session::provideParticles(const Scene& scene) {
  std::string input;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!scene.particles.show || particlesRead_) return;
    input = particleInput_;
    particlesRead_ = true;
  }
  particles_ = readParticlesIfAny(input);
  renderer_->setParticles(particles_);
  if (parts_) parts_->setParticles(particles_);
}

void Session::setDataNote(std::string note) {
  std::lock_guard<std::mutex> lock(mutex_);
  dataNote_ = std::move(note);
}

uint64_t Session::submit(const SceneDocument& doc, bool interactive) {
  std::lock_guard<std::mutex> lock(mutex_);
  Request r;
  r.id = ++newest_;
  r.doc = doc;
  r.interactive = interactive;
  r.accepted = std::chrono::steady_clock::now();
  currentDoc_ = doc;
  newestInteractive_ = interactive;
  pending_ = std::move(r);
  cancel_ = true; // the pass in flight stops before its next tile
  requestReady_.notify_all();
  frameReady_.notify_all(); // a wait for an older request's image ends now
  return newest_;
}

bool Session::superseded(uint64_t id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stopping_ || id != newest_;
}

std::shared_ptr<const PublishedFrame> Session::waitFrame(uint64_t afterSequence, int timeoutMs) {
  std::unique_lock<std::mutex> lock(mutex_);
  frameReady_.wait_for(lock, std::chrono::milliseconds(timeoutMs),
                       [&] { return stopping_ || (latest_ && latest_->info.sequence > afterSequence); });
  if (latest_ && latest_->info.sequence > afterSequence) return latest_;
  return nullptr;
}

Session::Snapshot Session::snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return snapshot_;
}

Session::Wait Session::waitSnapshot(uint64_t id, int timeoutMs, Snapshot& out) const {
  std::unique_lock<std::mutex> lock(mutex_);
  auto complete = [&] {
    return snapshot_.image && snapshot_.request == id &&
           (snapshot_.final || snapshot_.passes >= snapshot_.targetPasses);
  };
  if (id == 0 || id > newest_) return Wait::Unknown;
  std::optional<Wait> answer;
  const bool inTime = frameReady_.wait_for(lock, std::chrono::milliseconds(timeoutMs), [&] {
    if (complete())
      answer = Wait::Ready;
    else if (stopping_)
      answer = Wait::Stopped;
    else if (failed_ == id)
      answer = Wait::Failed;
    else if (id != newest_)
      answer = Wait::Superseded;
    else if (newestInteractive_)
      answer = Wait::Draft;
    return answer.has_value();
  });
  if (!inTime) return Wait::TimedOut;
  if (*answer == Wait::Ready) out = snapshot_;
  return *answer;
}

std::optional<SceneDocument> Session::current() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return currentDoc_;
}

void Session::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    requestReady_.wait(lock, [&] { return stopping_ || pending_.has_value(); });
    if (stopping_) return;
    const Request request = std::move(*pending_);
    pending_.reset();
    cancel_ = false;
    std::shared_ptr<const Model> model = std::move(pendingModel_);
    pendingModel_.reset();
    const DatasetInfo dataset = pendingDataset_;
    const LegendText legends = pendingLegends_;
    lock.unlock();
    if (model) {
      view_.reset(); // they refer to the model they replace
      renderer_.reset();
      model_ = std::move(model);
      dataset_ = dataset;
      legends_ = legends;
      renderer_ = std::make_unique<Renderer>(*model_, dataset_);
      renderer_->setParticles(particles_);
      view_ = std::make_unique<ProgressiveView>(*renderer_, options_.device, DraftPolicy{});
    }
    try {
      serve(request);
    } catch (const std::exception& e) {
      publishError(request, e.what());
    }
    lock.lock();
  }
}

void Session::serve(const Request& request) {
  const Frame& frame = request.doc.frame;
  provideParticles(request.doc.scene);
  ProgressiveView& view = *view_;
  view.show(request.doc);
  view.restart(); // every request publishes its own frames
  PassControl control;
  control.cancel = &cancel_;

  FrameInfo info;
  info.request = request.id;
  info.targetPasses = frame.samplesPerPixel;
  info.visibleRegions = renderer_->visibleRegions();
  info.regions = model_->regions.regions.size();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    info.data = dataNote_;
  }

  // A draft first; not when the draft on screen already shows this very scene (the request that
  // ends a drag).
  if (request.interactive || !view.draftIsCurrent()) {
    const Frame draft = view.draftFrame();
    if (!view.renderDraft(draft, draftBuffer_, control) || superseded(request.id)) return;
    const RenderStats& s = draftBuffer_.stats();
    info.draft = true;
    info.width = draft.width;
    info.height = draft.height;
    info.passes = 1;
    info.renderSeconds = s.seconds;
    info.samples = s.samples;
    info.samplesPerSecond = s.samplesPerSecond();
    publish(request, draftBuffer_.resolve(), info, false, options_.jpegQuality);
  }
  if (request.interactive) return;

  // Then the full-resolution image, refined pass by pass; with parts, it ends with every level
  // (path tracing scatters light between parts: it stays with the resident coarse levels).
  const bool everyLevel = parts_ && request.doc.scene.integration.integrator != Integrator::PathTrace;
  if (parts_ && !everyLevel) info.data += "; a path-traced view shows these levels only";
  info.draft = false;
  info.width = frame.width;
  info.height = frame.height;
  Image image;
  while (!view.complete()) {
    const RenderStats before = view.buffer().stats();
    if (!view.refine(control) || superseded(request.id)) return;
    const RenderStats& after = view.buffer().stats();
    info.passes = view.passes();
    info.final = view.complete() && !everyLevel;
    if (info.final && NoiseRounds::applies(request.doc.scene, frame))
      info.data +=
          strCat(info.data.empty() ? "" : "; ", "noise target ", frame.noiseTarget, "/255",
                 view.showsDenoised() ? " (denoised)" : "",
                 " reached: ", std::round(view.buffer().meanPasses() * 10) / 10, " samples per pixel on average");
    info.renderSeconds = after.seconds - before.seconds;
    info.samples = after.samples - before.samples;
    info.samplesPerSecond = info.renderSeconds > 0 ? double(info.samples) / info.renderSeconds : 0;
    view.resolve(image);
    publish(request, image, info, !everyLevel, info.final ? options_.finalJpegQuality : options_.jpegQuality);
  }
  if (everyLevel) serveParts(request, info, control);
}

void Session::serveParts(const Request& request, FrameInfo info, PassControl& control) {
  const Frame& frame = request.doc.frame;
  FrameBuffer buffer(frame.width, frame.height);
  Timer timer;
  auto said = [&](int passes) {
    return strCat("every level, drawn in ", parts_->parts(), " parts (", parts_->residentParts(), " resident",
                  passes < frame.samplesPerPixel ? strCat("; ", passes, " of ", frame.samplesPerPixel, " passes") : "",
                  "); ", formatBytes(residentBytesNow()), " resident of a ", formatBytes(budget_), " budget");
  };
  // Every level after one pass over the parts (a pass reads each part once), then after each
  // round of passes, until the last.
  auto afterRound = [&](const FrameBuffer& sofar, int passes) {
    if (superseded(request.id)) return;
    FrameInfo partial = info;
    partial.passes = passes;
    partial.final = false;
    partial.renderSeconds = timer.seconds();
    partial.data = said(passes);
    publish(request, sofar.resolve(), partial, false, options_.jpegQuality);
  };
  if (!renderStreamed(*parts_, request.doc.scene, RendererOptions{}, frame, buffer, control, afterRound) ||
      superseded(request.id))
    return;
  info.passes = frame.samplesPerPixel;
  info.final = true;
  info.renderSeconds = timer.seconds();
  info.samples = buffer.stats().samples;
  info.samplesPerSecond = info.renderSeconds > 0 ? double(info.samples) / info.renderSeconds : 0;
  info.data = said(frame.samplesPerPixel);
  publish(request, buffer.resolve(), info, true, options_.finalJpegQuality);
}

void Session::publish(const Request& request, const Image& rendered, FrameInfo info, bool keepImage, int quality) {
  const Scene& scene = request.doc.scene;
  // The legends the scene asks for, drawn into what is sent and saved.
  const Legends& l = scene.legends;
  std::optional<Image> withLegends;
  if (l.colorBar || l.annotation || l.levelLegend) {
    withLegends = rendered;
    drawLegends(scene, request.doc.frame, *model_, dataset_, legends_, *withLegends);
  }
  const Image& image = withLegends ? *withLegends : rendered;
  auto frame = std::make_shared<PublishedFrame>();
  frame->jpeg = encodeJpeg(image, scene.background, quality, info.final);
  std::shared_ptr<const Image> kept = keepImage ? std::make_shared<const Image>(image) : nullptr;
  std::lock_guard<std::mutex> lock(mutex_);
  if (stopping_ || request.id != newest_) return; // superseded: never sent after the newer request
  info.sequence = ++sequence_;
  info.sinceRequest = secondsSince(request.accepted);
  frame->info = info;
  latest_ = std::move(frame);
  if (kept) {
    snapshot_.image = std::move(kept);
    snapshot_.request = request.id;
    snapshot_.passes = info.passes;
    snapshot_.targetPasses = info.targetPasses;
    snapshot_.final = info.final;
    snapshot_.background = scene.background;
    snapshot_.keepAlpha = scene.keepAlpha;
  }
  frameReady_.notify_all();
}

void Session::publishError(const Request& request, const std::string& message) {
  auto frame = std::make_shared<PublishedFrame>();
  frame->error = message;
  std::lock_guard<std::mutex> lock(mutex_);
  if (stopping_ || request.id != newest_) return;
  failed_ = request.id;
  frame->info.request = request.id;
  frame->info.sequence = ++sequence_;
  frame->info.sinceRequest = secondsSince(request.accepted);
  latest_ = std::move(frame);
  frameReady_.notify_all();
}

} // namespace exa::view
