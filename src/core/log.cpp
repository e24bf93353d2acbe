#include "exabricks/core/log.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <thread>
#include <unistd.h>

namespace exa {
namespace {
std::atomic<int> gLevel{int(LogLevel::Warning)};
std::mutex gMutex;

void emit(const char* prefix, const std::string& message) {
  std::lock_guard<std::mutex> lock(gMutex);
  std::fprintf(stderr, "exabricks: %s%s\n", prefix, message.c_str());
}
} // namespace

void setLogLevel(LogLevel level) { gLevel = int(level); }
LogLevel logLevel() { return LogLevel(gLevel.load()); }
void logInfo(const std::string& m) {
  if (gLevel >= int(LogLevel::Info)) emit("", m);
}
void logNote(const std::string& m) {
  if (gLevel >= int(LogLevel::Warning)) emit("", m);
}
void logWarning(const std::string& m) {
  if (gLevel >= int(LogLevel::Warning)) emit("warning: ", m);
}
void logDebug(const std::string& m) {
  if (gLevel >= int(LogLevel::Debug)) emit("debug: ", m);
}

struct Progress::Impl {
  std::string label;
  std::atomic<uint64_t> total;
  std::atomic<uint64_t> done{0};
  bool enabled;
  bool terminal; ///< redraw one line; else append lines now and then
  std::atomic<bool> finished{false};
  std::atomic<bool> drawn{false};
  Timer timer;
  std::atomic<int64_t> lastDrawMs{0};
  // Elsewhere than on a terminal, a thread writes the lines, so that a long stage between two
  // advances still says that it runs.
  std::thread heartbeat;
  std::mutex wake;
  std::condition_variable stop;

  /// Draws the progress when it is time to (the terminal at most five times a second).
  void draw() {
    const int64_t ms = int64_t(timer.seconds() * 1000.0);
    int64_t last = lastDrawMs.load();
    if (!terminal && (ms < 5000 || (drawn && ms - last < 10000))) return;
    if (ms - last < 200 || !lastDrawMs.compare_exchange_strong(last, ms)) return;
    std::lock_guard<std::mutex> lock(gMutex);
    if (finished) return;
    drawn = true;
    const uint64_t all = total;
    const double fraction = all ? std::min(1.0, double(done) / double(all)) : 1.0;
    const double seconds = timer.seconds();
    if (terminal)
      std::fprintf(stderr, "\rexabricks: %s %5.1f%% (%.1f s)", label.c_str(), 100.0 * fraction, seconds);
    else if (fraction > 0.0)
      std::fprintf(stderr, "exabricks: %s: %.1f %% after %.0f s, about %.0f s left\n", label.c_str(), 100.0 * fraction,
                   seconds, seconds * (1.0 - fraction) / fraction);
    else
      std::fprintf(stderr, "exabricks: %s: running for %.0f s\n", label.c_str(), seconds);
    std::fflush(stderr);
  }
};

Progress::Progress(std::string label, uint64_t total) : impl_(new Impl) {
  impl_->label = std::move(label);
  impl_->total = total;
  impl_->terminal = isatty(STDERR_FILENO);
  impl_->enabled = gLevel >= int(LogLevel::Warning);
  if (impl_->enabled && !impl_->terminal)
    impl_->heartbeat = std::thread([im = impl_] {
      std::unique_lock<std::mutex> lock(im->wake);
      while (!im->stop.wait_for(lock, std::chrono::seconds(1), [im] { return im->finished.load(); }))
        im->draw();
    });
}

Progress::~Progress() {
  finish();
  delete impl_;
}

void Progress::advance(uint64_t amount) {
  impl_->done += amount;
  if (!impl_->enabled || impl_->finished || !impl_->terminal) return;
  impl_->draw();
}

void Progress::setTotal(uint64_t total) { impl_->total = total; }

void Progress::finish() {
  if (!impl_->enabled || impl_->finished.exchange(true)) return;
  if (impl_->heartbeat.joinable()) {
    { std::lock_guard<std::mutex> lock(impl_->wake); }
    impl_->stop.notify_all();
    impl_->heartbeat.join();
  }
  std::lock_guard<std::mutex> lock(gMutex);
  if (!impl_->drawn) return;
  if (impl_->terminal)
    std::fprintf(stderr, "\rexabricks: %s done (%.2f s)        \n", impl_->label.c_str(), impl_->timer.seconds());
  else
    std::fprintf(stderr, "exabricks: %s: done in %.1f s\n", impl_->label.c_str(), impl_->timer.seconds());
}

} // namespace exa
