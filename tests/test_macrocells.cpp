// The macrocells under the path tracer's majorant grid: each macrocell's value range holds the
// reconstruction anywhere in it (against the basis evaluated at random points) and the value of
// every cell whose support meets it (brute force), and no more than those touching it; a
// macrocell's range holds the reconstruction sampled densely over it and, where every corner of
// its pieces has a value, is exactly that range, both ends; the
// grid stays small for cells far apart. Then the majorant grid itself: far fewer tentative
// collisions where dense and empty space share a region, and the same picture as without it.
#include "datasets.h"
#include "lit_ball.h"

#include "exabricks/amr/macrocells.h"
#include "exabricks/amr/model.h"
#include "exabricks/render/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

using namespace exa;

namespace {

/// The range of the values of the cells whose open support (centre ± width), grown by `grow`
/// lattice units on every side, meets the closed box.
range1f bruteForceRange(const Model& m, const box3f& box, double grow) {
  range1f r;
  const ValueArray& values = m.fieldValues[0];
  for (const Brick& b : m.bricks) {
    const double w = b.cellWidth();
    for (int z = 0; z < b.size.z; ++z)
      for (int y = 0; y < b.size.y; ++y)
        for (int x = 0; x < b.size.x; ++x) {
          const vec3d centre = vec3d(b.lower) + vec3d(x + 0.5, y + 0.5, z + 0.5) * w;
          bool meets = true;
          for (int a = 0; a < 3; ++a)
            meets = meets && centre[a] - w - grow < double(box.upper[a]) && centre[a] + w + grow > double(box.lower[a]);
          if (meets) r.extend(values[b.valueOffset + size_t(x) + size_t(b.size.x) * (y + size_t(b.size.y) * z)]);
        }
  }
  return r;
}

bool holds(const range1f& outer, const range1f& inner) {
  return inner.empty() || (outer.lower <= inner.lower && outer.upper >= inner.upper);
}

} // namespace

TEST(Macrocells, RangesHoldTheReconstructionAndEveryCellWhoseSupportMeetsThem) {
  for (const test::NamedCells& d : test::smallDatasets()) {
    if (d.name == "ramp-far") continue; // far apart: below
    const Model m = buildModel(CellSet(d.cells));
    // Small macrocells, so that cells of several levels straddle them.
    const MacrocellGrid grid = macrocellsOver(m.regions.bounds, 12, 1);
    const std::vector<range1f> ranges = macrocellValueRanges(grid, m.bricks, m.fieldValues[0].data());
    ASSERT_EQ(ranges.size(), grid.count());
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    size_t sampled = 0;
    for (int z = 0; z < grid.dims.z; ++z)
      for (int y = 0; y < grid.dims.y; ++y)
        for (int x = 0; x < grid.dims.x; ++x) {
          const vec3i c(x, y, z);
          const box3f box = grid.bounds(c);
          const range1f& r = ranges[grid.index(c)];
          const range1f exact = bruteForceRange(m, box, 0.0);
          ASSERT_TRUE(holds(r, exact)) << d.name << " macrocell " << x << "," << y << "," << z << ": [" << r.lower
                                       << ", " << r.upper << "] misses [" << exact.lower << ", " << exact.upper << "]";
          // And no more: at most the cells whose supports touch its faces.
          ASSERT_TRUE(holds(bruteForceRange(m, box, 1e-3), r)) << d.name << " macrocell " << x << "," << y << "," << z;
          for (int k = 0; k < 8; ++k) {
            const vec3f p = box.lower + vec3f(u(rng), u(rng), u(rng)) * grid.cellSize;
            double v;
            vec3d g;
            if (!m.sampleWorld(0, vec3d(p), v, g)) continue;
            ++sampled;
            const double slack = 1e-5 * (1.0 + std::abs(v));
            ASSERT_TRUE(!r.empty() && v >= r.lower - slack && v <= r.upper + slack)
                << d.name << " value " << v << " at " << p.x << "," << p.y << "," << p.z << " outside [" << r.lower
                << ", " << r.upper << "]";
          }
        }
    EXPECT_GT(sampled, 50u) << d.name;
  }
}

TEST(Macrocells, ReconstructionRangesHoldItAndAreExactWhereEveryCornerHasAValue) {
  for (const test::NamedCells& d : test::smallDatasets()) {
    if (d.name == "ramp-far") continue;
    const Model m = buildModel(CellSet(d.cells));
    const MacrocellGrid grid = macrocellsOver(m.regions.bounds, 12, 1);
    const std::vector<range1f> supports = macrocellValueRanges(grid, m.bricks, m.fieldValues[0].data());
    const HatPlanes planes = hatPlanesOf(m.bricks);
    const FieldView view = m.view(0);
    size_t exactCount = 0, bounded = 0, narrower = 0, checked = 0;
    for (size_t i = 0; i < grid.count(); ++i) {
      const vec3i c = grid.cellAt(i);
      ASSERT_EQ(grid.index(c), i);
      range1f r;
      bool exact = false;
      const bool some = macrocellRange(grid, c, view, planes, size_t(1) << 20, r, &exact);
      const range1f& support = supports[i];
      const double slack = 1e-5 * (1.0 + std::max(std::abs(support.lower), std::abs(support.upper)));
      if (some) {
        (exact ? exactCount : bounded) += 1;
        ASSERT_TRUE(r.lower >= support.lower - slack && r.upper <= support.upper + slack)
            << d.name << " macrocell " << i << ": [" << r.lower << ", " << r.upper << "] beyond the supports' ["
            << support.lower << ", " << support.upper << "]";
        narrower += r.upper - r.lower < support.upper - support.lower - slack;
      }
      if (i % 5 != 0) continue;
      // Brute force on a lattice of quarter finest units over the macrocell within the data's box:
      // it holds every corner of the pieces (cell centres lie on multiples of half a finest unit).
      const box3f box = grid.bounds(c);
      vec3f lo, hi;
      for (int a = 0; a < 3; ++a)
        lo[a] = std::max(box.lower[a], view.bounds.lower[a]), hi[a] = std::min(box.upper[a], view.bounds.upper[a]);
      double low = INFINITY, high = -INFINITY;
      for (float z = lo.z; z <= hi.z; z += 0.25f)
        for (float y = lo.y; y <= hi.y; y += 0.25f)
          for (float x = lo.x; x <= hi.x; x += 0.25f) {
            double v;
            if (!sampleField(view, vec3d(x, y, z), v)) continue;
            ASSERT_TRUE(some) << d.name << " macrocell " << i << " has no range, but a value at " << x << "," << y
                              << "," << z;
            ASSERT_TRUE(v >= r.lower - slack && v <= r.upper + slack)
                << d.name << " value " << v << " at " << x << "," << y << "," << z << " outside [" << r.lower << ", "
                << r.upper << "]";
            low = std::min(low, v), high = std::max(high, v);
          }
      checked += some;
      if (!some || !exact) continue;
      // Exact: both ends are reached.
      EXPECT_NEAR(r.lower, low, slack) << d.name << " macrocell " << i;
      EXPECT_NEAR(r.upper, high, slack) << d.name << " macrocell " << i;
    }
    std::printf("%s: %zu exact ranges and %zu bounds where some corner has no value (%zu narrower than the "
                "supports', %zu checked densely)\n",
                d.name.c_str(), exactCount, bounded, narrower, checked);
    EXPECT_GT(exactCount, 0u) << d.name;
    if (d.name != "single") {
      EXPECT_GT(narrower, 0u) << d.name;
    }
  }
}

TEST(Macrocells, TheGridStaysSmallForCellsFarApartAndIsEmptyBetweenThem) {
  const Model m = buildModel(test::farApart(generateScene({"ramp", 800, 5, 3})));
  const MacrocellGrid grid = macrocellsOver(m.regions.bounds);
  EXPECT_LE(std::max({grid.dims.x, grid.dims.y, grid.dims.z}), 256);
  EXPECT_LE(grid.count(), size_t(128 * 128 * 128));
  const std::vector<range1f> ranges = macrocellValueRanges(grid, m.bricks, m.fieldValues[0].data());
  size_t empty = 0;
  for (const range1f& r : ranges)
    empty += r.empty();
  EXPECT_GT(double(empty), 0.9 * double(ranges.size())) << "the space between the two copies holds no cell";
  EXPECT_LT(empty, ranges.size());
}

TEST(MajorantGrid, CutsNullCollisionsAndKeepsThePicture) {
  // The lit ball: one brick, one region, dense at the centre and empty at the corners. The
  // region's majorant is the centre's; the grid's follows the ball.
  test::LitBall ball;
  ball.frame.samplesPerPixel = 64;
  Renderer r(ball.model, DatasetInfo::of(ball.model));
  r.setScene(ball.scene);
  RenderStats with, without;
  const Image a = r.render(ball.frame, &with);
  RendererOptions off = r.options();
  off.majorantGrid = false;
  r.setOptions(off);
  const Image b = r.render(ball.frame, &without);
  ball.frame.seed = 1;
  const Image c = r.render(ball.frame);
  std::printf("tentative collisions: %llu with the grid, %llu without (%.2fx); rms difference %.3f/255 against "
              "%.3f/255 between two seeds without it\n",
              (unsigned long long)with.samples, (unsigned long long)without.samples,
              double(without.samples) / double(with.samples), test::rmsSteps(a, b), test::rmsSteps(b, c));
  EXPECT_LT(double(with.samples), 0.5 * double(without.samples));
  // Unbiased either way: the grid's picture differs from the regions' by no more than noise.
  EXPECT_LT(test::rmsSteps(a, b), 1.3 * test::rmsSteps(b, c));
  // The mean radiance agrees within the pixels' noise (a z-score of the mean difference).
  double sum = 0, sumSquares = 0, meanB = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const double d =
        double(a.pixels[i].x + a.pixels[i].y + a.pixels[i].z) - (b.pixels[i].x + b.pixels[i].y + b.pixels[i].z);
    sum += d;
    sumSquares += d * d;
    meanB += b.pixels[i].x + b.pixels[i].y + b.pixels[i].z;
  }
  const double n = double(a.pixels.size()), mean = sum / n;
  const double standardError = std::sqrt((sumSquares / n - mean * mean) / n);
  std::printf("mean radiance: %.4f without the grid, difference %.5f, standard error %.5f\n", meanB / n, mean,
              standardError);
  EXPECT_LT(std::abs(mean), 4.0 * standardError);
  EXPECT_LT(std::abs(mean), 0.02 * meanB / n);
}
