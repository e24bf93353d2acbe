// Files written whole or not at all, and read whole: atomic publishing (temporary files beside
// their targets, renamed into place together), the removal of what an interrupted process left,
// and the interrupt handling that keeps a publication whole. Every writer of the project uses it.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace exa {

/// Files published together: each write goes to a temporary file beside its target, commit()
/// renames them all into place, and whatever was not committed is removed. A symlink keeps
/// pointing where it did (its target is replaced); a device, FIFO or other special file is
/// written through, never replaced.
class AtomicFiles {
public:
  AtomicFiles() = default;
  AtomicFiles(const AtomicFiles&) = delete;
  AtomicFiles& operator=(const AtomicFiles&) = delete;
  ~AtomicFiles();
  /// Starts a file written in pieces; returns its handle for append().
  size_t begin(const std::string& path);
  void append(size_t file, const void* data, size_t size);
  /// A whole file: begin() and one append().
  void write(const std::string& path, const void* data, size_t size);
  void commit();
  void discard();

private:
  struct Pending {
    std::string path, target, temporary; ///< temporary empty: written through
    int slot = -1;
    std::FILE* stream = nullptr;
  };
  std::vector<Pending> pending_;
};

/// Fails ("PATH: cannot write: ...") unless the folder `path` is to be written into exists: a
/// command checks its outputs before it loads and renders, not after.
void checkOutputFolder(const std::string& path);

/// Writes `size` bytes to `path` atomically (AtomicFiles with one file).
void writeFileAtomic(const std::string& path, const void* data, size_t size);

/// The temporary file beside `target` that the index-th write of this process goes to first
/// (TARGET.tmpPID.INDEX).
std::string temporaryPath(const std::string& target, size_t index);

/// Removes temporaries of `target` left by processes that no longer run (a write killed before
/// it could clean up); every write calls it first.
void removeStaleTemporaries(const std::string& target);

/// Registers a temporary file for removePendingTemporaries() while it lives, for writes that
/// stream into their own temporary (model files).
class PendingTemporary {
public:
  explicit PendingTemporary(const std::string& path);
  ~PendingTemporary();
  PendingTemporary(const PendingTemporary&) = delete;
  PendingTemporary& operator=(const PendingTemporary&) = delete;

private:
  int slot_;
};

/// Removes every temporary file not yet published; async-signal-safe, for an interrupt handler.
void removePendingTemporaries();

/// For an interrupt handler, first: true while files are being published together (their
/// renames have begun), and then the handler should return; `signal` is raised again once
/// they all are in place. Async-signal-safe.
bool deferInterrupt(int signal);

/// Reads a whole binary file; fails with the path when it cannot.
std::vector<char> readFile(const std::string& path);
/// Size of a regular file; fails with the path when it cannot be read.
uint64_t fileSize(const std::string& path);
/// Reads exactly `size` bytes from the start of a file.
void readInto(const std::string& path, void* data, uint64_t size);

} // namespace exa
