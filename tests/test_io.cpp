#include "datasets.h"
#include "exabricks/amr/basis.h"
#include "exabricks/core/error.h"
#include "exabricks/io/load.h"
#include "exabricks/io/model_file.h"
#include "exabricks/io/native.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sys/wait.h>
#include <unistd.h>

using namespace exa;
using namespace exa::test;
namespace fs = std::filesystem;

namespace {

class IoTest : public ::testing::Test {
protected:
  void SetUp() override {
    dir = fs::path(EXABRICKS_TEST_TMP) / ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  std::string path(const std::string& name) const { return (dir / name).string(); }
  void writeBytes(const std::string& name, const void* data, size_t size) const {
    std::ofstream(path(name), std::ios::binary).write(static_cast<const char*>(data), std::streamsize(size));
  }
  void writeText(const std::string& name, const std::string& text) const { std::ofstream(path(name)) << text; }
  /// Writes raw records and values as NAME.cells / NAME.scalars.
  void writeRaw(const std::string& name, const std::vector<Cell>& cells, const std::vector<float>& values) {
    writeBytes(name + ".cells", cells.data(), cells.size() * sizeof(Cell));
    writeBytes(name + ".scalars", values.data(), values.size() * sizeof(float));
  }
  /// The message of the error that loading `input` (building it too) throws.
  std::string loadError(const std::string& input) {
    try {
      loadModel(input);
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  }
  fs::path dir;
};

#define EXPECT_MESSAGE(msg, ...)                                                                                       \
  do {                                                                                                                 \
    const std::string m_ = (msg);                                                                                      \
    for (const char* part : {__VA_ARGS__})                                                                             \
      EXPECT_NE(m_.find(part), std::string::npos) << m_;                                                               \
  } while (0)

} // namespace

TEST_F(IoTest, NativeRoundTripWithSeveralFields) {
  const CellSet s = generateScene({"blobs", 2000, 1, 3});
  writeNative(s, path("a.cells"));
  EXPECT_TRUE(fs::exists(path("a.scalars")));
  EXPECT_TRUE(fs::exists(path("a.radius.scalars")));
  EXPECT_EQ(listNativeFields(path("a.cells")), (std::vector<std::string>{"radius", "scalar"}));
  const CellSet r = readNative(path("a.cells"));
  EXPECT_EQ(r.cells, s.cells);
  ASSERT_EQ(r.fields.size(), 2u);
  EXPECT_EQ(r.fields[r.fieldIndex("scalar")].values, s.fields[0].values);
  EXPECT_EQ(r.fields[r.fieldIndex("radius")].values, s.fields[1].values);
  const CellSet only = readNative(path("a.cells"), {"radius"});
  ASSERT_EQ(only.fields.size(), 1u);
  EXPECT_EQ(only.fields[0].name, "radius");
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << "temporary file left";
}

TEST_F(IoTest, NativeWriterInPiecesEqualsWholeWrite) {
  const CellSet s = generateScene({"blobs", 3000, 2, 3});
  writeNative(s, path("whole.cells"));
  {
    NativeWriter writer(path("pieces.cells"), {"scalar", "radius"});
    for (size_t begin = 0; begin < s.cells.size(); begin += 777) {
      const size_t end = std::min(s.cells.size(), begin + 777);
      CellSet piece;
      piece.cells.assign(s.cells.begin() + long(begin), s.cells.begin() + long(end));
      for (const Field& f : s.fields)
        piece.fields.push_back(
            {f.name, std::vector<float>(f.values.begin() + long(begin), f.values.begin() + long(end))});
      writer.append(piece);
      EXPECT_FALSE(fs::exists(path("pieces.cells"))) << "nothing is published before finish";
    }
    writer.finish();
  }
  for (const char* suffix : {".cells", ".scalars", ".radius.scalars"})
    EXPECT_EQ(readFile(path(std::string("whole") + suffix)), readFile(path(std::string("pieces") + suffix))) << suffix;
  {
    // A writer dropped before finish() leaves nothing behind.
    NativeWriter writer(path("dropped.cells"), {"scalar", "radius"});
    writer.append(s);
  }
  for (const auto& entry : fs::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().string().find("dropped"), std::string::npos) << entry.path();
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << "temporary file left";
  }
}

TEST_F(IoTest, GridsFixtureConstantAndTrilinear) {
  writeText("g.grids", "# a comment\n0 0 0 2 1 1 1 5.0\n\n4 0 0 2 2 2 0 0 1 0 1 0 1 0 1  # x ramp\n");
  const CellSet s = readGrids(path("g.grids"));
  ASSERT_EQ(s.cells.size(), 10u);
  EXPECT_EQ(s.cells[1], (Cell{vec3i(2, 0, 0), 1}));
  EXPECT_EQ(s.fields[0].values[0], 5.f);
  EXPECT_EQ(s.cells[2], (Cell{vec3i(4, 0, 0), 0}));
  EXPECT_FLOAT_EQ(s.fields[0].values[2], 0.25f);
  EXPECT_FLOAT_EQ(s.fields[0].values[3], 0.75f);
  EXPECT_MESSAGE(loadError(path("g.grids")), "no error");

  writeText("bad.grids", "0 0 0 1 1 1 0\n");
  EXPECT_MESSAGE(loadError(path("bad.grids")), "bad.grids", "line 1", "expected");
  writeText("mis.grids", "1 0 0 1 1 1 1 2.0\n");
  EXPECT_MESSAGE(loadError(path("mis.grids")), "mis.grids", "line 1", "not aligned");
  writeText("nan.grids", "0 0 0 1 1 1 0 nan\n");
  EXPECT_MESSAGE(loadError(path("nan.grids")), "nan.grids", "line 1", "finite");
  writeText("empty.grids", "# nothing\n");
  EXPECT_MESSAGE(loadError(path("empty.grids")), "empty.grids", "empty");
  writeText("over.grids", "0 0 0 2 2 2 1 1.0\n1 1 1 1 1 1 0 2.0\n");
  EXPECT_MESSAGE(loadError(path("over.grids")), "over.grids", "cells 0 ", "and 8 ", "overlap");
}

TEST_F(IoTest, EveryValidationErrorNamesFileRecordAndProblem) {
  const std::vector<Cell> good = {{vec3i(0, 0, 0), 1}, {vec3i(2, 0, 0), 1}, {vec3i(4, 0, 0), 0}};
  const std::vector<float> values = {1, 2, 3};

  writeRaw("ok", good, values);
  EXPECT_MESSAGE(loadError(path("ok.cells")), "no error");

  writeRaw("size", good, {1, 2});
  EXPECT_MESSAGE(loadError(path("size.cells")), "size.scalars", "size mismatch", "2 values for 3 cells");

  writeRaw("trunc", good, values);
  fs::resize_file(path("trunc.cells"), 3 * 16 - 5);
  EXPECT_MESSAGE(loadError(path("trunc.cells")), "trunc.cells", "truncated record 2");
  writeRaw("truncs", good, values);
  fs::resize_file(path("truncs.scalars"), 10);
  EXPECT_MESSAGE(loadError(path("truncs.cells")), "truncs.scalars", "truncated record 2");

  writeRaw("misaligned", {{vec3i(0, 0, 0), 1}, {vec3i(3, 0, 0), 1}}, {1, 2});
  EXPECT_MESSAGE(loadError(path("misaligned.cells")), "misaligned.cells", "record 1", "not aligned");

  writeRaw("neg", {{vec3i(0, 0, 0), 0}, {vec3i(1, 0, 0), -1}}, {1, 2});
  EXPECT_MESSAGE(loadError(path("neg.cells")), "neg.cells", "record 1", "negative level");

  writeRaw("absurd", {{vec3i(0, 0, 0), 40}}, {1});
  EXPECT_MESSAGE(loadError(path("absurd.cells")), "absurd.cells", "record 0", "absurd level 40");

  writeRaw("far", {{vec3i(2000000000, 0, 0), 0}}, {1});
  EXPECT_MESSAGE(loadError(path("far.cells")), "far.cells", "record 0", "outside");

  writeRaw("overlap", {{vec3i(0, 0, 0), 2}, {vec3i(8, 0, 0), 0}, {vec3i(1, 2, 3), 0}}, values);
  EXPECT_MESSAGE(loadError(path("overlap.cells")), "overlap.cells", "cells 0", "and 2", "overlap");

  writeRaw("dup", {{vec3i(0, 0, 0), 0}, {vec3i(1, 0, 0), 0}, {vec3i(1, 0, 0), 0}}, values);
  EXPECT_MESSAGE(loadError(path("dup.cells")), "dup.cells", "cells 1 and 2", "duplicates");

  writeRaw("nan", good, {1, std::nanf(""), 3});
  EXPECT_MESSAGE(loadError(path("nan.cells")), "nan.scalars", "record 1", "not finite");
  writeRaw("inf", good, {1, 2, INFINITY});
  EXPECT_MESSAGE(loadError(path("inf.cells")), "inf.scalars", "record 2", "not finite");

  writeRaw("empty", {}, {});
  EXPECT_MESSAGE(loadError(path("empty.cells")), "empty.cells", "empty");

  writeBytes("nofield.cells", good.data(), good.size() * sizeof(Cell));
  EXPECT_MESSAGE(loadError(path("nofield.cells")), "nofield.cells", "no field files");

  EXPECT_MESSAGE(loadError(path("missing.cells")), "missing.cells", "no such file");
  writeText("what.txt", "hello");
  EXPECT_MESSAGE(loadError(path("what.txt")), "what.txt", "unknown input format");

  LoadOptions o;
  o.fields = {"nope"};
  try {
    loadModel(path("ok.cells"), o);
    ADD_FAILURE() << "unknown field accepted";
  } catch (const Error& e) {
    EXPECT_MESSAGE(e.what(), "nope");
  }
}

namespace {
/// The two models hold the same world, fields, bricks and regions.
void expectSameModel(const Model& r, const Model& m) {
  EXPECT_EQ(r.world, m.world);
  EXPECT_EQ(r.fieldNames, m.fieldNames);
  EXPECT_EQ(r.fieldValues, m.fieldValues);
  ASSERT_EQ(r.bricks.size(), m.bricks.size());
  EXPECT_EQ(std::memcmp(r.bricks.data(), m.bricks.data(), m.bricks.size() * sizeof(Brick)), 0);
  EXPECT_EQ(r.regions.brickIds, m.regions.brickIds);
  EXPECT_EQ(r.regions.valueRanges, m.regions.valueRanges);
  ASSERT_EQ(r.regions.regions.size(), m.regions.regions.size());
  EXPECT_EQ(std::memcmp(r.regions.regions.data(), m.regions.regions.data(), m.regions.regions.size() * sizeof(Region)),
            0);
}
} // namespace

TEST_F(IoTest, ModelFileRoundTrip) {
  CellSet s = generateScene({"shells", 3000, 1, 4});
  const Model m = buildModel(std::move(s));
  writeModel(m, path("m.exa"));
  EXPECT_TRUE(isModelFile(path("m.exa")));
  const Model r = loadModel(path("m.exa")); // detected by magic, not by extension
  expectSameModel(r, m);
  double a, b;
  const vec3d p(40.3, 41.7, 12.2);
  EXPECT_EQ(sampleField(m.view(0), p, a), sampleField(r.view(0), p, b));
}

TEST_F(IoTest, NativeInputsBuildTheirValuesAfterTheBricksIntoTheSameModel) {
  // loadModel reads a NAME.cells input's values after building its bricks: the same model as
  // building the cells read with their values, for every selection of fields.
  writeNative(generateScene({"blobs", 4000, 3, 4}), path("v.cells"));
  for (const std::vector<std::string>& fields :
       {std::vector<std::string>{}, {"radius"}, {"scalar", "radius"}, {"scalar", "radius", "scalar"}}) {
    SCOPED_TRACE(fields.size());
    LoadOptions o;
    o.fields = fields;
    o.partCells = 0;
    CellSet cells = readNative(path("v.cells"), fields);
    expectSameModel(loadModel(path("v.cells"), o), buildModel(std::move(cells)));
  }
}

TEST_F(IoTest, ModelFileValuesAreUsedInPlaceAndVersion1IsStillRead) {
  const Model m = buildModel(generateScene({"blobs", 400, 1, 4}));
  writeModel(m, path("m.exa"));
  const Model r = readModel(path("m.exa"));
  // Version 2 aligns the values: they are a view into the mapped file (not a heap copy).
  ASSERT_FALSE(r.fieldValues.empty());
  for (size_t f = 0; f < r.fieldValues.size(); ++f) {
    EXPECT_EQ(reinterpret_cast<uintptr_t>(r.fieldValues[f].data()) % alignof(float), 0u);
    EXPECT_EQ(r.fieldValues[f], m.fieldValues[f]);
  }
  // The mapping outlives the model it came from for as long as a copy of the values lives.
  ValueArray kept;
  {
    const Model again = readModel(path("m.exa"));
    kept = again.fieldValues[0];
  }
  EXPECT_EQ(kept, m.fieldValues[0]);
  // A version 1 file (the layout earlier releases wrote: no padding) of `exabricks build` over
  // `exabricks generate -n 400` reads to a model of the same data as the one built now from the
  // same cells (whose bricks may be cut differently): the same world, fields and cells, and the
  // same reconstruction everywhere.
  writeNative(generateScene({"blobs", 400, 1, 4}), path("b.cells"));
  const Model built = loadModel(path("b.cells"));
  const Model v1 = readModel(std::string(EXABRICKS_REFERENCE_DIR) + "/blobs400-v1.model");
  EXPECT_EQ(v1.world, built.world);
  EXPECT_EQ(v1.fieldNames, built.fieldNames);
  ASSERT_EQ(v1.fieldValues.size(), built.fieldValues.size());
  for (size_t f = 0; f < v1.fieldValues.size(); ++f) {
    std::vector<float> a(v1.fieldValues[f].begin(), v1.fieldValues[f].end());
    std::vector<float> b(built.fieldValues[f].begin(), built.fieldValues[f].end());
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    EXPECT_EQ(a, b) << "field " << f;
  }
  EXPECT_EQ(v1.cellBounds(), built.cellBounds());
  const FieldView va = v1.view(0), vb = built.view(0);
  const box3i cb = built.cellBounds();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < 2000; ++i) {
    const vec3f p = vec3f(cb.lower) + vec3f(cb.size()) * vec3f(u(rng), u(rng), u(rng));
    float a = 0.f, b = 0.f;
    const bool ha = sampleField(va, p, a), hb = sampleField(vb, p, b);
    ASSERT_EQ(ha, hb) << "at " << p.x << " " << p.y << " " << p.z;
    if (ha) {
      EXPECT_NEAR(a, b, 1e-5f * (1.f + std::abs(b))) << "at " << p.x << " " << p.y << " " << p.z;
    }
  }
}

TEST_F(IoTest, CorruptTruncatedAndForeignModelsAreRejected) {
  CellSet s = generateScene({"blobs", 1000, 1, 3});
  const Model m = buildModel(std::move(s));
  writeModel(m, path("m.exa"));
  std::vector<char> bytes = readFile(path("m.exa"));

  std::vector<char> flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x10;
  writeBytes("flipped.exa", flipped.data(), flipped.size());
  EXPECT_MESSAGE(loadError(path("flipped.exa")), "flipped.exa", "corrupt");

  writeBytes("short.exa", bytes.data(), bytes.size() - 100);
  EXPECT_MESSAGE(loadError(path("short.exa")), "short.exa", "truncated");

  writeBytes("header.exa", bytes.data(), 20);
  EXPECT_MESSAGE(loadError(path("header.exa")), "header.exa", "truncated");

  std::vector<char> version = bytes;
  version[8] = 99;
  writeBytes("version.exa", version.data(), version.size());
  EXPECT_MESSAGE(loadError(path("version.exa")), "version.exa", "version 99");

  // A huge count in the brick array header must not allocate or crash.
  std::vector<char> huge = bytes;
  const uint64_t count = uint64_t(1) << 60;
  std::memcpy(huge.data() + 48 + sizeof(WorldTransform), &count, 8);
  writeBytes("huge.exa", huge.data(), huge.size());
  EXPECT_MESSAGE(loadError(path("huge.exa")), "huge.exa", "corrupt");

  writeText("foreign.cells", "EXABRMDX and then some text that is not a model");
  EXPECT_MESSAGE(loadError(path("foreign.cells")), "foreign.cells");
}

TEST_F(IoTest, ModelsWhoseTreeDoesNotMatchTheirRegionsAreRejected) {
  // Valid checksums over inconsistent contents: the traversal relies on each k-d leaf's cell
  // being its region's box, and on the tree being a tree.
  Model m = buildModel(generateScene({"blobs", 5000, 2, 3}));
  ASSERT_GT(m.regions.nodes.size(), 7u);
  writeModel(m, path("good.exa"));
  EXPECT_NO_THROW(readModel(path("good.exa")));

  Model grown = m;
  grown.regions.regions[0].halfBounds.upper.x += 2;
  writeModel(grown, path("grown.exa"));
  EXPECT_MESSAGE(loadError(path("grown.exa")), "grown.exa", "region 0 does not fill its k-d cell");

  Model shared = m; // both children of the root lead to the same subtree
  const uint32_t child = shared.regions.nodes[0].index;
  ASSERT_NE(shared.regions.nodes[child].axis, kLeafAxis);
  shared.regions.nodes[child + 1] = shared.regions.nodes[child];
  writeModel(shared, path("shared.exa"));
  // Whichever inconsistency the check meets first: a split outside its cell, a region beside
  // its cell, or the shared node.
  EXPECT_MESSAGE(loadError(path("shared.exa")), "shared.exa", "corrupt model file", "k-d");
}

TEST_F(IoTest, FailedWritesLeaveNoFile) {
  CellSet s = generateScene({"blobs", 500, 1, 2});
  const Model m = buildModel(std::move(s));
  EXPECT_THROW(writeModel(m, path("no/such/dir/m.exa")), Error);
  EXPECT_FALSE(fs::exists(path("no")));
}

TEST_F(IoTest, FilesArePublishedTogetherOrNotAtAll) {
  const std::string a = (dir / "a.bin").string(), b = (dir / "b.bin").string();
  const char data[4] = {1, 2, 3, 4};
  auto leftovers = [&] {
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir))
      n += e.path().filename().string().find(".tmp") != std::string::npos;
    return n;
  };
  {
    AtomicFiles files;
    files.write(a, data, 4);
    files.write(b, data, 4);
    EXPECT_FALSE(fs::exists(a)); // nothing appears before commit
    EXPECT_EQ(leftovers(), 2);
  } // not committed: the temporaries go
  EXPECT_FALSE(fs::exists(a));
  EXPECT_EQ(leftovers(), 0);
  {
    AtomicFiles files;
    files.write(a, data, 4);
    files.write(b, data, 4);
    files.commit();
  }
  EXPECT_EQ(fs::file_size(a), 4u);
  EXPECT_EQ(fs::file_size(b), 4u);
  EXPECT_EQ(leftovers(), 0);
  // What an interrupt handler calls: every pending temporary is removed.
  AtomicFiles pending;
  pending.write((dir / "c.bin").string(), data, 4);
  EXPECT_EQ(leftovers(), 1);
  removePendingTemporaries();
  EXPECT_EQ(leftovers(), 0);
}

TEST_F(IoTest, ModelHeadersWithReservedBytesSetAreRejected) {
  CellSet s = generateScene({"blobs", 500, 1, 2});
  writeModel(buildModel(std::move(s)), path("m.exa"));
  std::vector<char> bytes = readFile(path("m.exa"));
  bytes[40] = 1; // the second reserved word of the 48-byte header
  writeBytes("reserved.exa", bytes.data(), bytes.size());
  EXPECT_MESSAGE(loadError(path("reserved.exa")), "reserved.exa", "reserved bytes", "not zero");
}

TEST_F(IoTest, TemporariesOfKilledWritesAreRemovedByTheNextWrite) {
  // A write killed before it could clean up leaves TARGET.tmpPID.INDEX; a process that no longer
  // runs cannot own it. Temporaries of running processes and other files stay.
  const pid_t child = fork();
  if (child == 0) _exit(0);
  ASSERT_GT(child, 0);
  ASSERT_EQ(waitpid(child, nullptr, 0), child);
  const std::string dead = std::to_string(child), alive = std::to_string(getppid());
  for (const std::string& name :
       std::vector<std::string>{"m.exa.tmp" + dead + ".0", "m.exa.tmp" + dead, "d.cells.tmp" + dead + ".0",
                                "d.scalars.tmp" + dead + ".1", "m.exa.tmp" + alive + ".0", "m.exa.tmpx.0"})
    writeText(name, "partial");
  CellSet s = generateScene({"blobs", 500, 1, 2});
  writeNative(s, path("d.cells"));
  writeModel(buildModel(std::move(s)), path("m.exa"));
  for (const std::string& gone : std::vector<std::string>{"m.exa.tmp" + dead + ".0", "m.exa.tmp" + dead,
                                                          "d.cells.tmp" + dead + ".0", "d.scalars.tmp" + dead + ".1"})
    EXPECT_FALSE(fs::exists(path(gone))) << gone;
  for (const std::string& kept : std::vector<std::string>{"m.exa.tmp" + alive + ".0", "m.exa.tmpx.0"})
    EXPECT_TRUE(fs::exists(path(kept))) << kept;
}

TEST_F(IoTest, GridsFixturesAreBoundedBeforeExpanding) {
  writeText("big.grids", "0 0 0 1000 1000 1000 0 1.0\n");
  EXPECT_MESSAGE(loadError(path("big.grids")), "big.grids", "line 1", "1000x1000x1000", "at most");
}

TEST(IoFuzzRegressions, ModelFilesFoundByFuzzingAreReadOrRefused) {
  // Inputs on which fuzzing found undefined behaviour (zero-length arrays copied through null
  // pointers, fuzz/regressions/model): each reads cleanly or fails naming the file; under the
  // sanitizer build any undefined behaviour stops the test.
  const std::filesystem::path dir = std::filesystem::path(EXABRICKS_SOURCE_DIR) / "fuzz" / "regressions" / "model";
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    ++files;
    try {
      const Model m = readModel(entry.path().string());
      EXPECT_EQ(m.fieldNames.size(), m.fieldValues.size()) << entry.path();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(entry.path().filename().string()), std::string::npos) << e.what();
    }
  }
  EXPECT_GE(files, 4);
}
