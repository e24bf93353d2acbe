// Writes seed inputs for the fuzz targets from the project's own writers, so that the seeds
// follow the current formats (fuzz/run_all.sh runs it into each target's corpus):
//   fuzz_seeds model DIR   valid model files of several sizes, in version 1 (no padding) and
//                          version 2 (arrays aligned to 8 bytes), and one with every array empty
//   fuzz_seeds hdf5 DIR    the Chombo and FLASH test fixtures in both HDF5 file formats
#include "model_bytes.h"

#include "../tests/chombo_fixture.h"
#include "../tests/flash_fixture.h"

#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/io/model_file.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <type_traits>

namespace fs = std::filesystem;

namespace {

/// The model file layout of src/io/model_file.cpp written by hand for one version: every array
/// is its uint64 length, then (version 2) zeros up to a multiple of 8 bytes in the file, then
/// its data.
class LayoutWriter {
public:
  explicit LayoutWriter(uint32_t version) : version_(version), bytes_(fuzz::kModelHeaderBytes, '\0') {}
  template <typename T> void value(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    raw(&v, sizeof v);
  }
  template <typename A> void array(const A& a) {
    value(uint64_t(a.size()));
    if (version_ >= 2)
      while (bytes_.size() % 8 != 0)
        bytes_.push_back('\0');
    if (a.size() > 0) raw(a.data(), a.size() * sizeof(*a.data()));
  }
  void raw(const void* p, size_t n) { bytes_.append(static_cast<const char*>(p), n); }
  std::string finish() {
    std::memcpy(bytes_.data(), exa::kModelMagic, 8);
    std::memcpy(bytes_.data() + 8, &version_, 4);
    const uint32_t header = uint32_t(fuzz::kModelHeaderBytes);
    std::memcpy(bytes_.data() + 12, &header, 4);
    return fuzz::sealModel(bytes_);
  }

private:
  uint32_t version_;
  std::string bytes_;
};

std::string modelBytes(const exa::Model& m, uint32_t version) {
  LayoutWriter w(version);
  w.value(m.world);
  w.array(m.bricks);
  w.value(uint64_t(m.fieldNames.size()));
  for (size_t f = 0; f < m.fieldNames.size(); ++f) {
    w.value(uint64_t(m.fieldNames[f].size()));
    w.raw(m.fieldNames[f].data(), m.fieldNames[f].size());
    w.array(m.fieldValues[f]);
  }
  w.array(m.regions.regions);
  w.array(m.regions.brickIds);
  w.array(m.regions.nodes);
  w.value(m.regions.bounds);
  for (size_t f = 0; f < m.fieldNames.size(); ++f)
    w.array(m.regions.valueRanges[f]);
  for (double s : {m.stats.brickSeconds, m.stats.regionSeconds, m.stats.rangeSeconds})
    w.value(s);
  return w.finish();
}

void save(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
}

void modelSeeds(const fs::path& dir) {
  struct Size {
    const char* scene;
    uint64_t cells;
    int levels;
  };
  // From one brick (about 400 bytes) to about 22 KB, all within the fuzzers' -max_len.
  for (const Size& s : {Size{"blobs", 8, 1}, Size{"blobs", 100, 1}, Size{"shells", 60, 2}, Size{"blobs", 1000, 3},
                        Size{"blobs", 3000, 2}}) {
    const exa::Model m = exa::buildModel(exa::generateScene({s.scene, s.cells, 1, s.levels}));
    const std::string name = std::string(s.scene) + "-" + std::to_string(s.cells);
    for (uint32_t version : {1u, 2u})
      save(dir / (name + "-v" + std::to_string(version)), modelBytes(m, version));
    exa::writeModel(m, (dir / (name + "-current")).string());
  }
  // Every array empty: no bricks, fields, regions or k-d nodes; then one brick and one field of
  // no values whose (version 1) array starts at an odd offset, after a name of three bytes.
  exa::Model empty;
  for (uint32_t version : {1u, 2u})
    save(dir / ("empty-v" + std::to_string(version)), modelBytes(empty, version));
  empty.bricks.resize(1);
  empty.fieldNames = {"abc"};
  empty.fieldValues.resize(1);
  empty.regions.valueRanges.resize(1);
  for (uint32_t version : {1u, 2u})
    save(dir / ("empty-field-v" + std::to_string(version)), modelBytes(empty, version));
}

void hdf5Seeds(const fs::path& dir) {
  for (bool latest : {false, true}) {
    const std::string format = latest ? "-latest" : "";
    chombo_fixture::ChomboFixture c;
    c.latestFormat = latest;
    c.file = dir / ("chombo" + format + ".hdf5");
    c.write();
    c.file = dir / ("chombo-ghost-float" + format + ".hdf5");
    c.ghost = 1;
    c.float32 = true;
    c.write();
    flash_fixture::FlashFixture f;
    f.latestFormat = latest;
    f.file = dir / ("flash" + format + ".hdf5");
    f.write();
    f.file = dir / ("flash-float" + format + ".hdf5");
    f.float32 = true;
    f.write();
  }
}

} // namespace

int main(int argc, char** argv) {
  if (argc != 3 || (std::string(argv[1]) != "model" && std::string(argv[1]) != "hdf5")) {
    std::fprintf(stderr, "usage: fuzz_seeds model|hdf5 DIR\n");
    return 2;
  }
  const fs::path dir = argv[2];
  fs::create_directories(dir);
  try {
    if (std::string(argv[1]) == "model")
      modelSeeds(dir);
    else
      hdf5Seeds(dir);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
