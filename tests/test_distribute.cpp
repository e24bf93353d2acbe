// Cells spread over processes in arbitrary shares, redistributed into k-d parts with halos
// (distributeCells), with the processes as threads: every part holds exactly the cells whose
// supports reach its shading reach, taken straight from the whole dataset; the agreed values
// (bounds, finest level, ranges) are the whole dataset's; a failure on one process stops all.
#include "datasets.h"

#include "exabricks/amr/distribute.h"
#include "exabricks/core/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <barrier>
#include <functional>
#include <mutex>
#include <random>
#include <thread>

namespace exa {
namespace {

/// Threads as processes: each collective posts this thread's message, waits for all, reads.
class ThreadGroup {
public:
  explicit ThreadGroup(int n) : n_(n), barrier_(n), board_(size_t(n)) {}
  int size() const { return n_; }

  std::vector<std::vector<uint8_t>> allGather(int rank, const std::vector<uint8_t>& mine) {
    board_[size_t(rank)] = {mine};
    barrier_.arrive_and_wait();
    std::vector<std::vector<uint8_t>> out;
    for (int r = 0; r < n_; ++r)
      out.push_back(board_[size_t(r)][0]);
    barrier_.arrive_and_wait();
    return out;
  }
  std::vector<std::vector<uint8_t>> exchange(int rank, const std::vector<std::vector<uint8_t>>& outgoing) {
    board_[size_t(rank)] = outgoing;
    barrier_.arrive_and_wait();
    std::vector<std::vector<uint8_t>> out;
    for (int r = 0; r < n_; ++r)
      out.push_back(board_[size_t(r)][size_t(rank)]);
    barrier_.arrive_and_wait();
    return out;
  }

private:
  int n_;
  std::barrier<> barrier_;
  std::vector<std::vector<std::vector<uint8_t>>> board_;
};

class ThreadCollectives : public Collectives {
public:
  ThreadCollectives(ThreadGroup& g, int rank) : g_(g), rank_(rank) {}
  int rank() const override { return rank_; }
  int size() const override { return g_.size(); }
  std::vector<std::vector<uint8_t>> allGather(const std::vector<uint8_t>& mine) override {
    return g_.allGather(rank_, mine);
  }
  std::vector<std::vector<uint8_t>> exchange(const std::vector<std::vector<uint8_t>>& outgoing) override {
    return g_.exchange(rank_, outgoing);
  }

private:
  ThreadGroup& g_;
  int rank_;
};

/// Runs work(comm) on n threads; returns each one's error (empty where it succeeded).
std::vector<std::string> onThreads(int n, const std::function<void(Collectives&)>& work) {
  ThreadGroup group(n);
  std::vector<std::string> errors(static_cast<size_t>(n));
  std::vector<std::thread> threads;
  for (int r = 0; r < n; ++r)
    threads.emplace_back([&, r] {
      ThreadCollectives comm(group, r);
      try {
        work(comm);
      } catch (const std::exception& e) {
        errors[size_t(r)] = e.what();
      }
    });
  for (std::thread& t : threads)
    t.join();
  return errors;
}

/// A random share of the cells for each of n processes (some possibly empty).
std::vector<CellSet> randomShares(const CellSet& whole, int n, uint32_t seed) {
  std::vector<CellSet> shares(static_cast<size_t>(n));
  for (CellSet& s : shares) {
    s.world = whole.world;
    for (const Field& f : whole.fields)
      s.fields.push_back({f.name, {}, f.units});
  }
  std::mt19937 rng(seed);
  // Runs of consecutive cells, as a reader's blocks: each run to a random process.
  std::uniform_int_distribution<int> who(0, n - 1), run(1, 300);
  for (size_t i = 0; i < whole.cells.size();) {
    CellSet& s = shares[size_t(who(rng))];
    const size_t end = std::min(whole.cells.size(), i + size_t(run(rng)));
    for (; i < end; ++i) {
      s.cells.push_back(whole.cells[i]);
      for (size_t f = 0; f < whole.fields.size(); ++f)
        s.fields[f].values.push_back(whole.fields[f].values[i]);
    }
  }
  return shares;
}

using Keyed = std::vector<std::pair<std::tuple<int, int, int, int>, std::vector<float>>>;
Keyed keyed(const CellSet& s) {
  Keyed out;
  for (size_t i = 0; i < s.cells.size(); ++i) {
    const Cell& c = s.cells[i];
    std::vector<float> v;
    for (const Field& f : s.fields)
      v.push_back(f.values[i]);
    out.push_back({{c.lower.x, c.lower.y, c.lower.z, c.level}, v});
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Distribute, EveryPartHoldsExactlyTheCellsItsHaloNeeds) {
  for (const test::NamedCells& d : test::smallDatasets()) {
    for (int n : {1, 2, 3, 4}) {
      const std::vector<CellSet> shares = randomShares(d.cells, n, uint32_t(n * 7 + 1));
      std::vector<CellPart> parts(static_cast<size_t>(n));
      const std::vector<std::string> errors = onThreads(n, [&](Collectives& comm) {
        CellSet mine = shares[size_t(comm.rank())];
        parts[size_t(comm.rank())] = distributeCells(std::move(mine), comm);
      });
      for (const std::string& e : errors)
        ASSERT_EQ(e, "") << d.name << " n=" << n;
      // Independent truth: the whole dataset's cells whose supports reach each part's reach.
      CellCensus census;
      census.add(d.cells.cells.data(), d.cells.cells.size());
      const KdPartition expected = KdPartition::balance(census.finish(), n);
      uint64_t owned = 0;
      int finest = 99;
      for (const Cell& c : d.cells.cells)
        finest = std::min(finest, c.level);
      for (int p = 0; p < n; ++p) {
        const CellPart& part = parts[size_t(p)];
        EXPECT_EQ(part.box, expected.box(p)) << d.name;
        EXPECT_EQ(part.partition.encode(), parts[0].partition.encode());
        EXPECT_EQ(part.dataBounds, d.cells.bounds());
        EXPECT_EQ(part.finestLevel, finest);
        EXPECT_EQ(part.totalCells, d.cells.size());
        ASSERT_EQ(part.valueRanges.size(), d.cells.fields.size());
        for (size_t f = 0; f < d.cells.fields.size(); ++f) {
          const auto [lo, hi] = std::minmax_element(d.cells.fields[f].values.begin(), d.cells.fields[f].values.end());
          EXPECT_EQ(part.valueRanges[f].lower, *lo);
          EXPECT_EQ(part.valueRanges[f].upper, *hi);
        }
        CellSet truth = d.cells;
        keepSupportOf(truth, shadingReach(expected.box(p), part.coarsestLevel));
        EXPECT_EQ(keyed(part.cells), keyed(truth)) << d.name << " n=" << n << " part " << p;
        EXPECT_EQ(part.cells.world.scale, d.cells.world.scale);
        owned += part.ownedCells;
      }
      EXPECT_EQ(owned, d.cells.size()) << d.name << " n=" << n;
    }
  }
}

TEST(Distribute, AFailureOnOneProcessStopsEveryProcess) {
  const std::vector<std::string> errors = onThreads(3, [](Collectives& comm) {
    onEveryProcess(comm, [&] {
      if (comm.rank() == 1) fail("cannot read block 7");
    });
  });
  EXPECT_EQ(errors[1], "cannot read block 7");
  EXPECT_EQ(errors[0], "process 1: cannot read block 7");
  EXPECT_EQ(errors[2], "process 1: cannot read block 7");
}

TEST(Distribute, MoreProcessesThanDataLeaveEmptyParts) {
  CellSet one;
  one.cells.push_back(Cell{vec3i(0), 0});
  one.fields.push_back({"scalar", {1.f}, ""});
  std::vector<CellPart> parts(4);
  const std::vector<std::string> errors = onThreads(4, [&](Collectives& comm) {
    CellSet mine;
    mine.fields.push_back({"scalar", {}, ""});
    if (comm.rank() == 2) mine = one;
    parts[size_t(comm.rank())] = distributeCells(std::move(mine), comm);
  });
  for (const std::string& e : errors)
    ASSERT_EQ(e, "");
  uint64_t owned = 0;
  for (const CellPart& p : parts)
    owned += p.ownedCells;
  EXPECT_EQ(owned, 1u);
}

TEST(Distribute, CorruptMessagesAreRefused) {
  CellSet s;
  s.fields.push_back({"scalar", {}, ""});
  std::vector<uint8_t> bytes = encodeCells(s);
  bytes.push_back(0);
  EXPECT_THROW(appendDecodedCells(s, bytes), Error);
  std::vector<uint8_t> census = encodeCensus(Census{});
  census.resize(census.size() - 1);
  EXPECT_THROW(decodeCensus(census), Error);
}

} // namespace
} // namespace exa
