// Every cell merged into cubes (loadMergedLeaves) checked against sums cell by cell.
#pragma once

#include "exabricks/io/load.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

/// Each cube of `m` is the volume-weighted mean of the cells of `set` in it (field `set`'s first,
/// found by name), and there is a cube wherever a cell is; the value ranges, finest level and
/// bounds are the cells'.
inline void expectCubeMeans(const exa::MergedLeaves& m, const exa::CellSet& set) {
  using namespace exa;
  const int64_t w = int64_t(1) << m.level;
  std::map<std::array<int64_t, 3>, std::pair<double, double>> truth; // weight, weighted sum
  range1f range;
  int finest = kMaxLevel;
  for (size_t i = 0; i < set.cells.size(); ++i) {
    const Cell& c = set.cells[i];
    EXPECT_LE(c.width(), w);
    auto& t =
        truth[{int64_t(std::floor(double(c.lower.x) / double(w))), int64_t(std::floor(double(c.lower.y) / double(w))),
               int64_t(std::floor(double(c.lower.z) / double(w)))}];
    const double volume = std::pow(double(c.width()), 3);
    t.first += volume;
    t.second += volume * set.fields[0].values[i];
    range.extend(set.fields[0].values[i]);
    finest = std::min(finest, c.level);
  }
  const auto named = std::find(m.model.fieldNames.begin(), m.model.fieldNames.end(), set.fields[0].name);
  ASSERT_NE(named, m.model.fieldNames.end());
  const size_t field = size_t(named - m.model.fieldNames.begin());
  EXPECT_EQ(m.ranges.at(field), range);
  EXPECT_EQ(m.finestLevel, finest);
  const box3l bounds = set.bounds();
  EXPECT_EQ(box3l(vec3l(m.cellBounds.lower), vec3l(m.cellBounds.upper)), bounds);
  ASSERT_EQ(m.model.cellCount(), truth.size());
  size_t checked = 0;
  for (const Brick& b : m.model.bricks) {
    ASSERT_EQ(b.level, m.level);
    for (int z = 0; z < b.size.z; ++z)
      for (int y = 0; y < b.size.y; ++y)
        for (int x = 0; x < b.size.x; ++x) {
          const vec3i at = b.lower + vec3i(x, y, z) * int32_t(w);
          const auto it = truth.find({at.x / w, at.y / w, at.z / w});
          ASSERT_NE(it, truth.end());
          const float v = m.model.fieldValues[field][b.valueOffset + size_t((z * b.size.y + y) * b.size.x + x)];
          const double expected = it->second.second / it->second.first;
          EXPECT_NEAR(v, expected, 1e-5 * std::max(1.0, std::abs(expected)));
          ++checked;
        }
  }
  EXPECT_EQ(checked, truth.size());
}
