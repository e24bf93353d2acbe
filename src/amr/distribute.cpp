#include "exabricks/amr/distribute.h"

#include "exabricks/core/error.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace exa {

namespace {

// Little-endian on every platform exabricks runs on; the bytes never leave the run.
template <typename T> void put(std::vector<uint8_t>& out, const T& value) {
  const size_t at = out.size();
  out.resize(at + sizeof(T));
  std::memcpy(out.data() + at, &value, sizeof(T));
}

class Reader {
public:
  Reader(const std::vector<uint8_t>& bytes, const char* what) : bytes_(bytes), what_(what) {}
  template <typename T> T get() {
    T value;
    take(&value, sizeof(T));
    return value;
  }
  void take(void* out, size_t n) {
    if (n == 0) return; // an empty vector's data() may be null
    if (n > bytes_.size() - at_) fail("exabricks: a message of ", what_, " ends early (", bytes_.size(), " bytes)");
    std::memcpy(out, bytes_.data() + at_, n);
    at_ += n;
  }
  bool done() const { return at_ == bytes_.size(); }

private:
  const std::vector<uint8_t>& bytes_;
  const char* what_;
  size_t at_ = 0;
};

} // namespace

void agreeOrThrow(Collectives& comm, const std::string& error) {
  const std::vector<uint8_t> mine(error.begin(), error.end());
  const std::vector<std::vector<uint8_t>> all = comm.allGather(mine);
  for (size_t r = 0; r < all.size(); ++r) {
    if (all[r].empty()) continue;
    if (int(r) == comm.rank()) fail(error);
    fail("process ", r, ": ", std::string(all[r].begin(), all[r].end()));
  }
  if (!error.empty()) fail(error); // a group that lost this process's message still stops it
}

Census mergeCensuses(const std::vector<Census>& censuses) {
  Census merged;
  for (const Census& c : censuses) {
    merged.coarsestLevel = std::max(merged.coarsestLevel, c.coarsestLevel);
    merged.boxes.insert(merged.boxes.end(), c.boxes.begin(), c.boxes.end());
  }
  // One order whatever process sent which box: every process balances the same list.
  std::sort(merged.boxes.begin(), merged.boxes.end(), [](const CensusBox& a, const CensusBox& b) {
    for (int k = 2; k >= 0; --k)
      if (a.box.lower[k] != b.box.lower[k]) return a.box.lower[k] < b.box.lower[k];
    for (int k = 2; k >= 0; --k)
      if (a.box.upper[k] != b.box.upper[k]) return a.box.upper[k] < b.box.upper[k];
    return a.cells < b.cells;
  });
  return merged;
}

std::vector<uint8_t> encodeCensus(const Census& census) {
  std::vector<uint8_t> out;
  put(out, int32_t(census.coarsestLevel));
  put(out, uint64_t(census.boxes.size()));
  for (const CensusBox& b : census.boxes) {
    for (int a = 0; a < 3; ++a)
      put(out, b.box.lower[a]);
    for (int a = 0; a < 3; ++a)
      put(out, b.box.upper[a]);
    put(out, b.cells);
  }
  return out;
}

Census decodeCensus(const std::vector<uint8_t>& bytes) {
  Reader in(bytes, "a census");
  Census census;
  census.coarsestLevel = in.get<int32_t>();
  const uint64_t n = in.get<uint64_t>();
  if (n > bytes.size() / (7 * 8)) fail("exabricks: a census message claims ", n, " boxes in ", bytes.size(), " bytes");
  census.boxes.resize(n);
  for (CensusBox& b : census.boxes) {
    for (int a = 0; a < 3; ++a)
      b.box.lower[a] = in.get<int64_t>();
    for (int a = 0; a < 3; ++a)
      b.box.upper[a] = in.get<int64_t>();
    b.cells = in.get<double>();
  }
  if (!in.done()) fail("exabricks: a census message has bytes after its boxes");
  return census;
}

std::vector<uint8_t> encodeCells(const CellSet& set) {
  std::vector<uint8_t> out;
  const uint64_t n = set.cells.size();
  out.reserve(16 + n * (sizeof(Cell) + 4 * set.fields.size()));
  put(out, n);
  put(out, uint64_t(set.fields.size()));
  const size_t at = out.size();
  out.resize(at + n * sizeof(Cell));
  if (n) std::memcpy(out.data() + at, set.cells.data(), n * sizeof(Cell));
  for (const Field& f : set.fields) {
    const size_t fat = out.size();
    out.resize(fat + n * sizeof(float));
    if (n) std::memcpy(out.data() + fat, f.values.data(), n * sizeof(float));
  }
  return out;
}

void appendDecodedCells(CellSet& set, const std::vector<uint8_t>& bytes) {
  Reader in(bytes, "cells");
  const uint64_t n = in.get<uint64_t>();
  const uint64_t fields = in.get<uint64_t>();
  if (fields != set.fields.size())
    fail("exabricks: a message of cells holds ", fields, " fields, expected ", set.fields.size());
  if (n > bytes.size() / sizeof(Cell)) fail("exabricks: a message claims ", n, " cells in ", bytes.size(), " bytes");
  const size_t base = set.cells.size();
  set.cells.resize(base + n);
  in.take(set.cells.data() + base, n * sizeof(Cell));
  for (Field& f : set.fields) {
    f.values.resize(base + n);
    in.take(f.values.data() + base, n * sizeof(float));
  }
  if (!in.done()) fail("exabricks: a message of cells has bytes after its values");
}

namespace {

/// Where the cells lie: every process's census, merged the same way everywhere.
Census gatherCensus(const CellSet& mine, Collectives& comm) {
  std::vector<uint8_t> census;
  onEveryProcess(comm, [&] {
    CellCensus counter;
    counter.add(mine.cells.data(), mine.cells.size());
    census = encodeCensus(counter.finish());
  });
  std::vector<Census> all;
  for (const std::vector<uint8_t>& bytes : comm.allGather(census))
    all.push_back(decodeCensus(bytes));
  return mergeCensuses(all);
}

/// What this process sends each part: the cells whose supports reach its shading reach.
std::vector<std::vector<uint8_t>> outgoingShares(const CellSet& mine, const CellPart& part, Collectives& comm) {
  std::vector<std::vector<uint8_t>> outgoing(size_t(comm.size()));
  onEveryProcess(comm, [&] {
    for (int p = 0; p < comm.size(); ++p) {
      CellSet share;
      share.fields.resize(mine.fields.size());
      for (size_t f = 0; f < mine.fields.size(); ++f)
        share.fields[f].name = mine.fields[f].name;
      const box3l reach = shadingReach(part.partition.box(p), part.coarsestLevel);
      for (size_t i = 0; i < mine.cells.size(); ++i) {
        const Cell& c = mine.cells[i];
        if (!supportReaches(c.bounds(), c.level, reach)) continue;
        share.cells.push_back(c);
        for (size_t f = 0; f < mine.fields.size(); ++f)
          share.fields[f].values.push_back(mine.fields[f].values[i]);
      }
      outgoing[size_t(p)] = encodeCells(share);
    }
  });
  return outgoing;
}

} // namespace

CellPart distributeCells(CellSet&& mine, Collectives& comm) {
  CellPart part;
  // Where the cells lie: every process's census, merged and split the same way everywhere.
  const Census merged = gatherCensus(mine, comm);
  part.coarsestLevel = merged.coarsestLevel;
  part.totalCells = uint64_t(merged.cells() + 0.5);
  if (part.totalCells == 0) fail("exabricks: no process holds any cells");
  // The finest level and the value ranges over every process's cells.
  std::vector<uint8_t> summary;
  int finest = std::numeric_limits<int>::max();
  for (const Cell& c : mine.cells)
    finest = std::min(finest, c.level);
  put(summary, int32_t(finest));
  const box3l bounds = mine.bounds();
  for (int a = 0; a < 3; ++a)
    put(summary, bounds.lower[a]), put(summary, bounds.upper[a]);
  for (const Field& f : mine.fields) {
    range1f r;
    for (float v : f.values)
      if (std::isfinite(v)) r.extend(v);
    put(summary, r.lower);
    put(summary, r.upper);
  }
  part.finestLevel = std::numeric_limits<int>::max();
  part.valueRanges.assign(mine.fields.size(), range1f());
  for (const std::vector<uint8_t>& bytes : comm.allGather(summary)) {
    Reader in(bytes, "a summary");
    part.finestLevel = std::min(part.finestLevel, int(in.get<int32_t>()));
    box3l b;
    for (int a = 0; a < 3; ++a)
      b.lower[a] = in.get<int64_t>(), b.upper[a] = in.get<int64_t>();
    for (int a = 0; a < 3 && !b.empty(); ++a) {
      part.dataBounds.lower[a] = std::min(part.dataBounds.lower[a], b.lower[a]);
      part.dataBounds.upper[a] = std::max(part.dataBounds.upper[a], b.upper[a]);
    }
    for (range1f& r : part.valueRanges) {
      const float lo = in.get<float>(), hi = in.get<float>();
      r.extend(range1f{lo, hi}); // an empty range (no finite value there) extends nothing
    }
  }
  part.partition = KdPartition::balance(merged, comm.size());
  part.box = part.partition.box(comm.rank());

  // Each process sends every part the cells whose supports reach its shading reach.
  std::vector<std::vector<uint8_t>> outgoing = outgoingShares(mine, part, comm);
  const std::vector<std::vector<uint8_t>> incoming = comm.exchange(outgoing);
  outgoing.clear();
  part.cells.world = mine.world;
  part.cells.simulation = mine.simulation;
  for (const Field& f : mine.fields)
    part.cells.fields.push_back({f.name, {}, f.units});
  mine = CellSet(); // this process's share is sent: free it before the model is built
  onEveryProcess(comm, [&] {
    for (const std::vector<uint8_t>& bytes : incoming)
      appendDecodedCells(part.cells, bytes);
    for (const Cell& c : part.cells.cells)
      if (centreInside(c.lower, c.level, part.box)) ++part.ownedCells;
  });
  return part;
}

} // namespace exa
