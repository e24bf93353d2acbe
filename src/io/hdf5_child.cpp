// The check in a child process (checkInChild): libhdf5 walks the file's metadata in a forked
// child under limits, and the parent turns a crash, a hang or a structural failure there into
// DamagedFile.
#include "hdf5_checks.h"
#include "hdf5_file.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <ctime>
#include <fstream>
#include <memory>
#include <set>
#include <tuple>

#include <fcntl.h>
#include <poll.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
#define EXABRICKS_H5_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define EXABRICKS_H5_ASAN 1
#endif
#endif

// Sanitizer runtimes (sanitizer builds and fuzz targets) report errors through a death callback
// that a fuzzer sets; the checking child clears it, so that a crash there is only the child's.
extern "C" void __sanitizer_set_death_callback(void (*callback)(void)) __attribute__((weak));

namespace exa::h5 {
using namespace detail;
namespace {

// Objects of one file that are looked at.
constexpr size_t kMaxObjects = size_t(1) << 20;
// How long the checking child may take (plus a second per GB of file, for the chunk indexes of
// large files), and the memory it may map beyond what it inherits.
constexpr int kCheckSeconds = 60;
#ifndef EXABRICKS_H5_ASAN
constexpr uint64_t kCheckMemory = uint64_t(2) << 30;
#endif

/// What the child writes for the parent: the object it is reading, and the first structural
/// failure libhdf5 reported (empty when none).
struct Shared {
  char at[2048];
  char fault[2048];
  bool unopened; ///< H5Fopen failed
};

/// Reads, in the child, everything of the file that File can ask libhdf5 for: every group's
/// listing (and each listed name looked up), every object's header and attributes (read as
/// numbers or strings, as File reads them), every dataset's type, dataspace, layout, storage
/// and chunk index, and its first element (all of a small table or string dataset). No
/// exception leaves it. A structural failure (a group or attribute list, an object header, a
/// chunk index that libhdf5 cannot read) is recorded: libhdf5's error paths on damaged
/// metadata are not safe either (freeing what was never allocated), so the parent must not
/// take them. Failures reading data are left to the reader to meet.
class Walk {
public:
  Walk(hid_t file, Shared* shared) : file_(file), shared_(shared) {}

  void object(const std::string& path, bool soft, int depth) {
    if (++objects_ > kMaxObjects || depth > 64) return;
    at(path);
    H5O_info_t info;
    if (H5Oget_info_by_name(file_, path.c_str(), &info, H5P_DEFAULT) < 0) {
      if (!soft) fault(path + " (object header)"); // a soft link may dangle
      return;
    }
    const bool seen = !visited_.insert(info.addr).second;
    if (seen) return; // a second link to an object already read
    {
      const Id o(H5Oopen(file_, path.c_str(), H5P_DEFAULT), H5Oclose);
      if (!o) return fault(path + " (object)");
      attributes(o.get(), path);
    }
    if (info.type == H5O_TYPE_DATASET) dataset(path);
    if (info.type != H5O_TYPE_GROUP) return;
    std::vector<std::string> names;
    std::vector<uint8_t> softLinks;
    if (listLinks(file_, path, names, &softLinks) != Listing::Listed) return fault(path + " (group members)");
    for (size_t i = 0; i < names.size(); ++i)
      object(path == "/" ? "/" + names[i] : path + "/" + names[i], softLinks[i] != 0, depth + 1);
  }

  void fault(const std::string& what) {
    if (shared_->fault[0]) return;
    const size_t n = std::min(what.size(), sizeof shared_->fault - 1);
    std::memcpy(shared_->fault, what.data(), n);
    shared_->fault[n] = '\0';
  }

private:
  void at(const std::string& what) {
    const size_t n = std::min(what.size(), sizeof shared_->at - 1);
    std::memcpy(shared_->at, what.data(), n);
    shared_->at[n] = '\0';
  }

  void attributes(hid_t o, const std::string& path) {
    std::vector<std::string> names;
    if (!listAttributes(o, names)) return fault(path + " (attributes)");
    for (const std::string& name : names) {
      at(path + " (attribute '" + name + "')");
      const Id a(H5Aopen(o, name.c_str(), H5P_DEFAULT), H5Aclose);
      if (!a) return fault(path + " (attribute '" + name + "')");
      const Id type(H5Aget_type(a.get()), H5Tclose);
      const Id space(H5Aget_space(a.get()), H5Sclose);
      if (!type || !space) return fault(path + " (attribute '" + name + "')");
      std::string problem, text;
      std::vector<double> numbers;
      if (H5Tget_class(type.get()) == H5T_STRING)
        readAttributeString(a.get(), name, text, problem);
      else
        readAttributeNumbers(a.get(), name, numbers, problem);
      if (problem.rfind("cannot read", 0) == 0) return fault(path + " (attribute '" + name + "')");
    }
  }

  void dataset(const std::string& path) {
    const Id d(H5Dopen2(file_, path.c_str(), H5P_DEFAULT), H5Dclose);
    if (!d) return fault(path + " (dataset)");
    const Id type(H5Dget_type(d.get()), H5Tclose);
    const Id space(H5Dget_space(d.get()), H5Sclose);
    const Id plist(H5Dget_create_plist(d.get()), H5Pclose);
    if (!type || !space || !plist) return fault(path + " (dataset)");
    std::string problem;
    if (!typeIsSound(type.get(), problem) || !spaceIsSound(space.get(), problem)) return; // refused in the parent
    H5Pget_nfilters(plist.get());
    H5D_space_status_t allocated = H5D_SPACE_STATUS_ERROR;
    if (H5Dget_space_status(d.get(), &allocated) < 0) return fault(path + " (dataset)");
    // A dataset never written has no chunk index (the readers refuse it for its storage).
    if (H5Pget_layout(plist.get()) == H5D_CHUNKED && allocated != H5D_SPACE_STATUS_NOT_ALLOCATED) {
      at(path + " (chunk index)");
      hsize_t chunks = 0;
      if (H5Dget_num_chunks(d.get(), H5S_ALL, &chunks) < 0) return fault(path + " (chunk index)");
    }
    H5Dget_storage_size(d.get());
    const uint64_t n = elementCount(space.get());
    if (n == 0) return;
    at(path + " (first element)");
    const H5T_class_t c = H5Tget_class(type.get());
    if (c == H5T_INTEGER || c == H5T_FLOAT) {
      first(d.get(), space.get(), H5T_NATIVE_DOUBLE, sizeof(double));
      first(d.get(), space.get(), H5T_NATIVE_INT64, sizeof(int64_t));
    } else if (c == H5T_COMPOUND) {
      CompoundLayout layout;
      if (compoundLayout(type.get(), layout, problem)) {
        // Small tables whole (as File::readCompound reads them), else the first record.
        if (n * layout.size <= (uint64_t(1) << 20)) {
          std::vector<unsigned char> buf(size_t(n) * layout.size);
          H5Dread(d.get(), layout.type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
        } else {
          first(d.get(), space.get(), layout.type.get(), layout.size);
        }
      }
    } else if (c == H5T_STRING && n <= 4096) {
      at(path + " (strings)");
      Id mt(H5Tcopy(H5T_C_S1), H5Tclose);
      if (H5Tis_variable_str(type.get())) {
        H5Tset_size(mt.get(), H5T_VARIABLE);
        VlenStrings strings{mt.get(), space.get(), std::vector<char*>(static_cast<size_t>(n), nullptr)};
        H5Dread(d.get(), mt.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, strings.ptrs.data());
      } else if (H5Tget_size(type.get()) <= kMaxStringBytes) {
        const size_t size = H5Tget_size(type.get());
        H5Tset_size(mt.get(), size + 1);
        H5Tset_strpad(mt.get(), H5T_STR_NULLTERM);
        std::vector<char> buf(size_t(n) * (size + 1), '\0');
        H5Dread(d.get(), mt.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
      }
    }
  }

  /// Reads the dataset's first element as `memType`.
  void first(hid_t d, hid_t space, hid_t memType, size_t bytes) {
    std::vector<unsigned char> buf(bytes);
    const int rank = H5Sget_simple_extent_ndims(space);
    if (rank <= 0) {
      H5Dread(d, memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
      return;
    }
    const Id file(H5Scopy(space), H5Sclose);
    const std::vector<hsize_t> start(size_t(rank), 0), count(size_t(rank), 1);
    if (!file || H5Sselect_hyperslab(file.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr) < 0)
      return;
    const hsize_t one = 1;
    const Id mem(H5Screate_simple(1, &one, nullptr), H5Sclose);
    H5Dread(d, memType, mem.get(), file.get(), H5P_DEFAULT, buf.data());
  }

  hid_t file_;
  Shared* shared_;
  size_t objects_ = 0;
  std::set<haddr_t> visited_;
};

/// The file as the check last saw it: a file that passed is not checked again while this stays.
/// A file changed within the last seconds (whose times a change in the same tick of the file
/// system's clock would not move) is also identified by a hash of its bytes.
struct Identity {
  dev_t dev;
  ino_t ino;
  off_t size;
  long mtimeSec, mtimeNsec, ctimeSec, ctimeNsec;
  uint64_t content = 0;
  auto key() const { return std::tie(dev, ino, size, mtimeSec, mtimeNsec, ctimeSec, ctimeNsec, content); }
  bool operator<(const Identity& o) const { return key() < o.key(); }
};

// Files changed this recently are hashed (up to kHashBytes; larger ones are checked every time).
constexpr long kRecentSeconds = 2;
constexpr uint64_t kHashBytes = uint64_t(64) << 20;

/// FNV-1a of the file's bytes, or false when it cannot be read.
bool hashFile(const std::string& path, uint64_t& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  uint64_t h = 0xcbf29ce484222325ull;
  std::vector<char> buf(size_t(1) << 16);
  while (in) {
    in.read(buf.data(), std::streamsize(buf.size()));
    const std::streamsize n = in.gcount();
    for (std::streamsize i = 0; i < n; ++i)
      h = (h ^ uint64_t(static_cast<unsigned char>(buf[size_t(i)]))) * 0x100000001b3ull;
  }
  out = h;
  return in.eof();
}

bool& childCheck() {
  static bool enabled = true;
  return enabled;
}

std::set<Identity>& checkedFiles() {
  static std::set<Identity> files;
  return files;
}

#ifndef EXABRICKS_H5_ASAN
long mappedBytes() {
  std::ifstream in("/proc/self/statm");
  long pages = 0;
  in >> pages;
  return pages * sysconf(_SC_PAGESIZE);
}
#endif

/// The child: plain deaths on fatal signals (no handlers inherited from the parent, no core
/// files), a memory and CPU limit, then the walk; exits 0 whatever libhdf5 reports.
[[noreturn]] void runCheck(const std::string& path, Shared* shared, long seconds) {
  for (int sig : {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT, SIGTRAP, SIGSYS})
    std::signal(sig, SIG_DFL);
  if (__sanitizer_set_death_callback) __sanitizer_set_death_callback(nullptr);
  const rlimit noCore{0, 0};
  setrlimit(RLIMIT_CORE, &noCore);
  const rlimit cpu{rlim_t(seconds + 5), rlim_t(seconds + 5)};
  setrlimit(RLIMIT_CPU, &cpu);
#ifndef EXABRICKS_H5_ASAN
  const rlim_t memory = rlim_t(uint64_t(mappedBytes()) + kCheckMemory);
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) == 0 && (as.rlim_cur == RLIM_INFINITY || as.rlim_cur > memory)) {
    as.rlim_cur = memory;
    setrlimit(RLIMIT_AS, &as);
  }
#endif
  try {
    silence();
    Id access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    if (access) H5Pset_fclose_degree(access.get(), H5F_CLOSE_STRONG);
    const Id file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, access ? access.get() : H5P_DEFAULT), H5Fclose);
    Walk walk(file.get(), shared);
    if (file)
      walk.object("/", false, 0);
    else
      shared->unopened = true;
  } catch (...) {
  }
  _exit(0);
}

/// The file's identity for the record of checked files; `remember` is false for a file changed
/// in the last seconds that cannot be hashed (it is checked every time).
Identity identify(const std::string& path, const struct stat& st, bool& remember) {
  Identity identity{st.st_dev,
                    st.st_ino,
                    st.st_size,
                    long(st.st_mtim.tv_sec),
                    long(st.st_mtim.tv_nsec),
                    long(st.st_ctim.tv_sec),
                    long(st.st_ctim.tv_nsec)};
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  const bool recent = long(now.tv_sec) - std::max(identity.mtimeSec, identity.ctimeSec) < kRecentSeconds;
  remember = !recent || (uint64_t(st.st_size) <= kHashBytes && hashFile(path, identity.content));
  return identity;
}

void warnUnchecked(const std::string& path) {
  logWarning(strCat(path, ": cannot check the HDF5 file in a separate process (", std::strerror(errno),
                    "); reading it directly"));
}

/// How the child ended; `known` is false when there is no verdict (it was reaped elsewhere).
struct Ending {
  bool known = false;
  bool timedOut = false;
  int status = 0;
};

/// Waits for the child until its end of the pipe `done` closes, killing it after `seconds`.
Ending awaitChild(pid_t pid, int done, long seconds, std::chrono::steady_clock::time_point start) {
  Ending e;
  for (;;) {
    const pid_t r = ::waitpid(pid, &e.status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) return e; // children reaped elsewhere (SIGCHLD ignored): no verdict
    const auto waited = std::chrono::steady_clock::now() - start;
    if (waited > std::chrono::seconds(seconds)) {
      ::kill(pid, SIGKILL);
      while (::waitpid(pid, &e.status, 0) < 0 && errno == EINTR) {
      }
      e.timedOut = true;
      break;
    }
    // Until the child's end of the pipe closes (it is ending: then wait for it), looking again
    // every 100 ms.
    pollfd fd{done, POLLIN, 0};
    if (::poll(&fd, 1, 100) > 0 && (fd.revents & POLLHUP)) {
      pid_t ended;
      while ((ended = ::waitpid(pid, &e.status, 0)) < 0 && errno == EINTR) {
      }
      if (ended == pid) break;
      return e; // reaped elsewhere: no verdict
    }
  }
  e.known = true;
  return e;
}

/// Throws DamagedFile when the child crashed, hung, ran out of memory, could not open the file
/// or met a structural failure.
void judge(const std::string& path, const Shared& shared, const Ending& e, long seconds) {
  const std::string where(shared.at, strnlen(shared.at, sizeof shared.at));
  const std::string fault(shared.fault, strnlen(shared.fault, sizeof shared.fault));
  const int status = e.status;
  if (e.timedOut)
    throw DamagedFile(strCat(path, ": damaged HDF5 file: libhdf5 did not finish reading its metadata within ", seconds,
                             " s (at ", where, ")"));
  if (WIFSIGNALED(status))
    throw DamagedFile(strCat(path, ": damaged HDF5 file: libhdf5 crashed (", strsignal(WTERMSIG(status)), ") reading ",
                             where, " (found in a separate process; the file cannot be read)"));
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw DamagedFile(strCat(path, ": damaged HDF5 file: reading ", where,
                             " failed in a separate process (exit status ",
                             WIFEXITED(status) ? WEXITSTATUS(status) : -1, "; out of memory?)"));
  if (shared.unopened)
    throw DamagedFile(strCat(path, ": cannot open as HDF5 (truncated or damaged file, or one locked by a writer?)"));
  if (!fault.empty())
    throw DamagedFile(strCat(path, ": damaged HDF5 file: libhdf5 cannot read ", fault,
                             " (found in a separate process; the file cannot be read)"));
}

} // namespace

void setChildCheck(bool enabled) {
  const Lock lock(libraryLock());
  childCheck() = enabled;
}

void checkInChild(const std::string& path) {
  const Lock lock(libraryLock());
  if (!childCheck()) return;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return; // opening it reports that
  bool remember = false;
  const Identity identity = identify(path, st, remember);
  if (remember && checkedFiles().count(identity)) return;

  void* page = ::mmap(nullptr, sizeof(Shared), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  int done[2] = {-1, -1}; // closed by the child's end: wakes the parent at once
  if (page == MAP_FAILED || ::pipe2(done, O_CLOEXEC) != 0) {
    if (page != MAP_FAILED) ::munmap(page, sizeof(Shared));
    warnUnchecked(path);
    return;
  }
  const std::unique_ptr<void, void (*)(void*)> unmap(page, [](void* p) { ::munmap(p, sizeof(Shared)); });
  Shared* shared = static_cast<Shared*>(page); // zeros, as mapped
  std::strcpy(shared->at, "the superblock and the root group");
  const long seconds = kCheckSeconds + long(st.st_size >> 30);
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(done[0]);
    runCheck(path, shared, seconds);
  }
  ::close(done[1]);
  if (pid < 0) {
    ::close(done[0]);
    warnUnchecked(path);
    return;
  }
  const Ending ending = awaitChild(pid, done[0], seconds, start);
  ::close(done[0]);
  if (!ending.known) return;
  judge(path, *shared, ending, seconds);
  if (remember) checkedFiles().insert(identity);
}

} // namespace exa::h5
