// Logging and progress on stderr. Library code reports through here so that commands can keep
// stdout clean for their results (and for --json).
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace exa {

enum class LogLevel { Quiet = 0, Warning = 1, Info = 2, Debug = 3 };

void setLogLevel(LogLevel level);
LogLevel logLevel();
void logInfo(const std::string& message);
void logWarning(const std::string& message);
/// What a command chose for the user (a default field, a log scale), shown unless -q.
void logNote(const std::string& message);
void logDebug(const std::string& message);

/// Wall-clock stopwatch in seconds.
class Timer {
public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
  void reset() { start_ = std::chrono::steady_clock::now(); }

private:
  std::chrono::steady_clock::time_point start_;
};

/// Progress of long work on stderr, unless the tool is quiet: on a terminal, one line redrawn
/// (nothing for work that finishes within a fifth of a second); elsewhere (a log, a pipe, a
/// batch job), a line with the fraction done, the time taken and the time left once the work has
/// taken 5 s, then every 10 s, and one when it ends. Updates are thread-safe and rate limited.
class Progress {
public:
  Progress(std::string label, uint64_t total);
  ~Progress();
  void advance(uint64_t amount);
  /// The work's total, where it grows as the work goes (passes planned round by round).
  void setTotal(uint64_t total);
  void finish();

private:
  struct Impl;
  Impl* impl_;
};

} // namespace exa
