// Shared by the fuzz targets of readers that take paths: the input is cut into the files of one
// dataset (at lines "--8<--"), which are written into a folder of this process and read from
// there. Only exa::Error may escape a reader.
#pragma once

#include "exabricks/core/error.h"
#include "exabricks/io/patch_source.h"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fuzz {

/// A folder of this process, removed at exit.
inline const std::filesystem::path& folder() {
  static const std::filesystem::path dir = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "exabricks-fuzz-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) std::abort();
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(folder(), ec);
    });
    return std::filesystem::path(pattern);
  }();
  return dir;
}

/// The input cut at "\n--8<--\n" into exactly `count` parts (missing ones empty, the last one
/// takes the rest).
inline std::vector<std::string> parts(const uint8_t* data, size_t size, size_t count) {
  static const std::string cut = "\n--8<--\n";
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> out;
  size_t at = 0;
  while (out.size() + 1 < count) {
    const size_t next = text.find(cut, at);
    if (next == std::string::npos) break;
    out.push_back(text.substr(at, next - at));
    at = next + cut.size();
  }
  out.push_back(at <= text.size() ? text.substr(at) : std::string());
  out.resize(count);
  return out;
}

/// Writes `bytes` to `name` inside folder() (creating sub-folders) and returns its path.
inline std::string write(const std::string& name, const std::string& bytes) {
  const std::filesystem::path p = folder() / name;
  std::filesystem::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
  return p.string();
}

/// The input as a stream of values for structure-aware targets (zeros past its end).
class Bytes {
public:
  Bytes(const uint8_t* data, size_t size) : p_(data), n_(size) {}
  bool empty() const { return i_ >= n_; }
  uint8_t byte() { return i_ < n_ ? p_[i_++] : 0; }
  template <typename T> T value() {
    T v{};
    unsigned char b[sizeof(T)] = {};
    for (unsigned char& c : b)
      c = byte();
    std::memcpy(&v, b, sizeof(T));
    return v;
  }

private:
  const uint8_t* p_;
  size_t n_, i_ = 0;
};

/// A build from the input's boxes (structure without values) holds exactly the cells its read
/// returns, where both succeed (the build also refuses leaves that overlap, which a read keeps).
template <typename Read, typename Patches> void boxBuildMatchesRead(Read&& read, Patches&& patches) {
  bool readable = false;
  size_t cells = 0;
  try {
    cells = read().cells.size();
    readable = true;
  } catch (const exa::Error&) {
  }
  try {
    const exa::Model m = exa::buildModelOfPatches(patches());
    if (readable && m.cellCount() != cells) __builtin_trap();
  } catch (const exa::Error&) {
  }
}

} // namespace fuzz
