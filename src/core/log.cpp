#include "exabricks/core/log.h"

#include <atomic>
#include <cstdio>
#include <mutex>
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
  uint64_t total;
  std::atomic<uint64_t> done{0};
  bool enabled;
  std::atomic<bool> finished{false};
  std::atomic<bool> drawn{false};
  Timer timer;
  std::atomic<int64_t> lastDrawMs{0};
};

Progress::Progress(std::string label, uint64_t total) : impl_(new Impl) {
  impl_->label = std::move(label);
  impl_->total = total;
  impl_->enabled = gLevel >= int(LogLevel::Warning) && isatty(STDERR_FILENO);
}

Progress::~Progress() {
  finish();
  delete impl_;
}

void Progress::advance(uint64_t amount) {
  const uint64_t done = impl_->done += amount;
  if (!impl_->enabled || impl_->finished) return;
  const int64_t ms = int64_t(impl_->timer.seconds() * 1000.0);
  int64_t last = impl_->lastDrawMs.load();
  if (ms - last < 200 || !impl_->lastDrawMs.compare_exchange_strong(last, ms)) return;
  std::lock_guard<std::mutex> lock(gMutex);
  if (impl_->finished) return;
  impl_->drawn = true;
  const double pct = impl_->total ? 100.0 * double(done) / double(impl_->total) : 100.0;
  std::fprintf(stderr, "\rexabricks: %s %5.1f%% (%.1f s)", impl_->label.c_str(), pct, impl_->timer.seconds());
  std::fflush(stderr);
}

void Progress::finish() {
  if (!impl_->enabled || impl_->finished.exchange(true)) return;
  std::lock_guard<std::mutex> lock(gMutex);
  if (!impl_->drawn) return;
  std::fprintf(stderr, "\rexabricks: %s done (%.2f s)        \n", impl_->label.c_str(), impl_->timer.seconds());
}

} // namespace exa
