#include "datasets.h"
#include "exabricks/amr/model.h"

#include <gtest/gtest.h>

#include <random>

using namespace exa;
using namespace exa::test;

namespace {

void expectClose(double got, double want, double rel, const std::string& what) {
  const double tol = rel * std::max(1.0, std::abs(want));
  EXPECT_NEAR(got, want, tol) << what;
}

/// Compares the region-based sampler with brute force at p; returns whether p had a value.
bool compareAt(const CellSet& cells, const Model& m, int field, const vec3d& p) {
  const Reference ref = bruteForce(cells, field, p);
  double value = 0;
  vec3d grad;
  const bool ok = sampleField(m.view(field), p, value, &grad);
  const std::string where =
      "at (" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
  EXPECT_EQ(ok, ref.valid) << where;
  if (ok && ref.valid) {
    expectClose(value, ref.value, 1e-9, "value " + where);
    for (int a = 0; a < 3; ++a)
      expectClose(grad[a], ref.gradient[a], 1e-8, "gradient " + where);
  }
  return ok;
}

/// Points on the faces the structures introduce: brick faces, region faces (support faces),
/// cell centres and the corners where they meet.
std::vector<vec3d> boundaryPoints(const Model& m, std::mt19937& rng, size_t count) {
  std::vector<vec3d> points;
  std::uniform_real_distribution<double> u(0, 1);
  for (size_t i = 0; i < count; ++i) {
    vec3d p;
    if (i % 2 == 0) {
      const Brick& b = m.bricks[rng() % m.bricks.size()];
      const box3i bb = b.bounds();
      for (int a = 0; a < 3; ++a) {
        const int k = int(rng() % 4);
        const double w = b.cellWidth();
        p[a] = k == 0   ? bb.lower[a]
               : k == 1 ? bb.upper[a]
               : k == 2 ? bb.lower[a] + w * (0.5 + int(rng() % b.size[a]))
                        : bb.lower[a] + u(rng) * (bb.upper[a] - bb.lower[a]);
      }
    } else {
      const Region& r = m.regions.regions[rng() % m.regions.regions.size()];
      const box3f rb = r.bounds();
      for (int a = 0; a < 3; ++a) {
        const int k = int(rng() % 3);
        p[a] = k == 0 ? rb.lower[a] : k == 1 ? rb.upper[a] : rb.lower[a] + u(rng) * (rb.upper[a] - rb.lower[a]);
      }
    }
    points.push_back(p);
  }
  return points;
}

} // namespace

TEST(Basis, MatchesBruteForceAtRandomPoints) {
  for (const auto& d : smallDatasets()) {
    SCOPED_TRACE(d.name);
    CellSet copy = d.cells;
    const Model m = buildModel(std::move(copy));
    std::mt19937 rng(7);
    int valid = 0;
    for (int i = 0; i < 2000; ++i) {
      // Around a random brick (datasets may be far apart), reaching past its support.
      const box3i b = m.bricks[rng() % m.bricks.size()].bounds();
      const double margin = 2.0 * (b.upper.x - b.lower.x);
      vec3d p;
      for (int a = 0; a < 3; ++a)
        p[a] = std::uniform_real_distribution<double>(b.lower[a] - margin, b.upper[a] + margin)(rng);
      valid += compareAt(d.cells, m, int(i % d.cells.fields.size()), p);
    }
    EXPECT_GT(valid, 0);
  }
}

TEST(Basis, MatchesBruteForceOnBrickRegionAndLevelBoundaries) {
  for (const auto& d : smallDatasets()) {
    SCOPED_TRACE(d.name);
    CellSet copy = d.cells;
    const Model m = buildModel(std::move(copy));
    std::mt19937 rng(11);
    for (const vec3d& p : boundaryPoints(m, rng, 3000))
      compareAt(d.cells, m, 0, p);
  }
}

TEST(Basis, NoValueOutsideEverySupport) {
  const CellSet cells = makeCells({{{vec3i(0, 0, 0), 1}, 3.f}, {{vec3i(2, 0, 0), 0}, 5.f}});
  CellSet copy = cells;
  const Model m = buildModel(std::move(copy));
  double v;
  // The level-1 cell spans [0,2): its support is (-1, 3); the support face itself has no weight.
  EXPECT_FALSE(sampleField(m.view(0), vec3d(-1.0, 1.0, 1.0), v));
  EXPECT_FALSE(sampleField(m.view(0), vec3d(-5.0, 1.0, 1.0), v));
  EXPECT_FALSE(sampleField(m.view(0), vec3d(1.0, 1.0, 3.0), v));
  EXPECT_TRUE(sampleField(m.view(0), vec3d(-0.99, 1.0, 1.0), v));
  EXPECT_DOUBLE_EQ(v, 3.0);
  EXPECT_TRUE(sampleField(m.view(0), vec3d(1.0, 1.0, 1.0), v));
  EXPECT_DOUBLE_EQ(v, 3.0); // the fine cell's support ends at x = 1.5
  EXPECT_TRUE(sampleField(m.view(0), vec3d(2.5, 0.5, 0.5), v));
  // Both cells weigh in: level-1 centre (1,1,1) w=2, level-0 centre (2.5,.5,.5) w=1.
  const double w1 = (1 - 1.5 / 2) * (1 - 0.5 / 2) * (1 - 0.5 / 2);
  EXPECT_NEAR(v, (w1 * 3 + 1 * 5) / (w1 + 1), 1e-12);
}

TEST(Basis, GradientSignAgreesWithCentralDifferences) {
  for (const auto& d : smallDatasets()) {
    SCOPED_TRACE(d.name);
    CellSet copy = d.cells;
    const Model m = buildModel(std::move(copy));
    std::mt19937 rng(3);
    const double h = 1e-3;
    int compared = 0;
    for (int i = 0; i < 4000 && compared < 500; ++i) {
      const box3i b = m.bricks[rng() % m.bricks.size()].bounds();
      vec3d p;
      for (int a = 0; a < 3; ++a)
        p[a] = std::uniform_real_distribution<double>(b.lower[a] - 0.5, b.upper[a] + 0.5)(rng);
      // Smooth where no contributing hat has a kink within a few steps.
      const Reference ref = bruteForce(d.cells, 0, p, 1e-2);
      if (!ref.valid || ref.nearKink) continue;
      double v;
      vec3d g;
      ASSERT_TRUE(sampleField(m.view(0), p, v, &g));
      for (int a = 0; a < 3; ++a) {
        auto at = [&](double offset) {
          vec3d q = p;
          q[a] += offset;
          double value = 0;
          EXPECT_TRUE(sampleField(m.view(0), q, value));
          return value;
        };
        // Fourth-order central difference.
        const double fd = (at(-2 * h) - 8 * at(-h) + 8 * at(h) - at(2 * h)) / (12 * h);
        EXPECT_NEAR(g[a], fd, 1e-5 * std::max(1.0, std::abs(fd))) << "axis " << a;
      }
      ++compared;
    }
    EXPECT_GT(compared, 50);
  }
}

TEST(Basis, LinearFieldIsReproducedInsideOneLevel) {
  // On one level, the basis method interpolates trilinearly between centres: exact for a
  // linear field, with the exact gradient.
  CellSet s;
  s.fields.push_back({"scalar", {}});
  for (int z = 0; z < 6; ++z)
    for (int y = 0; y < 6; ++y)
      for (int x = 0; x < 6; ++x) {
        s.cells.push_back({vec3i(x, y, z) * 4, 2});
        const vec3d c = vec3d(x, y, z) * 4.0 + vec3d(2.0);
        s.fields[0].values.push_back(float(0.5 * c.x - 0.25 * c.y + 0.125 * c.z));
      }
  const Model m = buildModel(std::move(s));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(2.0, 22.0);
  for (int i = 0; i < 200; ++i) {
    const vec3d p = test::draw3(u, rng);
    double v;
    vec3d g;
    ASSERT_TRUE(sampleField(m.view(0), p, v, &g));
    EXPECT_NEAR(v, 0.5 * p.x - 0.25 * p.y + 0.125 * p.z, 1e-5);
    EXPECT_NEAR(g.x, 0.5, 1e-5);
    EXPECT_NEAR(g.y, -0.25, 1e-5);
    EXPECT_NEAR(g.z, 0.125, 1e-5);
  }
}

TEST(Basis, FloatSamplerAgreesWithDouble) {
  CellSet cells = generateScene({"shells", 5000, 2, 4});
  const Model m = buildModel(std::move(cells));
  std::mt19937 rng(9);
  const box3f b = m.regions.bounds;
  for (int i = 0; i < 2000; ++i) {
    vec3f p;
    for (int a = 0; a < 3; ++a)
      p[a] = std::uniform_real_distribution<float>(b.lower[a], b.upper[a])(rng);
    double vd;
    float vf;
    vec3d gd;
    vec3f gf;
    const bool okd = sampleField(m.view(0), vec3d(p), vd, &gd);
    const bool okf = sampleField(m.view(0), p, vf, &gf);
    ASSERT_EQ(okd, okf);
    if (okd) {
      EXPECT_NEAR(vf, vd, 1e-5 * std::max(1.0, std::abs(vd)));
    }
  }
}
