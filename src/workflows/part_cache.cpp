#include "part_cache.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/core/text.h"
#include "exabricks/io/model_file.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

namespace exa {

PartCache::PartCache(int parts, uint64_t bytes) : fds_(size_t(parts), -1) {
  if (bytes == 0) return; // one part: never read again
  if (const char* env = std::getenv("EXABRICKS_PART_CACHE"); env && std::string(env) == "0") return;
  const char* tmp = std::getenv("TMPDIR");
  const std::string base = tmp && *tmp ? tmp : "/tmp";
  struct statvfs fs {};
  if (::statvfs(base.c_str(), &fs) != 0) return;
  const uint64_t free = uint64_t(fs.f_bavail) * uint64_t(fs.f_frsize);
  if (free / 2 < bytes) {
    logNote(strCat("parts are read again from the step when needed again: ", base, " has ", formatBytes(free),
                   " free, less than twice their ", formatBytes(bytes)));
    return;
  }
  std::string pattern = base + "/exabricks-parts-XXXXXX";
  if (!::mkdtemp(pattern.data())) return;
  folder_ = pattern;
}

PartCache::~PartCache() { turnOff(""); }

void PartCache::turnOff(const std::string& why) {
  if (!why.empty() && on())
    logWarning(strCat("parts are no longer kept on disk (", why, "): each is read from the step when needed"));
  for (int& fd : fds_)
    if (fd >= 0) ::close(fd), fd = -1;
  for (auto& [key, kept] : gradientFds_)
    ::close(kept.first);
  gradientFds_.clear();
  if (on()) ::rmdir(folder_.c_str());
  folder_.clear();
}

int PartCache::keep(const std::string& name, const std::function<void(const std::string&)>& write) {
  if (!on()) return -1;
  const std::string path = strCat(folder_, "/", name);
  try {
    write(path);
  } catch (const std::exception& e) {
    ::unlink(path.c_str());
    turnOff(e.what());
    return -1;
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  ::unlink(path.c_str());
  return fd;
}

std::optional<Model> PartCache::read(int part) const {
  const int fd = fds_.at(size_t(part));
  if (fd < 0) return std::nullopt;
  ++hits_;
  return readModel(strCat("/proc/self/fd/", fd));
}

void PartCache::write(int part, const Model& model) {
  const int fd = keep(strCat("part_", part, ".exab"), [&](const std::string& path) { writeModel(model, path); });
  if (fd >= 0) fds_.at(size_t(part)) = fd;
}

namespace {
/// Reads `bytes` at `offset` of a file; false when it holds fewer.
bool readAt(int fd, void* to, size_t bytes, size_t offset) {
  size_t done = 0;
  while (done < bytes) {
    const ssize_t got = ::pread(fd, static_cast<char*>(to) + done, bytes - done, off_t(offset + done));
    if (got <= 0) return false;
    done += size_t(got);
  }
  return true;
}
} // namespace

std::optional<GradientFields> PartCache::readGradients(int part, int field, size_t cells, size_t bricks) const {
  const auto it = gradientFds_.find({part, field});
  if (it == gradientFds_.end()) return std::nullopt;
  const int fd = it->second.first;
  const size_t bytes = 2 * cells * sizeof(uint32_t), biasBytes = bricks * sizeof(int32_t);
  struct stat st {};
  if (::fstat(fd, &st) != 0 || size_t(st.st_size) != bytes + biasBytes + bricks) return std::nullopt;
  GradientFields g;
  g.cells.resize(2 * cells);
  g.scaleBias.resize(bricks);
  g.built.resize(bricks);
  if (!readAt(fd, g.cells.data(), bytes, 0) || !readAt(fd, g.scaleBias.data(), biasBytes, bytes) ||
      !readAt(fd, g.built.data(), bricks, bytes + biasBytes))
    return std::nullopt;
  ++gradientHits_;
  return g;
}

bool PartCache::buildsMore(int part, int field, const GradientFields& gradients) const {
  const auto it = gradientFds_.find({part, field});
  return it == gradientFds_.end() || gradients.missing < it->second.second;
}

void PartCache::writeGradients(int part, int field, const GradientFields& gradients) {
  const int fd = keep(
      strCat("part_", part, "_gradients_", field, "_", gradients.missing, ".packed"), [&](const std::string& path) {
        std::ofstream out(path, std::ios::binary);
        out.write(reinterpret_cast<const char*>(gradients.cells.data()),
                  std::streamsize(gradients.cells.size() * sizeof(uint32_t)));
        out.write(reinterpret_cast<const char*>(gradients.scaleBias.data()),
                  std::streamsize(gradients.scaleBias.size() * sizeof(int32_t)));
        out.write(reinterpret_cast<const char*>(gradients.built.data()), std::streamsize(gradients.built.size()));
        if (!out.flush()) fail(path, ": cannot write");
      });
  if (fd < 0) return;
  const auto it = gradientFds_.find({part, field});
  if (it != gradientFds_.end()) ::close(it->second.first);
  gradientFds_[{part, field}] = {fd, gradients.missing};
}

} // namespace exa
