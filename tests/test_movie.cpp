// Time series and camera paths: keyframes interpolated exactly and smoothly, the orbit closes,
// values rebuilt over a kept structure equal a fresh build, series generation and ordering.
#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/core/error.h"
#include "exabricks/io/native.h"
#include "exabricks/io/series.h"
#include "exabricks/render/camera_path.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/scene.h"
#include "exabricks/workflows/series.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

using namespace exa;

namespace {

CameraKeyframe key(double t, vec3d position, vec3d lookAt, double fov = 40) {
  CameraKeyframe k;
  k.time = t;
  k.camera.position = position;
  k.camera.lookAt = lookAt;
  k.camera.up = vec3d(0, 0, 1);
  k.camera.fovy = fov;
  return k;
}

/// Uneven times and turns: the spline's tangents differ from straight lines everywhere.
CameraPath curvedPath() {
  CameraPath p;
  p.keyframes = {key(0.0, {10, 0, 2}, {0, 0, 0}), key(0.7, {0, 9, 4}, {1, 0, 0}, 30),
                 key(1.0, {-8, 3, 1}, {1, 1, 0}, 50), key(2.5, {-2, -7, 6}, {0, 1, 1})};
  return p;
}

vec3d direction(const Camera& c) { return normalize(c.lookAt - c.position); }

} // namespace

TEST(CameraPath, PassesThroughEveryKeyframeExactly) {
  const CameraPath p = curvedPath();
  p.validate();
  for (const CameraKeyframe& k : p.keyframes) {
    const Camera c = p.cameraAt(k.time);
    EXPECT_EQ(c.position, k.camera.position);
    EXPECT_EQ(c.lookAt, k.camera.lookAt);
    EXPECT_NEAR(length(c.up - normalize(k.camera.up)), 0.0, 1e-15);
    EXPECT_DOUBLE_EQ(c.fovy, k.camera.fovy);
  }
  // Clamped outside the keyframes' times.
  EXPECT_EQ(p.cameraAt(-5).position, p.keyframes.front().camera.position);
  EXPECT_EQ(p.cameraAt(9).position, p.keyframes.back().camera.position);
}

TEST(CameraPath, PositionAndDirectionAreContinuousWithContinuousDerivatives) {
  const CameraPath p = curvedPath();
  const double h = 1e-6;
  for (size_t i = 1; i + 1 < p.keyframes.size(); ++i) {
    const double t = p.keyframes[i].time;
    const Camera before = p.cameraAt(t - h), at = p.cameraAt(t), after = p.cameraAt(t + h);
    // Continuous: values on both sides approach the keyframe.
    EXPECT_LT(length(before.position - at.position), 1e-4);
    EXPECT_LT(length(after.position - at.position), 1e-4);
    EXPECT_LT(length(direction(before) - direction(at)), 1e-4);
    EXPECT_LT(length(direction(after) - direction(at)), 1e-4);
    // C1: one-sided finite differences agree across the keyframe (they would differ by O(1)
    // for a polyline or a spline with mismatched tangents).
    const vec3d left = (at.position - before.position) / h, right = (after.position - at.position) / h;
    EXPECT_LT(length(left - right), 1e-3 * std::max(1.0, length(left))) << "keyframe " << i;
    const vec3d dl = (direction(at) - direction(before)) / h, dr = (direction(after) - direction(at)) / h;
    EXPECT_LT(length(dl - dr), 1e-3 * std::max(1.0, length(dl))) << "keyframe " << i;
  }
  // Smooth inside a segment too: no jumps anywhere on a fine sampling.
  vec3d previous = p.cameraAt(0).position;
  for (int i = 1; i <= 2500; ++i) {
    const vec3d q = p.cameraAt(i * 1e-3).position;
    EXPECT_LT(length(q - previous), 0.05);
    previous = q;
  }
}

TEST(CameraPath, ConstantSpeedSpacesFramesEvenlyAlongThePath) {
  CameraPath p = curvedPath();
  p.constantSpeed = true;
  const int n = 41;
  std::vector<double> steps;
  for (int i = 1; i < n; ++i)
    steps.push_back(length(p.cameraAt(p.frameTime(i, n)).position - p.cameraAt(p.frameTime(i - 1, n)).position));
  const auto [lo, hi] = std::minmax_element(steps.begin(), steps.end());
  EXPECT_LT(*hi / *lo, 1.02);
  EXPECT_EQ(p.frameTime(0, n), 0.0);
  EXPECT_EQ(p.frameTime(n - 1, n), 2.5);
  // Uneven in time: the default spacing is even in time instead.
  p.constantSpeed = false;
  EXPECT_DOUBLE_EQ(p.frameTime(20, n), 1.25);
}

TEST(CameraPath, KeyframedSettingsInterpolateAndMustBeGivenByEveryKeyframe) {
  CameraPath p;
  p.keyframes = {key(0, {5, 0, 0}, {0, 0, 0}), key(2, {0, 5, 0}, {0, 0, 0})};
  p.keyframes[0].range = range1f{0.f, 1.f};
  p.keyframes[1].range = range1f{2.f, 5.f};
  p.keyframes[0].isoValues = std::vector<float>{1.f, 3.f};
  p.keyframes[1].isoValues = std::vector<float>{2.f, 7.f};
  p.validate();
  Scene s;
  p.applySettings(1.0, s);
  EXPECT_FLOAT_EQ(s.layers[0].tf.valueRange.lower, 1.f);
  EXPECT_FLOAT_EQ(s.layers[0].tf.valueRange.upper, 3.f);
  ASSERT_EQ(s.iso.values.size(), 2u);
  EXPECT_FLOAT_EQ(s.iso.values[1], 5.f);
  p.keyframes[1].isoValues = std::vector<float>{2.f};
  EXPECT_THROW(p.validate(), Error);
  p.keyframes[1].isoValues.reset();
  EXPECT_THROW(p.validate(), Error);
  p.keyframes[1].isoValues = std::vector<float>{2.f, 7.f};
  p.keyframes[1].time = 0;
  EXPECT_THROW(p.validate(), Error);
}

TEST(CameraPath, OrbitClosesTheLoop) {
  const box3d box(vec3d(-1, 0, 2), vec3d(3, 2, 5));
  const int n = 36;
  const Camera first = orbitCamera(box, 30, 20, 40, false, 0, n);
  const Camera afterLast = orbitCamera(box, 30, 20, 40, false, n, n);
  EXPECT_LT(length(first.position - afterLast.position), 1e-9);
  // Equal steps between neighbours, the last to the first included.
  const Camera last = orbitCamera(box, 30, 20, 40, false, n - 1, n);
  const double step = length(orbitCamera(box, 30, 20, 40, false, 1, n).position - first.position);
  EXPECT_NEAR(length(first.position - last.position), step, 1e-9);
  EXPECT_EQ(first.position, Camera::frame(box, 30, 20, 40, false).position);
}

TEST(CameraPath, SceneFilesRoundTrip) {
  SceneDocument doc;
  doc.path = curvedPath();
  doc.path.constantSpeed = true;
  doc.path.keyframes[0].opacityScale = 0.5f;
  for (size_t i = 1; i < doc.path.keyframes.size(); ++i)
    doc.path.keyframes[i].opacityScale = 0.25f;
  const SceneDocument back = readSceneJson(writeSceneJson(doc), "test");
  ASSERT_EQ(back.path.keyframes.size(), doc.path.keyframes.size());
  EXPECT_TRUE(back.path.constantSpeed);
  for (size_t i = 0; i < doc.path.keyframes.size(); ++i) {
    EXPECT_EQ(back.path.keyframes[i].time, doc.path.keyframes[i].time);
    EXPECT_EQ(back.path.keyframes[i].camera.position, doc.path.keyframes[i].camera.position);
    EXPECT_EQ(back.path.keyframes[i].opacityScale, doc.path.keyframes[i].opacityScale);
  }
  EXPECT_THROW(readSceneJson(R"({"camera_path": {"keyframes": []}})", "test"), Error);
  EXPECT_THROW(readSceneJson(R"({"camera_path": {"keyframes": [{"time": 0}]}})", "test"), Error);
  try {
    readSceneJson(R"({"camera_path": {"keyframes": [{"time": 1, "camera": {"position": [1,0,0]}},
                                                     {"time": 0, "camera": {"position": [2,0,0]}}]}})",
                  "s.json");
    FAIL() << "decreasing times accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("s.json"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("increase"), std::string::npos);
  }
}

TEST(Series, ValuesRebuiltOverAKeptStructureEqualAFreshBuild) {
  SceneOptions so = resolveSceneSize(SceneOptions{"blobs", 40000, 3, 4});
  so.gridTime = 0;
  ModelStructure structure;
  const Model first = buildModel(generateScene(so), {}, structure);
  so.time = 2; // the blobs moved; the hierarchy is the one of time 0
  CellSet next = generateScene(so);
  ASSERT_TRUE(structure.matches(next, {}));
  const Model fresh = buildModel(generateScene(so));
  const Model reused = rebuildValues(first, structure, std::move(next));
  ASSERT_EQ(reused.bricks.size(), fresh.bricks.size());
  EXPECT_EQ(reused.fieldNames, fresh.fieldNames);
  EXPECT_EQ(reused.fieldValues, fresh.fieldValues);
  EXPECT_NE(reused.fieldValues, first.fieldValues);
  EXPECT_EQ(reused.regions.brickIds, fresh.regions.brickIds);
  ASSERT_EQ(reused.regions.valueRanges.size(), fresh.regions.valueRanges.size());
  for (size_t f = 0; f < fresh.regions.valueRanges.size(); ++f)
    for (size_t r = 0; r < fresh.regions.valueRanges[f].size(); ++r) {
      EXPECT_EQ(reused.regions.valueRanges[f][r].lower, fresh.regions.valueRanges[f][r].lower);
      EXPECT_EQ(reused.regions.valueRanges[f][r].upper, fresh.regions.valueRanges[f][r].upper);
    }
  // The same image.
  Frame frame;
  frame.width = frame.height = 48;
  frame.camera = Camera::frame(box3d(vec3d(0.0), vec3d(fresh.cellBounds().upper)), 30, 20, 40, false);
  Renderer a(fresh), b(reused);
  a.setScene(Scene{});
  b.setScene(Scene{});
  EXPECT_EQ(a.render(frame).pixels, b.render(frame).pixels);
  // Another hierarchy is refused.
  so.gridTime = 6;
  CellSet other = generateScene(so);
  EXPECT_FALSE(structure.matches(other, {}));
  EXPECT_THROW(rebuildValues(first, structure, std::move(other)), Error);
}

TEST(Series, StepsShareTheLatticeAndStepZeroIsTheScene) {
  const SceneOptions base{"blobs", 30000, 1, 4};
  const SceneOptions resolved = resolveSceneSize(base);
  EXPECT_GT(resolved.base, 0);
  const CellSet a = generateScene(base), b = generateScene(resolved);
  EXPECT_EQ(a.cells, b.cells);
  EXPECT_EQ(a.fields[0].values, b.fields[0].values);
  SceneOptions later = resolved;
  later.time = 5;
  const CellSet c = generateScene(later);
  EXPECT_EQ(c.bounds().upper.x, b.bounds().upper.x); // the same lattice
  EXPECT_NE(c.fields[0].values, b.fields[0].values);
  SceneOptions shells{"shells", 1000, 1, 3};
  shells.time = 1;
  EXPECT_THROW(generateScene(shells), Error);
}

TEST(Series, NaturalOrder) {
  EXPECT_TRUE(naturalLess("plt200", "plt1000"));
  EXPECT_FALSE(naturalLess("plt1000", "plt200"));
  EXPECT_TRUE(naturalLess("plt00100", "plt00200"));
  EXPECT_TRUE(naturalLess("DD0009/DD0009", "DD0010/DD0010"));
  EXPECT_TRUE(naturalLess("a_2.cells", "a_10.cells"));
  EXPECT_TRUE(naturalLess("a", "b"));
  EXPECT_TRUE(naturalLess("x9", "x09") != naturalLess("x09", "x9")); // a strict order even for equal numbers
  EXPECT_FALSE(naturalLess("same", "same"));
}

TEST(SeriesRenderer, FramePlansStepsAndShares) {
  const FramePlan perStep = FramePlan::perStep(3, 2);
  EXPECT_EQ(perStep.frames, 6);
  EXPECT_EQ(perStep.stepOf(0), 0);
  EXPECT_EQ(perStep.stepOf(3), 1);
  EXPECT_EQ(perStep.stepOf(5), 2);
  EXPECT_EQ(perStep.framesOf(1), (std::vector<int>{2, 3}));
  const FramePlan spread = FramePlan::spread(3, 7);
  for (int step = 0; step < 3; ++step)
    EXPECT_FALSE(spread.framesOf(step).empty()) << step;
  EXPECT_EQ(spread.stepOf(6), 2);
  EXPECT_THROW(FramePlan::spread(3, 2), Error);
  EXPECT_EQ(frameShare({4, 5, 6, 7, 8}, 1, 2), (std::vector<int>{5, 7}));
  EXPECT_EQ(frameShare({4, 5}, 0, 1), (std::vector<int>{4, 5}));
  EXPECT_EQ(framePath("out", 42), (std::filesystem::path("out") / "frame_00042.png").string());
}

TEST(SeriesRenderer, ReusesStructuresPrefetchesAndEqualsSeparateRenders) {
  const std::filesystem::path dir = std::filesystem::path(EXABRICKS_TEST_TMP) / "series_renderer";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  SceneOptions so = resolveSceneSize(SceneOptions{"blobs", 20000, 3, 4});
  so.gridTime = 0; // one hierarchy for every step
  for (int t = 0; t < 3; ++t) {
    so.time = t;
    writeNative(generateScene(so), (dir / ("s_" + std::to_string(t) + ".cells")).string());
  }
  const std::vector<std::string> steps = seriesSteps({(dir / "s_*.cells").string()});
  ASSERT_EQ(steps.size(), 3u);
  SeriesRenderer series(steps, {});
  Frame frame;
  frame.width = frame.height = 24;
  const Model first = loadModel(steps[0]);
  frame.camera = Camera::frame(box3d(vec3d(0.0), vec3d(first.cellBounds().upper)), 30, 20, 40, false);
  const FramePlan plan = FramePlan::perStep(3);
  std::vector<Image> images(3);
  series.renderFrames(plan, Scene{}, frame, {0, 1, 2},
                      [&](int i, const SeriesStep& step, const Scene&, const Frame&, Image& image) {
                        EXPECT_EQ(step.index, i);
                        images[size_t(i)] = image;
                      });
  EXPECT_EQ(series.stats().loaded, 3);
  EXPECT_EQ(series.stats().reused, 2);
  for (int t = 0; t < 3; ++t) {
    const Model m = loadModel(steps[size_t(t)]);
    Renderer r(m);
    r.setScene(Scene{});
    EXPECT_EQ(r.render(frame).pixels, images[size_t(t)].pixels) << t;
  }
  const SeriesRange range = seriesRange(steps, {}, first.fieldNames[0]);
  EXPECT_FALSE(range.range.empty());
  EXPECT_THROW(series.load(3), Error);
  EXPECT_THROW(seriesSteps({(dir / "nothing_*.cells").string()}), Error);
}
