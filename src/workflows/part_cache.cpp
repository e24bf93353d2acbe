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
  for (auto& [key, fd] : gradientFds_)
    ::close(fd);
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

std::optional<std::array<std::vector<float>, 3>> PartCache::readGradients(int part, int field) const {
  const auto it = gradientFds_.find({part, field});
  if (it == gradientFds_.end()) return std::nullopt;
  struct stat st {};
  if (::fstat(it->second, &st) != 0 || st.st_size % (3 * sizeof(float)) != 0) return std::nullopt;
  const size_t n = size_t(st.st_size) / (3 * sizeof(float));
  std::array<std::vector<float>, 3> g;
  for (int a = 0; a < 3; ++a) {
    g[size_t(a)].resize(n);
    const size_t bytes = n * sizeof(float);
    size_t done = 0;
    while (done < bytes) {
      const ssize_t got = ::pread(it->second, reinterpret_cast<char*>(g[size_t(a)].data()) + done, bytes - done,
                                  off_t(size_t(a) * bytes + done));
      if (got <= 0) return std::nullopt;
      done += size_t(got);
    }
  }
  return g;
}

void PartCache::writeGradients(int part, int field, const std::array<std::vector<float>, 3>& gradients) {
  const int fd = keep(strCat("part_", part, "_gradients_", field, ".f32"), [&](const std::string& path) {
    std::ofstream out(path, std::ios::binary);
    for (const std::vector<float>& g : gradients)
      out.write(reinterpret_cast<const char*>(g.data()), std::streamsize(g.size() * sizeof(float)));
    if (!out.flush()) fail(path, ": cannot write");
  });
  if (fd >= 0) gradientFds_[{part, field}] = fd;
}

} // namespace exa
