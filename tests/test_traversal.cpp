#include "datasets.h"
#include "exabricks/accel/traversal.h"

#include <gtest/gtest.h>

#include <random>

using namespace exa;
using namespace exa::test;

namespace {

std::vector<Segment> collect(const RegionTraversal& t, const Ray& ray) {
  std::vector<Segment> out;
  t.traverse(ray, [&](const Segment& s) {
    out.push_back(s);
    return true;
  });
  return out;
}

/// Brute force: the union of every region's ray interval beyond tmin, as sorted disjoint spans.
std::vector<std::pair<float, float>> coverage(const Model& m, const Ray& ray) {
  std::vector<std::pair<float, float>> spans;
  const vec3f inv = safeInverse(ray.dir);
  for (const Region& r : m.regions.regions) {
    float t0, t1;
    if (!rayBoxInterval(ray, inv, r.bounds(), t0, t1)) continue;
    t0 = std::max(t0, ray.tmin);
    t1 = std::min(t1, ray.tmax);
    if (t1 > t0) spans.push_back({t0, t1});
  }
  std::sort(spans.begin(), spans.end());
  std::vector<std::pair<float, float>> merged;
  for (const auto& s : spans) {
    if (!merged.empty() && s.first <= merged.back().second + 1e-4f)
      merged.back().second = std::max(merged.back().second, s.second);
    else
      merged.push_back(s);
  }
  return merged;
}

std::vector<Ray> testRays(const Model& m, std::mt19937& rng) {
  std::vector<Ray> rays;
  const box3f b = m.regions.bounds;
  std::uniform_real_distribution<float> u(0.f, 1.f);
  auto inside = [&] {
    return vec3f(b.lower.x + u(rng) * (b.upper.x - b.lower.x), b.lower.y + u(rng) * (b.upper.y - b.lower.y),
                 b.lower.z + u(rng) * (b.upper.z - b.lower.z));
  };
  for (int i = 0; i < 300; ++i) {
    Ray r;
    const vec3f target = inside();
    const vec3f dir = normalize(vec3f(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f));
    if (i % 3 == 0) { // from outside
      r.org = target - dir * (2.f * length(b.size()));
      r.dir = dir;
    } else if (i % 3 == 1) { // starting inside the data
      r.org = target;
      r.dir = dir;
    } else { // along a region face, parallel to one or two axes
      const Region& reg = m.regions.regions[rng() % m.regions.regions.size()];
      const box3f rb = reg.bounds();
      r.org = vec3f(rb.lower.x, rb.lower.y + u(rng) * (rb.upper.y - rb.lower.y), rb.upper.z);
      r.dir = i % 2 ? vec3f(0.f, 1.f, 0.f) : normalize(vec3f(0.f, 1.f, u(rng)));
      r.org.y = b.lower.y - 1.f;
    }
    rays.push_back(r);
  }
  return rays;
}

} // namespace

TEST(Traversal, SegmentsTileEachRayAndBothBackEndsAgree) {
  for (const auto& d : smallDatasets()) {
    SCOPED_TRACE(d.name);
    CellSet copy = d.cells;
    const Model m = buildModel(std::move(copy));
    const RegionTraversal kd(m, TraversalKind::KdTree), embree(m, TraversalKind::Embree);
    std::mt19937 rng(17);
    for (const Ray& ray : testRays(m, rng)) {
      const std::vector<Segment> a = collect(kd, ray), b = collect(embree, ray);
      ASSERT_EQ(a.size(), b.size());
      for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].region, b[i].region);
        EXPECT_EQ(a[i].t0, b[i].t0);
        EXPECT_EQ(a[i].t1, b[i].t1);
        EXPECT_LT(a[i].t0, a[i].t1);
        if (i > 0) {
          EXPECT_GE(a[i].t0, a[i - 1].t1) << "segments overlap";
        }
      }
      // Same coverage as the brute-force union of region intervals: no gaps, no extra.
      std::vector<std::pair<float, float>> merged;
      for (const Segment& s : a) {
        if (!merged.empty() && s.t0 <= merged.back().second + 1e-4f)
          merged.back().second = s.t1;
        else
          merged.push_back({s.t0, s.t1});
      }
      const auto truth = coverage(m, ray);
      ASSERT_EQ(merged.size(), truth.size())
          << "ray org " << ray.org.x << " " << ray.org.y << " " << ray.org.z << " dir " << ray.dir.x << " " << ray.dir.y
          << " " << ray.dir.z << " first truth " << (truth.empty() ? 0.f : truth[0].first) << ".."
          << (truth.empty() ? 0.f : truth[0].second);
      for (size_t i = 0; i < truth.size(); ++i) {
        EXPECT_NEAR(merged[i].first, truth[i].first, 1e-3f);
        EXPECT_NEAR(merged[i].second, truth[i].second, 1e-3f);
      }
    }
  }
}

TEST(Traversal, HiddenRegionsAreSkipped) {
  CellSet cells = generateScene({"blobs", 5000, 2, 3});
  const Model m = buildModel(std::move(cells));
  for (TraversalKind kind : {TraversalKind::KdTree, TraversalKind::Embree}) {
    RegionTraversal t(m, kind);
    std::vector<uint8_t> visible(m.regions.regions.size(), 0);
    for (size_t i = 0; i < visible.size(); i += 3)
      visible[i] = 1;
    t.setVisible(visible);
    std::mt19937 rng(5);
    for (const Ray& ray : testRays(m, rng))
      for (const Segment& s : collect(t, ray))
        EXPECT_TRUE(visible[s.region]);
  }
}

TEST(Traversal, HiddenSubtreesGiveTheVisibleSegmentsOfTheFullWalk) {
  const Model m = buildModel(generateScene({"blobs", 5000, 2, 3}));
  // Whole subtrees hidden (the lower half in x), and a scattering of hidden regions elsewhere.
  const float mid = 0.5f * (m.regions.bounds.lower.x + m.regions.bounds.upper.x);
  std::vector<uint8_t> visible(m.regions.regions.size(), 0);
  size_t shown = 0;
  for (size_t i = 0; i < visible.size(); ++i) {
    const box3f b = m.regions.regions[i].bounds();
    visible[i] = (b.lower.x >= mid) != (i % 7 == 0);
    shown += visible[i];
  }
  ASSERT_GT(shown, 0u);
  ASSERT_LT(shown, visible.size());
  RegionTraversal all(m, TraversalKind::KdTree), some(m, TraversalKind::KdTree), embree(m, TraversalKind::Embree);
  some.setVisible(visible);
  embree.setVisible(visible);
  std::mt19937 rng(9);
  size_t segments = 0;
  for (const Ray& ray : testRays(m, rng)) {
    std::vector<Segment> expected;
    for (const Segment& s : collect(all, ray))
      if (visible[s.region]) expected.push_back(s);
    const std::vector<Segment> got = collect(some, ray), viaEmbree = collect(embree, ray);
    ASSERT_EQ(got.size(), expected.size());
    ASSERT_EQ(viaEmbree.size(), expected.size());
    for (size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].region, expected[i].region);
      EXPECT_EQ(viaEmbree[i].region, expected[i].region);
      EXPECT_NEAR(got[i].t0, expected[i].t0, 1e-4f * (1.f + std::abs(expected[i].t0)));
      EXPECT_EQ(got[i].t1, expected[i].t1);
    }
    segments += got.size();
  }
  EXPECT_GT(segments, 0u);
}
