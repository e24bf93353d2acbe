// Running a load in a forked child: under an address-space limit (not under AddressSanitizer,
// whose shadow memory needs terabytes of address space) and an alarm, with its message passed
// back through a pipe, so that a crash, a hang or an allocation the input does not pay for ends
// the child and is reported, not the test. The test must have no threads of its own when it forks.
#pragma once

#include <chrono>
#include <fstream>
#include <functional>
#include <string>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include "asan.h"

namespace exa::test {

/// The bytes of address space this process maps now.
inline long mappedBytes() {
  std::ifstream in("/proc/self/statm");
  long pages = 0;
  in >> pages;
  return pages * sysconf(_SC_PAGESIZE);
}

struct ChildOutcome {
  int status = -1; ///< the child's exit code, or 128 + N where signal N ended it
  std::string message;
  double seconds = 0;
  long peakKiB = 0;
};

/// Runs `body` in a forked child whose address space may grow by `extraBytes` beyond the
/// parent's (not under AddressSanitizer) and that an alarm ends after `alarmSeconds` (0: none).
/// `body` sets the message and returns the exit code.
inline ChildOutcome runInChild([[maybe_unused]] long extraBytes, unsigned alarmSeconds,
                               const std::function<int(std::string&)>& body) {
  ChildOutcome out;
  int fds[2];
  if (pipe(fds) != 0) return out;
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
#ifndef EXABRICKS_ASAN
    const rlim_t limit = rlim_t(mappedBytes() + extraBytes);
    const rlimit lim{limit, limit};
    setrlimit(RLIMIT_AS, &lim);
#endif
    if (alarmSeconds) alarm(alarmSeconds);
    std::string message;
    const int code = body(message);
    [[maybe_unused]] const ssize_t written = write(fds[1], message.data(), message.size());
    close(fds[1]);
    _exit(code);
  }
  close(fds[1]);
  char buf[4096];
  for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) > 0;)
    out.message.append(buf, size_t(n));
  close(fds[0]);
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  out.peakKiB = usage.ru_maxrss;
  return out;
}

} // namespace exa::test
