#include "parallel_parts.h"

#include "amr_cells.h"

#include "exabricks/core/error.h"

#include <nlohmann/json.hpp>

#include <vtkCommunicator.h>
#include <vtkMultiProcessController.h>
#include <vtkOverlappingAMR.h>

#include <algorithm>
#include <cstring>

namespace exa::paraview {

int ControllerCollectives::rank() const { return controller_->GetLocalProcessId(); }

int ControllerCollectives::size() const { return controller_->GetNumberOfProcesses(); }

std::vector<std::vector<uint8_t>> ControllerCollectives::allGather(const std::vector<uint8_t>& mine) {
  vtkCommunicator* comm = controller_->GetCommunicator();
  const int n = size();
  long long length = static_cast<long long>(mine.size());
  std::vector<long long> lengths(size_t(n), 0);
  if (!comm->AllGather(&length, lengths.data(), 1)) fail("ExaBricks: the processes could not exchange sizes");
  std::vector<vtkIdType> counts(static_cast<size_t>(n)), offsets(static_cast<size_t>(n));
  vtkIdType total = 0;
  for (int r = 0; r < n; ++r) {
    counts[size_t(r)] = vtkIdType(lengths[size_t(r)]);
    offsets[size_t(r)] = total;
    total += counts[size_t(r)];
  }
  std::vector<char> all(size_t(std::max<vtkIdType>(total, 1)));
  const char empty = 0;
  if (!comm->AllGatherV(mine.empty() ? &empty : reinterpret_cast<const char*>(mine.data()), all.data(),
                        vtkIdType(mine.size()), counts.data(), offsets.data()))
    fail("ExaBricks: the processes could not exchange data");
  std::vector<std::vector<uint8_t>> out(static_cast<size_t>(n));
  for (int r = 0; r < n; ++r)
    out[size_t(r)].assign(all.begin() + offsets[size_t(r)], all.begin() + offsets[size_t(r)] + counts[size_t(r)]);
  return out;
}

std::vector<std::vector<uint8_t>> ControllerCollectives::exchange(const std::vector<std::vector<uint8_t>>& outgoing) {
  vtkCommunicator* comm = controller_->GetCommunicator();
  const int n = size(), me = rank();
  if (int(outgoing.size()) != n) fail("ExaBricks: ", outgoing.size(), " messages for ", n, " processes");
  // Every process learns every message's size, then each process gathers what is sent to it.
  std::vector<long long> mine(static_cast<size_t>(n)), sizes(size_t(n) * size_t(n));
  for (int p = 0; p < n; ++p)
    mine[size_t(p)] = static_cast<long long>(outgoing[size_t(p)].size());
  if (!comm->AllGather(mine.data(), sizes.data(), n)) fail("ExaBricks: the processes could not exchange sizes");
  std::vector<std::vector<uint8_t>> incoming(static_cast<size_t>(n));
  for (int root = 0; root < n; ++root) {
    std::vector<vtkIdType> counts(static_cast<size_t>(n)), offsets(static_cast<size_t>(n));
    vtkIdType total = 0;
    for (int r = 0; r < n; ++r) {
      counts[size_t(r)] = vtkIdType(sizes[size_t(r) * size_t(n) + size_t(root)]);
      offsets[size_t(r)] = total;
      total += counts[size_t(r)];
    }
    std::vector<char> received(root == me ? size_t(std::max<vtkIdType>(total, 1)) : 1);
    const std::vector<uint8_t>& send = outgoing[size_t(root)];
    const char empty = 0;
    if (!comm->GatherV(send.empty() ? &empty : reinterpret_cast<const char*>(send.data()), received.data(),
                       vtkIdType(send.size()), counts.data(), offsets.data(), root))
      fail("ExaBricks: the processes could not exchange cells");
    if (root == me)
      for (int r = 0; r < n; ++r)
        incoming[size_t(r)].assign(received.begin() + offsets[size_t(r)],
                                   received.begin() + offsets[size_t(r)] + counts[size_t(r)]);
  }
  return incoming;
}

namespace {

std::vector<uint8_t> encodeBoxes(const std::vector<GridPatch>& boxes) {
  std::vector<uint8_t> out(boxes.size() * 9 * 8);
  uint8_t* q = out.data();
  for (const GridPatch& p : boxes)
    for (int a = 0; a < 3; ++a) {
      const double lo = p.lower[a], hi = p.upper[a];
      const int64_t cells = p.cells[a];
      std::memcpy(q, &lo, 8), std::memcpy(q + 8, &hi, 8), std::memcpy(q + 16, &cells, 8);
      q += 24;
    }
  return out;
}

void decodeBoxes(const std::vector<uint8_t>& bytes, std::vector<GridPatch>& out) {
  if (bytes.size() % (9 * 8)) fail("ExaBricks: a message of block boxes has ", bytes.size(), " bytes");
  const uint8_t* q = bytes.data();
  for (size_t i = 0; i < bytes.size() / (9 * 8); ++i) {
    GridPatch p;
    p.elsewhere = true;
    for (int a = 0; a < 3; ++a) {
      int64_t cells = 0;
      std::memcpy(&p.lower[a], q, 8), std::memcpy(&p.upper[a], q + 8, 8), std::memcpy(&cells, q + 16, 8);
      p.cells[a] = cells;
      q += 24;
    }
    out.push_back(p);
  }
}

} // namespace

PartNumbers partNumbers(const Model* model, uint64_t ownedCells) {
  PartNumbers n;
  n.ownedCells = ownedCells;
  if (model) {
    const ModelSummary s = summarize(*model);
    n.cells = s.cells;
    n.bytes = s.brickBytes + s.valueBytes + s.regionBytes;
  }
  return n;
}

std::string partsJson(const std::vector<PartNumbers>& parts) {
  nlohmann::json out = nlohmann::json::array();
  for (size_t r = 0; r < parts.size(); ++r)
    out.push_back(
        {{"rank", r}, {"cells", parts[r].cells}, {"owned_cells", parts[r].ownedCells}, {"bytes", parts[r].bytes}});
  return out.dump();
}

ProcessPart buildProcessPart(vtkOverlappingAMR* amr, const std::string& name, Collectives& comm) {
  // The boxes of every other process's blocks: they set the lattice and cover coarser cells here.
  std::vector<uint8_t> mine;
  onEveryProcess(comm, [&] { mine = encodeBoxes(amrBlockBoxes(amr)); });
  const std::vector<std::vector<uint8_t>> boxes = comm.allGather(mine);
  CellSet cells;
  onEveryProcess(comm, [&] {
    std::vector<GridPatch> elsewhere;
    for (int r = 0; r < comm.size(); ++r)
      if (r != comm.rank()) decodeBoxes(boxes[size_t(r)], elsewhere);
    cells = amrLeafCells(amr, name, elsewhere);
  });
  const WorldTransform world = cells.world;
  CellPart part = distributeCells(std::move(cells), comm);

  ProcessPart out;
  onEveryProcess(comm, [&] {
    if (!part.cells.cells.empty()) out.model = std::make_unique<Model>(buildModel(std::move(part.cells)));
  });
  const box3l& b = part.dataBounds;
  out.dataset = DatasetInfo::from(part.finestLevel,
                                  box3i(vec3i(int(b.lower.x), int(b.lower.y), int(b.lower.z)),
                                        vec3i(int(b.upper.x), int(b.upper.y), int(b.upper.z))),
                                  world.scale, part.valueRanges);
  out.domain = world.toWorld(part.box);
  const box3d data = world.toWorld(part.dataBounds);
  for (int a = 0; a < 3; ++a) {
    out.bounds[2 * a] = std::clamp(out.domain.lower[a], data.lower[a], data.upper[a]);
    out.bounds[2 * a + 1] = std::clamp(out.domain.upper[a], data.lower[a], data.upper[a]);
  }

  // What each process holds, for the representation's information.
  const PartNumbers mineNumbers = partNumbers(out.model.get(), part.ownedCells);
  std::vector<uint8_t> numbers(sizeof(PartNumbers));
  std::memcpy(numbers.data(), &mineNumbers, sizeof(PartNumbers));
  std::vector<PartNumbers> all;
  for (const std::vector<uint8_t>& bytes : comm.allGather(numbers)) {
    PartNumbers n;
    if (bytes.size() == sizeof(n)) std::memcpy(&n, bytes.data(), sizeof(n));
    all.push_back(n);
  }
  out.partsJson = partsJson(all);
  return out;
}

} // namespace exa::paraview
