#include "exabricks/core/files.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

namespace exa {
namespace fs = std::filesystem;

uint64_t fileSize(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) fail(path, ": is a directory, not a file");
  const auto size = fs::file_size(path, ec);
  if (ec) fail(path, ": cannot open: ", ec.message());
  return size;
}

void readInto(const std::string& path, void* data, uint64_t size) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) fail(path, ": cannot open: ", std::strerror(errno));
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> closer(f, std::fclose);
  // Large files in pieces, with progress on stderr (fraction, time taken and left).
  constexpr uint64_t kPiece = uint64_t(64) << 20;
  std::optional<Progress> progress;
  if (size >= 4 * kPiece)
    progress.emplace(strCat("reading ", path, " (", (size + (1 << 20) - 1) >> 20, " MiB)"),
                     (size + kPiece - 1) / kPiece);
  char* out = static_cast<char*>(data);
  for (uint64_t at = 0; at < size; at += kPiece) {
    const size_t n = size_t(std::min(kPiece, size - at));
    if (std::fread(out + at, 1, n, f) != n) fail(path, ": read error (file changed while reading?)");
    if (progress) progress->advance(1);
  }
}

std::vector<char> readFile(const std::string& path) {
  std::vector<char> data(fileSize(path));
  readInto(path, data.data(), data.size());
  return data;
}

namespace {

/// Temporary files not yet published, for removePendingTemporaries() (which a signal handler
/// may call): fixed slots, each claimed and released with an atomic flag.
constexpr int kPendingSlots = 64;
struct PendingSlot {
  std::atomic<bool> used{false};
  char path[4096];
};
PendingSlot gPending[kPendingSlots];

int claimPending(const std::string& path) {
  if (path.size() >= sizeof(PendingSlot::path)) return -1;
  for (int i = 0; i < kPendingSlots; ++i) {
    bool expected = false;
    if (!gPending[i].used.compare_exchange_strong(expected, true)) continue;
    std::memcpy(gPending[i].path, path.c_str(), path.size() + 1);
    return i;
  }
  return -1;
}

void releasePending(int slot) {
  if (slot >= 0) gPending[slot].used.store(false);
}

/// Commits renaming their files into place right now, and an interrupt that arrived meanwhile
/// (deferInterrupt), raised again when the last of them ends.
std::atomic<int> gPublishing{0};
std::atomic<int> gDeferredSignal{0};

/// Marks a commit's renames; the interrupt deferred during them is raised again at the end.
struct Publishing {
  Publishing() { gPublishing.fetch_add(1); }
  ~Publishing() {
    if (gPublishing.fetch_sub(1) == 1)
      if (const int signal = gDeferredSignal.exchange(0)) std::raise(signal);
  }
  Publishing(const Publishing&) = delete;
  Publishing& operator=(const Publishing&) = delete;
};

/// Where a write to `path` goes: symlinks are followed, so the link stays and its target changes.
std::string resolveTarget(const std::string& path) {
  std::error_code ec;
  fs::path p(path);
  for (int hops = 0; hops < 40 && fs::is_symlink(fs::symlink_status(p, ec)); ++hops) {
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) break;
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  return p.string();
}

/// Flushes and closes a file being written; false (errno set) when any of it failed.
bool closeWritten(std::FILE* f, bool sync) {
  // A file renamed into place is on disk first: a crash leaves the old file or the new one.
  const bool flushed = std::fflush(f) == 0 && (!sync || ::fsync(::fileno(f)) == 0);
  const int err = errno;
  const bool closed = std::fclose(f) == 0;
  if (!closed && flushed) return false;
  errno = err;
  return flushed;
}

/// Flushes a directory's entries (a rename into it) to disk; best effort.
void syncDirectory(const std::string& target) {
  const fs::path parent = fs::path(target).parent_path();
  const int fd = ::open(parent.empty() ? "." : parent.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

} // namespace

void checkOutputFolder(const std::string& path) {
  const fs::path p(path);
  const fs::path folder = p.has_parent_path() ? p.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::exists(folder, ec)) fail(path, ": cannot write: the folder ", folder.string(), " does not exist");
  if (!fs::is_directory(folder, ec)) fail(path, ": cannot write: ", folder.string(), " is not a folder");
}

std::string temporaryPath(const std::string& target, size_t index) {
  return target + ".tmp" + std::to_string(::getpid()) + "." + std::to_string(index);
}

void removeStaleTemporaries(const std::string& target) {
  const fs::path t(target);
  const fs::path dir = t.has_parent_path() ? t.parent_path() : fs::path(".");
  const std::string prefix = t.filename().string() + ".tmp";
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    // NAME.tmpPID.INDEX (or NAME.tmpPID): only when process PID no longer runs.
    const std::string rest = name.substr(prefix.size());
    const size_t dot = rest.find('.');
    const std::string pid = rest.substr(0, dot), index = dot == std::string::npos ? "1" : rest.substr(dot + 1);
    auto digits = [](const std::string& x) {
      return !x.empty() && x.size() < 10 && x.find_first_not_of("0123456789") == std::string::npos;
    };
    if (!digits(pid) || !digits(index)) continue;
    const long id = std::stol(pid);
    if (id <= 0 || id == long(::getpid()) || ::kill(pid_t(id), 0) == 0 || errno != ESRCH) continue;
    std::error_code rec;
    fs::remove(it->path(), rec);
  }
}

PendingTemporary::PendingTemporary(const std::string& path) : slot_(claimPending(path)) {}
PendingTemporary::~PendingTemporary() { releasePending(slot_); }

bool deferInterrupt(int signal) {
  // The signal is recorded before the count is read: a commit that ends after this read raises
  // it, and one that ended before leaves the count at zero, so the caller goes on.
  gDeferredSignal.store(signal);
  return gPublishing.load() > 0;
}

void removePendingTemporaries() {
  for (PendingSlot& s : gPending)
    if (s.used.load()) ::unlink(s.path);
}

size_t AtomicFiles::begin(const std::string& path) {
  Pending p;
  p.path = path;
  p.target = resolveTarget(path);
  std::error_code ec;
  const fs::file_status st = fs::status(p.target, ec);
  if (!ec && fs::exists(st) && !fs::is_regular_file(st)) {
    // A device, a FIFO or another special file: written through, never replaced.
    if (fs::is_directory(st)) fail(path, ": cannot write: is a directory");
    p.stream = std::fopen(p.target.c_str(), "wb");
    if (!p.stream) fail(path, ": cannot write: ", std::strerror(errno));
    pending_.push_back(p);
    return pending_.size() - 1;
  }
  removeStaleTemporaries(p.target);
  p.temporary = temporaryPath(p.target, pending_.size());
  p.slot = claimPending(p.temporary);
  p.stream = std::fopen(p.temporary.c_str(), "wb");
  if (!p.stream) {
    const std::string why = std::strerror(errno);
    releasePending(p.slot);
    discard();
    fail(path, ": cannot write: ", why);
  }
  pending_.push_back(p);
  return pending_.size() - 1;
}

void AtomicFiles::append(size_t file, const void* data, size_t size) {
  Pending& p = pending_.at(file);
  EXA_CHECK(p.stream != nullptr, "appending to a finished file");
  if (size > 0 && std::fwrite(data, 1, size, p.stream) != size) {
    const std::string why = std::strerror(errno ? errno : EIO), path = p.path;
    discard();
    fail(path, ": write failed: ", why);
  }
}

void AtomicFiles::write(const std::string& path, const void* data, size_t size) { append(begin(path), data, size); }

void AtomicFiles::commit() {
  // Everything is on disk before anything is renamed into place.
  for (Pending& p : pending_) {
    errno = 0;
    const bool ok = closeWritten(p.stream, !p.temporary.empty());
    p.stream = nullptr;
    if (!ok) {
      const std::string why = std::strerror(errno ? errno : EIO), path = p.path;
      discard();
      fail(path, ": write failed: ", why);
    }
  }
  // An interrupt during the renames waits for them, so that all files appear or none.
  const Publishing publishing;
  for (size_t i = 0; i < pending_.size(); ++i) {
    Pending& p = pending_[i];
    if (p.temporary.empty()) continue; // written through
    if (std::rename(p.temporary.c_str(), p.target.c_str()) != 0) {
      const std::string why = std::strerror(errno);
      pending_.erase(pending_.begin(), pending_.begin() + long(i)); // those are published
      discard();
      fail(p.path, ": cannot rename the temporary file into place: ", why);
    }
    releasePending(p.slot);
    syncDirectory(p.target);
  }
  pending_.clear();
}

void AtomicFiles::discard() {
  for (const Pending& p : pending_) {
    if (p.stream) std::fclose(p.stream);
    if (p.temporary.empty()) continue;
    std::remove(p.temporary.c_str());
    releasePending(p.slot);
  }
  pending_.clear();
}

AtomicFiles::~AtomicFiles() { discard(); }

void writeFileAtomic(const std::string& path, const void* data, size_t size) {
  AtomicFiles files;
  files.write(path, data, size);
  files.commit();
}

} // namespace exa
