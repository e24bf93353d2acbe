// Steps held in parts under a memory budget: sizes as people write them, plans that fit the
// budget (or name the smallest that works), frames drawn part by part equal to the in-core render
// (several passes, so the per-pass compositing counts) and the same when the parts come back from
// the disk, and a step that changes while its parts are read is reported instead of drawn mixed.
#include "asan.h"
#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/core/text.h"
#include "exabricks/io/amrex_write.h"
#include "exabricks/io/model_file.h"
#include "exabricks/io/native.h"
#include "exabricks/workflows/coarse_first.h"
#include "exabricks/workflows/streamed.h"
#include "merged_leaves_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace exa;

// Under AddressSanitizer the process's size grows with its quarantine from one plan to the next;
// plans are checked in the other builds.
#ifdef EXABRICKS_ASAN
#define SKIP_PLANS_UNDER_ASAN() GTEST_SKIP() << "the sanitizer's quarantine grows the process between plans"
#else
#define SKIP_PLANS_UNDER_ASAN() (void)0
#endif

namespace {

std::string writeStep(const std::string& name, uint64_t cells) {
  const std::string dir = std::string(EXABRICKS_TEST_TMP) + "/streamed";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/" + name + ".cells";
  writeNative(generateScene({"blobs", cells, 3, 4}), path);
  return path;
}

/// The step in `parts` k-d parts (whatever the process's size now), with room for `resident`
/// of them beside the process.
MemoryPlan planOfParts(const std::string& path, int parts, int resident, uint64_t frameBytes) {
  MemoryPlan plan = planMemory(path, {}, uint64_t(64) << 30, frameBytes);
  const Census census = loadCensus(path);
  plan.partition = KdPartition::balance(census, parts, int64_t(1) << census.coarsestLevel);
  plan.partCells.assign(size_t(parts), plan.cells / parts);
  plan.budget = plan.fixedBytes + uint64_t(resident) * plan.largestPartBytes();
  return plan;
}

/// An AMReX plotfile of about `cells` cells in `levels` levels (the census then comes from its
/// boxes).
std::string writePlotfile(const std::string& name, uint64_t cells, int levels = 4) {
  const std::string dir = std::string(EXABRICKS_TEST_TMP) + "/streamed";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/" + name + ".plt";
  std::filesystem::remove_all(path);
  const SceneOptions o = resolveSceneSize({"blobs", cells, 3, levels});
  std::unique_ptr<AmrexPlotfileWriter> writer;
  generateScenePieces(o, AmrexPlotfileWriter::kSlabCells, [&](CellSet& piece) {
    std::vector<std::string> names;
    for (const Field& f : piece.fields)
      names.push_back(f.name);
    if (!writer)
      writer = std::make_unique<AmrexPlotfileWriter>(path, names, o.levels, int64_t(sceneLatticeWidth(o)), true);
    writer->append(piece);
  });
  writer->finish();
  return path;
}

/// The in-core criterion: mean <= 0.5/255, 99.9 % of the channels within 2/255 (parts end their
/// regions, and so their sampling steps, at the part planes).
void expectEqualToInCore(const Image& image, const Image& reference) {
  ASSERT_EQ(image.pixels.size(), reference.pixels.size());
  double sum = 0;
  size_t beyond = 0;
  for (size_t i = 0; i < image.pixels.size(); ++i)
    for (int c = 0; c < 4; ++c) {
      const float* a = &image.pixels[i].x;
      const float* r = &reference.pixels[i].x;
      const double d = std::abs(double(a[c]) - double(r[c]));
      sum += d;
      beyond += d > 2.0 / 255.0 ? 1 : 0;
    }
  EXPECT_LE(sum / double(4 * image.pixels.size()), 0.5 / 255.0);
  EXPECT_LE(double(beyond), 0.001 * double(4 * image.pixels.size()));
}

/// The step's first field in viridis, at 0.3 of its default opacity.
Scene sceneOf(const Model& model) {
  Scene scene = Scene::volumeOf(defaultTransferFunction("viridis"), model.fieldNames[0]);
  scene.layers[0].tf.opacityScale = 0.3f;
  return scene;
}

/// The step rendered whole.
Image inCore(const Model& model, const Scene& scene, const Frame& frame) {
  Renderer whole(model);
  whole.setScene(scene);
  return whole.render(frame);
}

/// A view of `model` from above one corner.
Frame frameOf(const Model& model, int samplesPerPixel) {
  Frame frame;
  frame.width = 64;
  frame.height = 48;
  frame.samplesPerPixel = samplesPerPixel;
  frame.jitter = samplesPerPixel > 1;
  const box3d b = model.worldBounds();
  frame.camera.lookAt = (b.lower + b.upper) * 0.5;
  frame.camera.position = frame.camera.lookAt + vec3d(0.4, 0.5, 1.4) * length(b.size());
  return frame;
}

} // namespace

TEST(Streamed, ByteSizesAsPeopleWriteThem) {
  uint64_t b = 0;
  EXPECT_TRUE(parseByteSize("512M", b) && b == uint64_t(512) << 20);
  EXPECT_TRUE(parseByteSize("2G", b) && b == uint64_t(2) << 30);
  EXPECT_TRUE(parseByteSize("1.5GiB", b) && b == uint64_t(3) << 29);
  EXPECT_TRUE(parseByteSize("64mb", b) && b == uint64_t(64) << 20);
  EXPECT_TRUE(parseByteSize("300k", b) && b == 300 * 1024);
  EXPECT_TRUE(parseByteSize("1000000", b) && b == 1000000);
  for (const char* bad : {"", "0", "-1G", "G", "2X", "2 G", "1e30", "nan", "2GB extra", "0.1"})
    EXPECT_FALSE(parseByteSize(bad, b)) << bad;
  EXPECT_EQ(formatBytes(512), "512 B");
  EXPECT_EQ(formatBytes(uint64_t(3) << 29), "1.50 GiB");
}

TEST(Streamed, PlansFitTheBudgetOrNameTheSmallestThatWorks) {
  SKIP_PLANS_UNDER_ASAN();
  const std::string path = writeStep("plan", 600000);
  const uint64_t frame = streamedFrameBytes(64, 64, 1);
  const MemoryPlan whole = planMemory(path, {}, uint64_t(64) << 30, frame);
  EXPECT_FALSE(whole.streamed());
  // Three quarters of the step beside the process; where the process grew since (sanitizer
  // builds' shadow memory) and that no longer holds a part, the smallest budget named then.
  MemoryPlan parts;
  try {
    parts = planMemory(path, {}, whole.fixedBytes + uint64_t(whole.cells * double(whole.bytesPerCell)) * 3 / 4, frame);
  } catch (const BudgetTooSmall& e) {
    parts = planMemory(path, {}, e.smallest + (uint64_t(4) << 20), frame);
  }
  ASSERT_TRUE(parts.streamed());
  EXPECT_LE(parts.fixedBytes + parts.largestPartBytes(), parts.budget);
  try {
    planMemory(path, {}, whole.fixedBytes + 1024, frame);
    FAIL() << "a budget without room for a part was taken";
  } catch (const BudgetTooSmall& e) {
    EXPECT_GT(e.smallest, whole.fixedBytes);
    EXPECT_NE(std::string(e.what()).find("smallest budget that works"), std::string::npos) << e.what();
    // The budget named works (the process's own size may have grown a little since).
    EXPECT_TRUE(planMemory(path, {}, e.smallest + (uint64_t(4) << 20), frame).streamed());
  }
}

TEST(Streamed, AViewsPartsArePlannedBesideTheCoarseLevelsItHolds) {
  SKIP_PLANS_UNDER_ASAN();
  const uint64_t frame = streamedFrameBytes(64, 64, 1);
  const std::string path = writePlotfile("beside", 4000000);
  const MemoryPlan whole = sizeMemory(path, {}, uint64_t(64) << 30, frame);
  ASSERT_TRUE(whole.fitsWhole());
  const uint64_t step = uint64_t(whole.cells * double(whole.bytesPerCell));
  // Whole: nothing to plan. Under a budget that does not hold the step: coarse levels, and parts
  // whose largest fits beside them and the process.
  EXPECT_FALSE(coarseBesideParts(path, {}, whole.fixedBytes + 2 * step, frame, 0, "a test"));
  std::optional<CoarseBeside> beside;
  uint64_t budget = whole.fixedBytes + step / 2;
  try {
    beside = coarseBesideParts(path, {}, budget, frame, 0, "a test");
  } catch (const BudgetTooSmall& e) { // the process grew since (sanitizer builds' shadow memory)
    budget = e.smallest + (uint64_t(4) << 20);
    beside = coarseBesideParts(path, {}, budget, frame, 0, "a test");
  }
  ASSERT_TRUE(beside);
  ASSERT_GT(beside->coarse.level, 0);
  ASSERT_TRUE(beside->parts.streamed());
  const uint64_t coarse = uint64_t(std::ceil(beside->coarse.coarseCells)) * beside->parts.bytesPerCell;
  EXPECT_EQ(beside->parts.budget, budget - coarse);
  EXPECT_LE(beside->parts.fixedBytes + beside->parts.largestPartBytes() + coarse, budget);
  // A budget that holds no part beside the coarse levels is refused, naming one that does.
  try {
    coarseBesideParts(path, {}, whole.fixedBytes + step / 100, frame, 0, "a test");
    FAIL() << "a budget without room for a part beside the coarse levels was taken";
  } catch (const BudgetTooSmall& e) {
    EXPECT_NE(std::string(e.what()).find("beside the parts"), std::string::npos) << e.what();
    const std::optional<CoarseBeside> named =
        coarseBesideParts(path, {}, e.smallest + (uint64_t(4) << 20), frame, 0, "a test");
    ASSERT_TRUE(named);
    EXPECT_TRUE(named->parts.streamed());
  }
}

TEST(Streamed, FramesFromPartsEqualTheInCoreRender) {
  const std::string path = writeStep("frame", 120000);
  const Model model = loadModel(path);
  const Scene scene = sceneOf(model);
  const Frame frame = frameOf(model, 3); // jittered passes, each composited over the parts
  const Image reference = inCore(model, scene, frame);

  const MemoryPlan plan = planOfParts(path, 4, 1, streamedFrameBytes(64, 48, 3));
  StreamedStep step(path, {}, plan);
  EXPECT_EQ(step.survey().cells, model.cellCount());
  const DatasetInfo in = DatasetInfo::of(model), parts = step.survey().dataset;
  EXPECT_EQ(in.referenceWidth, parts.referenceWidth);
  EXPECT_EQ(in.extentCells, parts.extentCells);
  ASSERT_EQ(in.valueRanges.size(), parts.valueRanges.size());
  for (size_t f = 0; f < in.valueRanges.size(); ++f)
    EXPECT_TRUE(in.valueRanges[f].lower == parts.valueRanges[f].lower &&
                in.valueRanges[f].upper == parts.valueRanges[f].upper)
        << f;
  FrameBuffer buffer;
  ASSERT_TRUE(renderStreamed(step, scene, RendererOptions(), frame, buffer));
  const Image image = buffer.resolve();
  ASSERT_EQ(image.pixels.size(), reference.pixels.size());
  expectEqualToInCore(image, reference);
  EXPECT_LE(step.residentBytes() + plan.fixedBytes, plan.budget);

  // Again: the parts that the budget did not keep come back from the disk (their models and
  // smooth shading's gradients, as built: not in the bricks only their halos' regions hold), and
  // the frame is the same to the bit.
  const uint64_t fromDisk = step.partsFromDisk();
  EXPECT_EQ(step.gradientsFromDisk(), 0u);
  FrameBuffer again;
  ASSERT_TRUE(renderStreamed(step, scene, RendererOptions(), frame, again));
  EXPECT_GT(step.partsFromDisk(), fromDisk);
  EXPECT_GT(step.gradientsFromDisk(), 0u);
  const Image second = again.resolve();
  for (size_t i = 0; i < image.pixels.size(); ++i)
    ASSERT_TRUE(image.pixels[i].x == second.pixels[i].x && image.pixels[i].y == second.pixels[i].y &&
                image.pixels[i].z == second.pixels[i].z && image.pixels[i].w == second.pixels[i].w)
        << i;

  // Shown as it goes (the viewer): a picture of every level after one pass over the parts, then
  // the rest of the passes, which end in the same frame.
  std::vector<int> shown;
  FrameBuffer progressive;
  ASSERT_TRUE(
      renderStreamed(step, scene, RendererOptions(), frame, progressive, {}, [&](const FrameBuffer& sofar, int passes) {
        shown.push_back(passes);
        EXPECT_EQ(sofar.resolve().pixels.size(), image.pixels.size());
      }));
  EXPECT_EQ(shown, std::vector<int>{1});
  const Image third = progressive.resolve();
  for (size_t i = 0; i < image.pixels.size(); ++i)
    ASSERT_TRUE(image.pixels[i].x == third.pixels[i].x && image.pixels[i].w == third.pixels[i].w) << i;
}

TEST(Streamed, AModelFileIsReadBrickByBrickInPartsEqualToTheWhole) {
  // `build`'s model of a NAME.cells step: its census from the brick table, each part built from
  // the bricks that reach it, read on demand from the file, and the frame that of the whole.
  const std::string cells = writeStep("model", 120000);
  const std::string path = cells.substr(0, cells.size() - 6) + ".model";
  writeModel(loadModel(cells), path);
  const Model model = loadModel(path);
  const Census census = loadCensus(path);
  EXPECT_DOUBLE_EQ(census.cells(), double(model.cellCount()));
  EXPECT_EQ(census.boxes.size(), model.bricks.size());
  EXPECT_EQ(listFields(path), model.fieldNames);
  const Scene scene = sceneOf(model);
  const Frame frame = frameOf(model, 2);
  const Image reference = inCore(model, scene, frame);
  const MemoryPlan plan = planOfParts(path, 4, 1, streamedFrameBytes(64, 48, 2));
  StreamedStep step(path, {}, plan);
  EXPECT_EQ(step.survey().cells, model.cellCount());
  FrameBuffer buffer;
  ASSERT_TRUE(renderStreamed(step, scene, RendererOptions(), frame, buffer));
  expectEqualToInCore(buffer.resolve(), reference);
  // A part's cells are the whole model's cells that reach it, value for value.
  const box3l part = step.partBox(0);
  const std::optional<Model> first = loadModelPart(path, {}, part, plan.coarsestLevel);
  const std::optional<Model> fromCells = loadModelPart(cells, {}, part, plan.coarsestLevel);
  ASSERT_TRUE(first && fromCells);
  EXPECT_EQ(first->cellCount(), fromCells->cellCount());

  // A brick whose values are damaged is named when it is read; a truncated file at once.
  const Brick& b = model.bricks[model.bricks.size() / 2];
  const ModelTable table = readModelTable(path);
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    const float nan = std::nanf("");
    f.seekp(std::streamoff(table.valuesAt[0] + uint64_t(b.valueOffset) * sizeof(float)));
    f.write(reinterpret_cast<const char*>(&nan), sizeof nan);
  }
  const std::string brick = strCat(": brick ", model.bricks.size() / 2, ": field");
  try {
    loadModelPart(path, {}, box3l(vec3l(b.lower), vec3l(b.bounds().upper)), plan.coarsestLevel);
    FAIL() << "a damaged brick was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path + brick), std::string::npos) << e.what();
  }
  // Every cell merged for a viewer's first picture leaves that brick out (and says so).
  const std::optional<MergedLeaves> merged = loadMergedLeaves(path, {}, 2000);
  ASSERT_TRUE(merged);
  EXPECT_GT(merged->model.cellCount(), 0u);
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 8);
  try {
    loadCensus(path);
    FAIL() << "a truncated model file was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

TEST(Streamed, AStepChangedWhileItsPartsAreReadIsReported) {
  const std::string path = writeStep("changing", 120000);
  const MemoryPlan plan = planOfParts(path, 4, 1, 0);
  StreamedStep step(path, {}, plan);
  std::filesystem::resize_file(path.substr(0, path.size() - 6) + ".scalars",
                               std::filesystem::file_size(path.substr(0, path.size() - 6) + ".scalars") + 4);
  try {
    for (int p = 0; p < step.parts(); ++p)
      step.part(p);
    FAIL() << "the change was not noticed";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("changed while its parts were being read"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(".scalars"), std::string::npos) << e.what();
  }
}

TEST(Streamed, TheCensusOutlineEqualsTheSurveyAndTheFrameGathersIt) {
  // What the census says of the whole step (cells per level, bounds, the dataset's values but
  // its ranges) equals the survey of its parts, for a census of cells and one of boxes. A frame
  // whose transfer function has its range then reads each part once, and gathers the survey as
  // it goes: the same picture as a step surveyed first, and no part read again for the survey.
  for (const std::string& path : {writeStep("outline", 150000), writePlotfile("outline", 150000)}) {
    SCOPED_TRACE(path);
    const MemoryPlan plan = planOfParts(path, 4, 1, streamedFrameBytes(48, 40, 1));
    StreamedStep surveyed(path, {}, plan);
    const StepSurvey whole = surveyed.survey();
    StreamedStep step(path, {}, plan);
    ASSERT_TRUE(step.outline().has_value());
    const StepSurvey& outline = *step.outline();
    EXPECT_EQ(outline.cells, whole.cells);
    EXPECT_EQ(outline.levels, whole.levels);
    EXPECT_EQ(outline.levelCells, whole.levelCells);
    EXPECT_EQ(outline.cellBounds.lower, whole.cellBounds.lower);
    EXPECT_EQ(outline.cellBounds.upper, whole.cellBounds.upper);
    EXPECT_EQ(outline.dataset.referenceWidth, whole.dataset.referenceWidth);
    EXPECT_EQ(outline.dataset.worldDiagonal, whole.dataset.worldDiagonal);
    EXPECT_EQ(outline.dataset.extentCells, whole.dataset.extentCells);
    EXPECT_EQ(outline.dataset.defaultOpacityScale, whole.dataset.defaultOpacityScale);
    ASSERT_EQ(outline.dataset.valueRanges.size(), whole.dataset.valueRanges.size());

    Scene scene = Scene::volumeOf(defaultTransferFunction("viridis"), step.skeleton().fieldNames[0]);
    scene.layers[0].tf.valueRange = whole.dataset.valueRanges[0];
    Frame frame;
    frame.width = 48;
    frame.height = 40;
    const box3d b = step.skeleton().world.toWorld(whole.cellBounds);
    frame.camera.lookAt = (b.lower + b.upper) * 0.5;
    frame.camera.position = frame.camera.lookAt + vec3d(0.4, 0.5, 1.4) * length(b.size());
    const uint64_t before = step.partsRead();
    FrameBuffer gathered, reference;
    ASSERT_TRUE(renderStreamed(step, scene, RendererOptions(), frame, gathered));
    EXPECT_LE(step.partsRead() - before, uint64_t(step.parts())) << "each part read once: no pass before the frame";
    const uint64_t afterFrame = step.partsRead();
    const StepSurvey& gatheredSurvey = step.survey();
    EXPECT_EQ(step.partsRead(), afterFrame) << "the survey read parts again";
    EXPECT_EQ(gatheredSurvey.cells, whole.cells);
    EXPECT_EQ(gatheredSurvey.bricks, whole.bricks);
    EXPECT_EQ(gatheredSurvey.regions, whole.regions);
    for (size_t f = 0; f < whole.dataset.valueRanges.size(); ++f)
      EXPECT_TRUE(gatheredSurvey.dataset.valueRanges[f].lower == whole.dataset.valueRanges[f].lower &&
                  gatheredSurvey.dataset.valueRanges[f].upper == whole.dataset.valueRanges[f].upper)
          << f;
    ASSERT_TRUE(renderStreamed(surveyed, scene, RendererOptions(), frame, reference));
    const Image a = gathered.resolve(), r = reference.resolve();
    ASSERT_EQ(a.pixels.size(), r.pixels.size());
    for (size_t i = 0; i < a.pixels.size(); ++i)
      ASSERT_TRUE(a.pixels[i].x == r.pixels[i].x && a.pixels[i].y == r.pixels[i].y && a.pixels[i].z == r.pixels[i].z &&
                  a.pixels[i].w == r.pixels[i].w)
          << i;
  }
}

TEST(Streamed, EveryCellMergedIntoCubesIsTheVolumeMeanOfItsCells) {
  // Inputs without coarse levels to read alone (NAME.cells, a model file): every cell merged into
  // cubes, checked against sums cell by cell, on a step whose corners are negative and whose
  // halves lie 2^26 finest cells apart (nothing may be allocated by bounding volume).
  CellSet set = generateScene({"blobs", 60000, 3, 4});
  const size_t half = set.cells.size() / 2;
  for (size_t i = 0; i < set.cells.size(); ++i)
    set.cells[i].lower += vec3i(i < half ? -(1 << 26) : (1 << 26), -64, 0);
  const std::string dir = std::string(EXABRICKS_TEST_TMP) + "/streamed";
  std::filesystem::create_directories(dir);
  const std::string cells = dir + "/apart.cells", model = dir + "/apart.model";
  writeNative(set, cells);
  writeModel(loadModel(cells), model);
  EXPECT_FALSE(mergesLeaves(writePlotfile("levels", 60000))); // its coarse levels are read instead
  const std::string oneLevel = writePlotfile("one_level", 60000, 1);
  EXPECT_TRUE(mergesLeaves(oneLevel));
  for (const std::string& path : {cells, model, oneLevel}) {
    SCOPED_TRACE(path);
    const CellSet truth = path == oneLevel ? loadCells(path) : set;
    EXPECT_FALSE(loadMergedLeaves(path, {}, double(truth.cells.size())));
    const std::optional<MergedLeaves> m = loadMergedLeaves(path, {}, 2000);
    ASSERT_TRUE(m);
    EXPECT_EQ(m->cells, double(truth.cells.size()));
    expectCubeMeans(*m, truth);
    EXPECT_LT(m->model.cellCount(), truth.cells.size() / 8);
  }
}
