// The native exchange format: NAME.cells (int32 x, y, z, level records, little-endian) with one
// float32 value per cell in NAME.scalars (field "scalar") and NAME.FIELD.scalars; and the
// ".grids" text fixture format (one box per line: x y z nx ny nz level value, or eight trilinear
// corner values).
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/partition.h"

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace exa {

/// Reads NAME.cells and its fields. `fields` selects fields by name (all when empty). Validates
/// everything but overlaps; errors name the file, the record and the problem. With a box, only
/// the cells overlapping it are kept, read in pieces.
CellSet readNative(const std::string& cellsPath, const std::vector<std::string>& fields = {}, const box3i& box = {});
/// Where the cells of NAME.cells lie, read in pieces (values are not read).
Census nativeCensus(const std::string& cellsPath);

/// Names of the fields stored beside a .cells file.
std::vector<std::string> listNativeFields(const std::string& cellsPath);

/// Writes NAME.cells and one NAME[.FIELD].scalars per field (field "scalar" is NAME.scalars).
/// Every file is written to a temporary name first; they are renamed into place together.
void writeNative(const CellSet& cells, const std::string& cellsPath);

/// Most cells a .grids fixture may describe (2^26): each line expands to a box of cells.
constexpr uint64_t kMaxGridsCells = uint64_t(1) << 26;

/// Reads a .grids text fixture (field "scalar").
CellSet readGrids(const std::string& path);

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

/// Writes NAME.cells and its field files in pieces, in order; finish() publishes them together
/// (nothing appears when it is not called).
class NativeWriter {
public:
  NativeWriter(const std::string& cellsPath, const std::vector<std::string>& fieldNames);
  /// Appends cells with one value per cell of every field, fields in the constructor's order.
  void append(const CellSet& piece);
  void finish();
  uint64_t cellCount() const { return cells_; }

private:
  std::string cellsPath_;
  std::vector<std::string> fieldNames_;
  AtomicFiles files_;
  uint64_t cells_ = 0;
};

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
