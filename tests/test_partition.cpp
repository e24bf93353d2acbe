// Data-parallel pieces without MPI: the k-d partition (tiling, balance, visibility order), the
// halo (reconstruction inside a part equals the whole dataset's), box reads of native files, and
// parts rendered with their domains and composited front to back against the whole render.
#include "datasets.h"

#include "exabricks/amr/model.h"
#include "exabricks/amr/partition.h"
#include "exabricks/core/error.h"
#include "exabricks/io/load.h"
#include "exabricks/io/native.h"
#include "exabricks/render/composite.h"
#include "exabricks/render/renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

namespace exa {
namespace {

namespace fs = std::filesystem;

bool contains(const box3l& b, const vec3d& p) {
  for (int a = 0; a < 3; ++a)
    if (!(p[a] >= double(b.lower[a]) && p[a] < double(b.upper[a]))) return false;
  return true;
}

Census censusOf(const CellSet& s) {
  CellCensus c;
  c.add(s.cells.data(), s.cells.size());
  return c.finish();
}

/// Cells per part, each cell counted in the part that holds its centre.
std::vector<uint64_t> ownedPerPart(const CellSet& s, const KdPartition& p) {
  std::vector<uint64_t> n(size_t(p.parts()), 0);
  for (const Cell& c : s.cells) {
    int owners = 0;
    for (int k = 0; k < p.parts(); ++k)
      if (centreInside(c.lower, c.level, p.box(k))) ++n[size_t(k)], ++owners;
    EXPECT_EQ(owners, 1);
  }
  return n;
}

TEST(Partition, PartsTileTheLatticeAndBalanceTheCells) {
  for (const test::NamedCells& d : test::smallDatasets()) {
    const Census census = censusOf(d.cells);
    EXPECT_DOUBLE_EQ(census.cells(), double(d.cells.size())) << d.name;
    for (int parts : {1, 2, 3, 4, 5, 8}) {
      const KdPartition p = KdPartition::balance(census, parts);
      ASSERT_EQ(p.parts(), parts);
      // Every point lies in exactly one part, inside the data and far outside it.
      std::mt19937 rng{uint32_t(parts)};
      const box3l b = census.bounds();
      std::uniform_real_distribution<double> u(-0.5, 1.5);
      for (int i = 0; i < 2000; ++i) {
        vec3d q;
        for (int a = 0; a < 3; ++a)
          q[a] = double(b.lower[a]) + u(rng) * double(b.upper[a] - b.lower[a]);
        int holders = 0;
        for (int k = 0; k < parts; ++k)
          holders += contains(p.box(k), q);
        EXPECT_EQ(holders, 1) << d.name << " at " << q.x << " " << q.y << " " << q.z;
        const int at = p.partAt(q); // down the tree: the part whose box holds it
        ASSERT_TRUE(at >= 0 && at < parts);
        EXPECT_TRUE(contains(p.box(at), q)) << d.name;
      }
      EXPECT_EQ(p.partAt(vec3d(std::nan(""), 0.0, 0.0)), -1);
      // Balanced: with the few thousand cells of these datasets, within a quarter of the mean (the blocks
      // of the census are assumed evenly filled) once there are enough cells.
      if (d.cells.size() >= 2500 && parts <= 4) {
        const std::vector<uint64_t> owned = ownedPerPart(d.cells, p);
        const double mean = double(d.cells.size()) / parts;
        for (uint64_t n : owned)
          EXPECT_NEAR(double(n), mean, 0.25 * mean) << d.name << " parts " << parts;
      }
    }
  }
}

TEST(Partition, GrainedPlanesCutNoCell) {
  for (const test::NamedCells& d : test::smallDatasets()) {
    const Census census = censusOf(d.cells);
    const int64_t grain = int64_t(1) << census.coarsestLevel;
    for (int parts : {2, 3, 5, 8}) {
      const KdPartition p = KdPartition::balance(census, parts, grain);
      ASSERT_EQ(p.parts(), parts);
      for (int k = 0; k < parts; ++k)
        for (int a = 0; a < 3; ++a) {
          EXPECT_EQ(p.box(k).lower[a] % grain, 0) << d.name;
          EXPECT_EQ(p.box(k).upper[a] % grain, 0) << d.name;
        }
      // Every cell lies wholly inside the one part that owns it.
      for (const Cell& c : d.cells.cells) {
        int inside = 0;
        const box3i cb = c.bounds();
        for (int k = 0; k < parts; ++k) {
          const box3l& b = p.box(k);
          bool in = true;
          for (int a = 0; a < 3; ++a)
            in = in && cb.lower[a] >= b.lower[a] && cb.upper[a] <= b.upper[a];
          inside += in;
        }
        ASSERT_EQ(inside, 1) << d.name << " parts " << parts;
      }
      if (d.cells.size() >= 2500 && parts <= 2) {
        const std::vector<uint64_t> owned = ownedPerPart(d.cells, p);
        for (uint64_t n : owned)
          EXPECT_GT(double(n), 0.25 * double(d.cells.size()) / parts) << d.name;
      }
    }
  }
  EXPECT_THROW(KdPartition::balance(Census{}, 2, 0), Error);
}

TEST(Partition, VisibilityOrderIsTheOrderRaysMeetTheParts) {
  const CellSet s = generateScene({"blobs", 5000, 3, 4});
  const KdPartition p = KdPartition::balance(censusOf(s), 7);
  const box3l b = censusOf(s).bounds();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 2.0), dir(-1.0, 1.0);
  for (int i = 0; i < 300; ++i) {
    vec3d eye;
    for (int a = 0; a < 3; ++a)
      eye[a] = double(b.lower[a]) + u(rng) * double(b.upper[a] - b.lower[a]);
    const std::vector<int> order = p.orderFrom(eye);
    ASSERT_EQ(order.size(), 7u);
    std::vector<int> rank(7);
    for (int k = 0; k < 7; ++k)
      rank[size_t(order[size_t(k)])] = k;
    // March a ray from the eye: the parts it passes through come in the order's order.
    const vec3d d = normalize(test::draw3(dir, rng));
    int last = -1;
    const double step = double(reduceMax(b.size())) / 2000.0;
    for (double t = 0; t < 4.0 * double(reduceMax(b.size())); t += step) {
      const vec3d q = eye + d * t;
      for (int k = 0; k < 7; ++k)
        if (contains(p.box(k), q)) {
          EXPECT_GE(rank[size_t(k)], last) << "ray " << i;
          last = std::max(last, rank[size_t(k)]);
        }
    }
    // Orthographic: the same along the direction from any start.
    const std::vector<int> along = p.orderAlong(d);
    std::vector<int> rankAlong(7);
    for (int k = 0; k < 7; ++k)
      rankAlong[size_t(along[size_t(k)])] = k;
    last = -1;
    const vec3d start = eye - d * (4.0 * double(reduceMax(b.size())));
    for (double t = 0; t < 8.0 * double(reduceMax(b.size())); t += step) {
      const vec3d q = start + d * t;
      for (int k = 0; k < 7; ++k)
        if (contains(p.box(k), q)) {
          EXPECT_GE(rankAlong[size_t(k)], last);
          last = std::max(last, rankAlong[size_t(k)]);
        }
    }
  }
}

TEST(Partition, EncodesAndRejectsCorruptForms) {
  const KdPartition p = KdPartition::balance(censusOf(generateScene({"shells", 3000, 2, 4})), 5);
  const KdPartition q = KdPartition::decode(p.encode());
  ASSERT_EQ(q.parts(), 5);
  for (int k = 0; k < 5; ++k)
    EXPECT_EQ(q.box(k), p.box(k));
  EXPECT_EQ(q.orderFrom(vec3d(1, 2, 3)), p.orderFrom(vec3d(1, 2, 3)));
  std::vector<int64_t> bad = p.encode();
  bad[2 + 2] = 0; // a node pointing back at the root
  EXPECT_THROW(KdPartition::decode(bad), Error);
  bad = p.encode();
  bad.pop_back();
  EXPECT_THROW(KdPartition::decode(bad), Error);
  EXPECT_THROW(KdPartition::decode({}), Error);
  EXPECT_THROW(KdPartition::balance(Census{}, 0), Error);
}

TEST(Partition, MorePartsThanDataLeavesEmptyPartsThatStillTile) {
  const CellSet one = test::makeCells({{{vec3i(-4, 4, 12), 2}, 0.5f}});
  const KdPartition p = KdPartition::balance(censusOf(one), 4);
  const std::vector<uint64_t> owned = ownedPerPart(one, p);
  EXPECT_EQ(std::count(owned.begin(), owned.end(), 1u), 1);
}

TEST(Partition, SupportTestMatchesTheBasis) {
  // A cell's support reaches into a box exactly when some point of the box has weight from it.
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> pos(-12, 12), lvl(0, 2);
  for (int i = 0; i < 3000; ++i) {
    const int level = lvl(rng), w = 1 << level;
    const vec3i lower = vec3i(pos(rng), pos(rng), pos(rng)) / w * w;
    box3l box;
    for (int a = 0; a < 3; ++a) {
      const int64_t x = pos(rng), y = pos(rng);
      box.lower[a] = std::min(x, y);
      box.upper[a] = std::max(x, y) + 1;
    }
    // Brute force on a grid of 1/8 lattice units: points strictly inside the open support.
    bool reaches = true;
    for (int a = 0; a < 3; ++a) {
      const double centre = lower[a] + 0.5 * w;
      bool axis = false;
      for (double x = double(box.lower[a]); x < double(box.upper[a]); x += 0.125)
        axis = axis || std::abs(x - centre) < double(w);
      reaches = reaches && axis;
    }
    EXPECT_EQ(supportReaches(Cell{lower, level}.bounds(), level, box), reaches);
  }
}

/// The part of a cell set one process holds: the cells whose supports reach into the part.
CellSet partOf(CellSet s, const box3l& part) {
  keepSupportOf(s, part);
  return s;
}

TEST(Partition, ReconstructionInsideAPartEqualsTheWholeData) {
  for (const test::NamedCells& d : test::smallDatasets()) {
    if (d.cells.size() < 100) continue;
    const Model whole = buildModel(CellSet(d.cells));
    const KdPartition p = KdPartition::balance(censusOf(d.cells), 3);
    const box3i cb = whole.cellBounds();
    for (int k = 0; k < 3; ++k) {
      CellSet mine = partOf(d.cells, p.box(k));
      ASSERT_FALSE(mine.cells.empty());
      EXPECT_LT(mine.cells.size(), d.cells.size()) << d.name;
      const Model part = buildModel(std::move(mine));
      std::mt19937 rng{uint32_t(k)};
      std::uniform_real_distribution<double> u(-0.1, 1.1);
      int checked = 0;
      for (int i = 0; i < 4000 && checked < 400; ++i) {
        vec3d q;
        for (int a = 0; a < 3; ++a)
          q[a] = double(cb.lower[a]) + u(rng) * double(cb.upper[a] - cb.lower[a]);
        if (!contains(p.box(k), q)) continue;
        ++checked;
        double v0 = 0, v1 = 0;
        vec3d g0, g1;
        const bool h0 = whole.sampleWorld(0, whole.world.toWorld(q), v0, g0);
        const bool h1 = part.sampleWorld(0, part.world.toWorld(q), v1, g1);
        ASSERT_EQ(h0, h1) << d.name << " part " << k;
        if (!h0) continue;
        EXPECT_NEAR(v0, v1, 1e-5 * (1.0 + std::abs(v0))) << d.name;
        for (int a = 0; a < 3; ++a)
          EXPECT_NEAR(g0[a], g1[a], 1e-4 * (1.0 + std::abs(g0[a]))) << d.name;
      }
    }
  }
}

TEST(Partition, NativeBoxReadsAndCensusStreamTheRecords) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "partition-native";
  fs::create_directories(dir);
  const std::string path = (dir / "s.cells").string();
  // More records than one piece of the streamed read (65,536), so that boxes keep cells from
  // several pieces.
  CellSet s = generateScene({"shells", 150000, 4, 4});
  ASSERT_GT(s.size(), size_t(2) << 16);
  writeNative(s, path);
  EXPECT_DOUBLE_EQ(nativeCensus(path).cells(), double(s.size()));
  EXPECT_EQ(nativeCensus(path).coarsestLevel, censusOf(s).coarsestLevel);
  const box3l all = s.bounds();
  const box3i half(vec3i(all.lower), vec3i(vec3l(all.upper.x, all.upper.y, (all.lower.z + all.upper.z) / 2)));
  for (const box3i& box : {box3i(vec3i(0), vec3i(20)), box3i(vec3i(10, -5, 30), vec3i(40, 18, 31)),
                           box3i(vec3i(-100), vec3i(-90)), half}) {
    CellSet cropped = s;
    cropCells(cropped, box);
    // Room reserved for none, too few and about as many as the box holds: the same cells.
    const CellSet read = readNative(path, {}, box, false, cropped.size() / 2);
    for (size_t expected : {size_t(0), cropped.size() + 7})
      EXPECT_EQ(readNative(path, {}, box, false, expected).cells, cropped.cells);
    EXPECT_EQ(read.cells, cropped.cells);
    ASSERT_EQ(read.fields.size(), s.fields.size());
    for (const Field& f : cropped.fields) {
      const int i = read.fieldIndex(f.name);
      ASSERT_GE(i, 0) << f.name;
      EXPECT_EQ(read.fields[size_t(i)].values, f.values) << f.name;
    }
  }
  // A part loaded through the registry is exactly the cells whose supports reach into it, grown
  // by two coarsest cell widths (smooth shading's reach).
  const KdPartition p = KdPartition::balance(loadCensus(path), 2);
  const int coarsest = loadCensus(path).coarsestLevel;
  for (int k = 0; k < 2; ++k) {
    const std::optional<Model> m = loadModelPart(path, {}, p.box(k), coarsest);
    ASSERT_TRUE(m.has_value());
    EXPECT_EQ(m->cellCount(), partOf(s, shadingReach(p.box(k), coarsest)).size());
  }
}

namespace {

/// The two models' values and gradients agree at 3000 random points in and around the cells.
void expectSameReconstruction(const Model& a, const Model& b) {
  const box3i cb = a.cellBounds();
  std::mt19937 rng{7};
  std::uniform_real_distribution<double> u(-0.1, 1.1);
  for (int i = 0; i < 3000; ++i) {
    vec3d q;
    for (int k = 0; k < 3; ++k)
      q[k] = double(cb.lower[k]) + u(rng) * double(cb.upper[k] - cb.lower[k]);
    for (int f = 0; f < int(a.fieldNames.size()); ++f) {
      double v0 = 0, v1 = 0;
      vec3d g0, g1;
      const bool h0 = a.sampleWorld(f, a.world.toWorld(q), v0, g0);
      const bool h1 = b.sampleWorld(f, b.world.toWorld(q), v1, g1);
      ASSERT_EQ(h0, h1);
      if (!h0) continue;
      EXPECT_NEAR(v0, v1, 1e-5 * (1.0 + std::abs(v0)));
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(g0[k], g1[k], 1e-4 * (1.0 + std::abs(g0[k])));
    }
  }
}

} // namespace

TEST(Partition, BuildInPartsEqualsTheWholeBuild) {
  const fs::path dir = fs::path(EXABRICKS_TEST_TMP) / "partition-build";
  fs::create_directories(dir);
  for (const test::NamedCells& d : test::smallDatasets()) {
    if (d.cells.size() < 1000) continue;
    SCOPED_TRACE(d.name);
    const std::string path = (dir / (d.name + ".cells")).string();
    writeNative(d.cells, path);
    LoadOptions inParts;
    inParts.partCells = d.cells.size() / 5;
    LoadOptions whole;
    whole.partCells = 0;
    const Model a = loadModel(path, whole), b = loadModel(path, inParts);
    EXPECT_EQ(a.stats.parts, 1);
    EXPECT_GE(b.stats.parts, 5);
    ASSERT_EQ(a.cellCount(), b.cellCount());
    ASSERT_EQ(a.fieldNames, b.fieldNames);
    // The same values (in another order), and bricks that tile the values without overlapping.
    for (size_t f = 0; f < a.fieldValues.size(); ++f) {
      std::vector<float> va = a.fieldValues[f].toVector(), vb = b.fieldValues[f].toVector();
      std::sort(va.begin(), va.end());
      std::sort(vb.begin(), vb.end());
      EXPECT_EQ(va, vb);
    }
    uint64_t next = 0;
    for (const Brick& br : b.bricks) {
      EXPECT_EQ(br.valueOffset, next);
      next += br.cellCount();
    }
    // The reconstruction agrees everywhere (the brick order within a region may differ).
    ASSERT_NO_FATAL_FAILURE(expectSameReconstruction(a, b));
  }
  // Overlapping cells are found when built in parts too (they lie in one part).
  CellSet bad = generateScene({"blobs", 5000, 1, 3});
  const Cell twin = bad.cells[bad.cells.size() / 2];
  bad.cells.push_back(twin);
  for (Field& f : bad.fields)
    f.values.push_back(1.0f);
  const std::string path = (dir / "bad.cells").string();
  writeNative(bad, path);
  LoadOptions inParts;
  inParts.partCells = 1000;
  auto buildError = [&](const std::string& input) {
    try {
      loadModel(input, inParts);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  {
    const std::string m = buildError(path);
    EXPECT_NE(m.find("bad.cells"), std::string::npos) << m;
    EXPECT_EQ(m.find("bad.cells"), m.rfind("bad.cells")) << "the file is named once: " << m;
    EXPECT_NE(m.find("duplicates"), std::string::npos) << m;
  }
  // A bad value is named by its record in the file.
  CellSet nan = generateScene({"blobs", 5000, 1, 3});
  nan.fields[0].values[777] = std::nanf("");
  const std::string nanPath = (dir / "nan.cells").string();
  writeNative(nan, nanPath);
  const std::string m = buildError(nanPath);
  EXPECT_NE(m.find("record 777"), std::string::npos) << m;
  EXPECT_NE(m.find("not finite"), std::string::npos) << m;
}

/// Renders parts of `cells` as data-parallel processes do (each part's renderer restricted to its
/// box, given the whole data's DatasetInfo), compositing every pass front to back.
Image renderInParts(const CellSet& cells, const KdPartition& p, const Scene& scene, const Frame& frame,
                    const DatasetInfo& dataset, const BuildOptions& build = {}) {
  std::vector<Model> models;
  for (int k = 0; k < p.parts(); ++k)
    models.push_back(buildModel(partOf(cells, p.box(k)), build));
  std::vector<std::unique_ptr<Renderer>> renderers;
  for (int k = 0; k < p.parts(); ++k) {
    renderers.push_back(std::make_unique<Renderer>(models[size_t(k)], dataset));
    const box3l& b = p.box(k);
    renderers.back()->setDomain(models[size_t(k)].world.toWorld(b));
    renderers.back()->setScene(scene);
  }
  const Camera& cam = frame.camera;
  const std::vector<int> order = cam.orthographic ? p.orderAlong((cam.lookAt - cam.position) / models[0].world.scale)
                                                  : p.orderFrom(models[0].world.toLattice(cam.position));
  const size_t pixels = size_t(frame.width) * size_t(frame.height);
  std::vector<vec4f> sum(pixels);
  for (int pass = 0; pass < frame.samplesPerPixel; ++pass) {
    Frame f = frame;
    f.frameIndex = pass;
    std::vector<std::vector<float>> layers(size_t(p.parts()), std::vector<float>(pixels * kCompositeChannels));
    for (int k = 0; k < p.parts(); ++k) {
      FrameBuffer fb(frame.width, frame.height);
      renderers[size_t(k)]->renderPass(f, fb, {});
      const FrameBuffer::Sums s = fb.sums();
      for (size_t i = 0; i < pixels; ++i) {
        for (int c = 0; c < 4; ++c)
          layers[size_t(k)][i * kCompositeChannels + size_t(c)] = s.colors[4 * i + size_t(c)];
        layers[size_t(k)][i * kCompositeChannels + 4] = s.steps[i];
      }
    }
    std::vector<const float*> ordered;
    for (int k : order)
      ordered.push_back(layers[size_t(k)].data());
    std::vector<float> out(pixels * kCompositeChannels);
    compositeFrontToBack(ordered.data(), ordered.size(), pixels, out.data());
    for (size_t i = 0; i < pixels; ++i)
      sum[i] += vec4f(out[i * kCompositeChannels], out[i * kCompositeChannels + 1], out[i * kCompositeChannels + 2],
                      out[i * kCompositeChannels + 3]);
  }
  Image image(frame.width, frame.height);
  for (size_t i = 0; i < pixels; ++i)
    image.pixels[i] = sum[i] * (1.f / float(frame.samplesPerPixel));
  return image;
}

struct Difference {
  float max = 0;
  double mean = 0, above = 0; ///< mean absolute difference; share of channels more than 2/255 off
};

Difference compare(const Image& a, const Image& b) {
  Difference d;
  for (size_t i = 0; i < a.pixels.size(); ++i)
    for (int c = 0; c < 4; ++c) {
      const float* pa = &a.pixels[i].x;
      const float* pb = &b.pixels[i].x;
      const float e = std::abs(pa[c] - pb[c]);
      d.max = std::max(d.max, e);
      d.mean += e;
      d.above += e > 2.f / 255.f;
    }
  d.mean /= 4.0 * double(a.pixels.size());
  d.above /= 4.0 * double(a.pixels.size());
  return d;
}

/// Renders `cells` whole and in parts with the given build options (see the test below).
void checkPartsComposited(const CellSet& cells, const BuildOptions& build, double aboveBound) {
  const Model whole = buildModel(CellSet(cells), build);
  const DatasetInfo dataset = DatasetInfo::of(whole);
  Scene scene;
  scene.layers[0].tf.valueRange = dataset.valueRanges[0];
  Frame frame;
  frame.width = 96;
  frame.height = 80;
  frame.samplesPerPixel = 2;
  const box3d wb = whole.worldBounds();
  frame.camera = Camera::frame(wb, 35, 25, 40, false);
  Renderer serial(whole, dataset);
  for (int variant = 0; variant < 3; ++variant) {
    if (variant == 1) { // iso-surfaces, a clip plane, and a mesh in the clipped half (meshes are not clipped)
      scene.iso.values = {0.3f};
      scene.clip.planes = {ClipPlane{(wb.lower + wb.upper) * 0.5, normalize(vec3d(1, 0.2, 0))}};
      auto quad = std::make_shared<TriangleMesh>();
      const vec3d lo = wb.lower, size = wb.size();
      quad->vertices = {vec3f(lo + size * vec3d(0.6, 0.1, 0.2)), vec3f(lo + size * vec3d(0.9, 0.1, 0.8)),
                        vec3f(lo + size * vec3d(0.9, 0.9, 0.8)), vec3f(lo + size * vec3d(0.6, 0.9, 0.2))};
      quad->triangles = {vec3i(0, 1, 2), vec3i(0, 2, 3)};
      scene.meshes = {SceneMesh{quad, vec3f(0.8f, 0.3f, 0.2f), {}}};
    }
    if (variant == 2) frame.camera.orthographic = true, frame.camera.orthoHeight = reduceMax(wb.size());
    serial.setScene(scene);
    const Image reference = serial.render(frame);
    // One part: the whole lattice, bit for bit the serial image.
    EXPECT_EQ(renderInParts(cells, KdPartition::whole(), scene, frame, dataset, build).pixels, reference.pixels);
    for (int parts : {2, 3, 4}) {
      const KdPartition p = KdPartition::balance(censusOf(cells), parts);
      // Orthographic frames order the parts along the view direction.
      const Image image = renderInParts(cells, p, scene, frame, dataset, build);
      const Difference d = compare(image, reference);
      EXPECT_LT(d.mean, 0.5 / 255.0) << "variant " << variant << " parts " << parts;
      EXPECT_LT(d.above, aboveBound) << "variant " << variant << " parts " << parts;
      if (variant == 0) {
        EXPECT_LE(d.max, 4.5f / 255.f) << "parts " << parts;
      }
    }
  }
}

// Samples inside a part equal the whole data's; what differs is where the rays' sample intervals
// are cut (the parts' regions end at the part's faces, the whole's regions at its own bricks'
// faces) and early termination counted per part: volume within 4/255, iso-surfaces may flip at
// isolated grazing pixels, where the iso search steps from a region's entry. With one region per
// set of bricks under 0.75 % of the channels are more than 2/255 off; merged regions (the
// default) differ more between the whole and the parts, and iso-surfaces flip at up to 1.5 %.
TEST(Partition, PartsCompositedEqualTheWholeRender) {
  const CellSet cells = generateScene({"shells", 12000, 2, 4});
  BuildOptions exact;
  exact.regions.segmentCost = 0.0;
  {
    SCOPED_TRACE("one region per set of bricks");
    checkPartsComposited(cells, exact, 0.0075);
  }
  {
    SCOPED_TRACE("merged regions");
    checkPartsComposited(cells, BuildOptions(), 0.015);
  }
}

TEST(Partition, CellsCentredInABoxAreCountedAsTheyAreVisited) {
  // Bricks of three levels, some with negative corners, against boxes that cut them anywhere
  // (on cell centres, between them, outside): the count equals the cells visited.
  uint32_t seed = 7;
  auto next = [&](int range) {
    seed = seed * 1664525u + 1013904223u;
    return int((seed >> 8) % uint32_t(range));
  };
  for (int t = 0; t < 500; ++t) {
    Brick b;
    b.level = next(3);
    b.size = vec3i(1 + next(9), 1 + next(9), 1 + next(9));
    b.lower = vec3i(next(40) - 20, next(40) - 20, next(40) - 20) * b.cellWidth();
    box3l box;
    for (int a = 0; a < 3; ++a) {
      box.lower[a] = next(80) - 40;
      box.upper[a] = box.lower[a] + next(60);
    }
    uint64_t visited = 0;
    forCellsCentredIn(b, box, [&](uint32_t) { ++visited; });
    ASSERT_EQ(cellsCentredIn(b, box), visited) << t;
  }
}

TEST(Partition, CellsReadByPartsAreThoseOfTheBoxesThatReachTheirReadBoxes) {
  // Random boxes of several widths, some far apart and on both sides of the origin.
  std::mt19937 rng{5};
  std::uniform_int_distribution<int64_t> at(-300, 300), size(1, 40);
  Census census;
  census.coarsestLevel = 3;
  for (int i = 0; i < 3000; ++i) {
    box3l b;
    for (int a = 0; a < 3; ++a) {
      b.lower[a] = at(rng) * (i % 50 == 0 ? 1000 : 1);
      b.upper[a] = b.lower[a] + size(rng);
    }
    census.boxes.push_back({b, double(size(rng)) * 1.37});
  }
  for (int parts : {1, 2, 3, 7, 16, 48}) {
    const KdPartition p = KdPartition::balance(census, parts, 8);
    const std::vector<double> cells = cellsReadByParts(census, p);
    ASSERT_EQ(int(cells.size()), parts);
    for (int k = 0; k < parts; ++k) {
      // Every box against the part's read box, in order: the same sum to the bit.
      const box3i r = haloReadBox(shadingReach(p.box(k), census.coarsestLevel), census.coarsestLevel);
      double expected = 0;
      for (const CensusBox& c : census.boxes) {
        bool overlaps = true;
        for (int a = 0; a < 3; ++a)
          overlaps =
              overlaps && std::max(c.box.lower[a], int64_t(r.lower[a])) < std::min(c.box.upper[a], int64_t(r.upper[a]));
        if (overlaps) expected += c.cells;
      }
      EXPECT_EQ(cells[size_t(k)], expected) << parts << " parts, part " << k;
    }
  }
}

} // namespace
} // namespace exa
