// Damaged copies of valid Chombo and FLASH files (both HDF5 file formats: symbol tables with
// B-trees and local heaps, and the newest format with version 2 object headers) must each give
// a clean error or a successful load, never a crash, a hang or an unbounded allocation. Every
// byte of the superblock and of every B-tree, symbol table node, heap and object header that
// carries a signature is damaged in turn, and bytes at a stride elsewhere; each copy is loaded
// in a forked child so that a crash fails the test instead of ending it. The quick sweep takes
// about 90 offsets a file; EXABRICKS_DAMAGE_SWEEP=full takes every one (minutes). This binary
// starts no threads of its own before forking.
#include "exabricks/core/error.h"
#include "exabricks/io/load.h"

#include "child_run.h"
#include "chombo_fixture.h"
#include "flash_fixture.h"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace exa;
namespace fs = std::filesystem;

namespace {

fs::path fresh(const std::string& name) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "damaged-hdf5" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string readBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void writeBytes(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
}

/// status: 0 loaded, 1 refused with exa::Error, 3 another exception, 128+N signal N.
using Outcome = test::ChildOutcome;

/// Lists the fields of `path` and loads its cells in a child process under a memory limit and
/// an alarm: the outcome and the message of the error, if any.
Outcome loadInChild(const std::string& path) {
  return test::runInChild(1L << 30, 60, [&](std::string& message) {
    try {
      listFields(path);
      loadCells(path);
    } catch (const Error& e) {
      message = e.what();
      return 1;
    } catch (const std::exception& e) {
      message = std::string("not an exa::Error: ") + e.what();
      return 3;
    }
    return 0;
  });
}

/// Offsets to damage: the superblock, the 160 bytes from each of libhdf5's structure signatures
/// (B-tree and symbol table nodes, heaps, object headers and their continuations, ...), and
/// every `stride`-th byte.
std::set<size_t> offsetsToDamage(const std::string& bytes, size_t stride) {
  static const char* kSignatures[] = {"TREE", "SNOD", "HEAP", "OHDR", "OCHK", "FRHP", "FHDB", "FHIB",
                                      "BTHD", "BTIN", "BTLF", "FSHD", "FSSE", "GCOL", "SMTB", "SMLI"};
  std::set<size_t> out;
  for (size_t i = 0; i < std::min<size_t>(bytes.size(), 136); ++i)
    out.insert(i);
  for (const char* sig : kSignatures)
    for (size_t at = bytes.find(sig); at != std::string::npos; at = bytes.find(sig, at + 1))
      for (size_t i = at; i < std::min(bytes.size(), at + 160); ++i)
        out.insert(i);
  for (size_t i = 0; i < bytes.size(); i += stride)
    out.insert(i);
  return out;
}

struct Tally {
  int loaded = 0, refused = 0;
  int crashedChild = 0; ///< refused because libhdf5 crashed (or hung) in the checking child
  int faultInChild = 0; ///< refused because libhdf5 reported a structural failure there
  std::vector<std::string> failures;
};

/// Offsets of a quick sweep: every `step`-th of the offsets to damage (all of them with
/// EXABRICKS_DAMAGE_SWEEP=full, about 12 ms a copy).
std::vector<size_t> sweep(const std::set<size_t>& offsets, size_t quickCount) {
  const char* mode = std::getenv("EXABRICKS_DAMAGE_SWEEP");
  const size_t step = mode && std::string(mode) == "full" ? 1 : std::max<size_t>(1, offsets.size() / quickCount);
  std::vector<size_t> out;
  size_t i = 0;
  for (size_t at : offsets)
    if (i++ % step == 0) out.push_back(at);
  return out;
}

/// Loads the valid file, then damaged copies: each byte of the sweep replaced by its complement,
/// by 0 and by 0xff (each distinct copy once).
Tally damageAndLoad(const fs::path& valid, size_t stride) {
  const Outcome ok = loadInChild(valid.string());
  EXPECT_EQ(ok.status, 0) << ok.message;
  const std::string bytes = readBytes(valid);
  const fs::path copy = valid.parent_path() / ("damaged" + valid.extension().string());
  Tally t;
  const auto start = std::chrono::steady_clock::now();
  for (size_t at : sweep(offsetsToDamage(bytes, stride), 90)) {
    for (int pattern = 0; pattern < 3; ++pattern) {
      std::string damaged = bytes;
      const unsigned char was = (unsigned char)bytes[at];
      const unsigned char now = pattern == 0 ? (unsigned char)~was : pattern == 1 ? 0 : 0xff;
      if (now == was || (pattern == 2 && was == 0)) continue; // the same copy as another pattern
      damaged[at] = char(now);
      writeBytes(copy, damaged);
      const Outcome o = loadInChild(copy.string());
      if (o.status == 0) {
        ++t.loaded;
      } else if (o.status == 1 && o.message.find(copy.filename().string()) != std::string::npos) {
        ++t.refused;
        if (o.message.find("libhdf5 cannot read") != std::string::npos)
          ++t.faultInChild;
        else if (o.message.find("separate process") != std::string::npos ||
                 o.message.find("did not finish") != std::string::npos)
          ++t.crashedChild;
      } else {
        t.failures.push_back(
            strCat("byte ", at, " set to ", int(now), " (was ", int(was),
                   "): ", o.status >= 128 ? strCat("killed by signal ", o.status - 128) : strCat("exit ", o.status),
                   ": ", o.message));
      }
    }
  }
  std::printf("%s: %zu bytes, %d damaged copies loaded, %d refused (libhdf5 crashed in the checking child: %d, "
              "reported a damaged structure there: %d), %zu failures, %.1f s\n",
              valid.filename().c_str(), bytes.size(), t.loaded, t.refused, t.crashedChild, t.faultInChild,
              t.failures.size(), std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return t;
}

void expectNoFailures(const Tally& t) {
  EXPECT_TRUE(t.failures.empty()) << t.failures.size()
                                  << " damaged copies crashed or failed badly; the first: " << t.failures.front();
  for (size_t i = 0; i < std::min<size_t>(t.failures.size(), 10); ++i)
    std::printf("  %s\n", t.failures[i].c_str());
}

} // namespace

TEST(DamagedHdf5, ChomboFilesGiveAnErrorOrLoad) {
  for (bool latest : {false, true}) {
    chombo_fixture::ChomboFixture f;
    f.latestFormat = latest;
    f.file = fresh(latest ? "chombo-latest" : "chombo") / "c.hdf5";
    f.write();
    expectNoFailures(damageAndLoad(f.file, 13));
  }
}

TEST(DamagedHdf5, FlashFilesGiveAnErrorOrLoad) {
  for (bool latest : {false, true}) {
    flash_fixture::FlashFixture f;
    f.latestFormat = latest;
    f.file = fresh(latest ? "flash-latest" : "flash") / "f.hdf5";
    f.write();
    expectNoFailures(damageAndLoad(f.file, 13));
  }
}

TEST(DamagedHdf5, FilesThatCrashedLibhdf5AreRefusedByName) {
  // Damaged copies that crashed libhdf5 (corrupt number and compound datatypes whose conversions
  // wrote outside their buffers) before the datatypes were checked, kept in fuzz/regressions.
  const fs::path dir = fs::path(EXABRICKS_SOURCE_DIR) / "fuzz" / "regressions" / "hdf5";
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    ++files;
    const Outcome o = loadInChild(entry.path().string());
    EXPECT_EQ(o.status, 1) << entry.path() << ": " << o.message;
    EXPECT_NE(o.message.find(entry.path().filename().string()), std::string::npos) << o.message;
    EXPECT_NE(o.message.find("corrupt"), std::string::npos) << o.message;
  }
  EXPECT_GE(files, 4);
}
