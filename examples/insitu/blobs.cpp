// A small AMR simulation handing every step to ParaView Catalyst: Gaussian blobs that move on
// circles through the unit cube, sampled on a four-level hierarchy (32^3 cells at level 0,
// ratio 2) that follows the blobs and is rebuilt every few steps. The blocks are dealt out
// round-robin over the MPI processes; each process computes its blocks only. Every step goes to
// Catalyst as a vtkOverlappingAMR (the metadata of every block on every process, the cells of a
// block only where it lives), and the Catalyst Python script renders it (render.py: the ExaBricks
// representation, an image per step, the data every few steps).
//
//   mpirun -np 4 exabricks_insitu_blobs render.py --steps 20 --regrid 5 --out frames
//
// A failing Catalyst script is reported and the simulation goes on.
#include <vtkAMRBox.h>
#include <vtkCPDataDescription.h>
#include <vtkCPInputDataDescription.h>
#include <vtkCPProcessor.h>
#include <vtkCPPythonScriptV2Pipeline.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkOverlappingAMR.h>
#include <vtkSmartPointer.h>
#include <vtkStructuredData.h>
#include <vtkUniformGrid.h>

#include <mpi.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

constexpr int kLevels = 4;
constexpr int kBlock = 8;   // cells per block side, every level
constexpr int kCoarse = 32; // level-0 cells per side of the unit cube
constexpr int kBlobs = 3;
constexpr double kSigma = 0.09;

struct Block {
  int level = 0;
  std::array<int, 3> lower{}; // first cell, in the level's cell indices
};

std::array<double, 3> blobCentre(int b, double t) {
  const double phase = 2.0944 * b, w = 0.6 + 0.2 * b;
  return {0.5 + 0.22 * std::cos(w * t + phase), 0.5 + 0.22 * std::sin(w * t + phase), 0.3 + 0.2 * b};
}

double field(const std::array<double, 3>& x, double t) {
  double v = 0.0;
  for (int b = 0; b < kBlobs; ++b) {
    const std::array<double, 3> c = blobCentre(b, t);
    const double d2 = (x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) + (x[2] - c[2]) * (x[2] - c[2]);
    v += std::exp(-d2 / (kSigma * kSigma));
  }
  return v;
}

double spacing(int level) { return 1.0 / (kCoarse << level); }

// The hierarchy at time t: every level-0 block; a block's octant is refined (into one block of
// the next level) where a blob centre lies within `reach` of the octant's centre.
std::vector<Block> regrid(double t) {
  std::vector<Block> blocks;
  const int n = kCoarse / kBlock;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        blocks.push_back({0, {x * kBlock, y * kBlock, z * kBlock}});
  const double reach[kLevels] = {0.16, 0.08, 0.04, 0.0};
  for (int level = 0; level + 1 < kLevels; ++level) {
    std::vector<Block> children;
    for (const Block& b : blocks) {
      if (b.level != level) continue;
      for (int o = 0; o < 8; ++o) {
        std::array<int, 3> lower;
        std::array<double, 3> centre;
        for (int a = 0; a < 3; ++a) {
          lower[size_t(a)] = b.lower[size_t(a)] + ((o >> a) & 1) * kBlock / 2;
          centre[size_t(a)] = (lower[size_t(a)] + kBlock / 4.0) * spacing(level);
        }
        bool near = false;
        for (int k = 0; k < kBlobs && !near; ++k) {
          const std::array<double, 3> c = blobCentre(k, t);
          double d2 = 0.0;
          for (int a = 0; a < 3; ++a)
            d2 += (centre[size_t(a)] - c[size_t(a)]) * (centre[size_t(a)] - c[size_t(a)]);
          near = d2 < reach[level] * reach[level];
        }
        if (near) children.push_back({level + 1, {lower[0] * 2, lower[1] * 2, lower[2] * 2}});
      }
    }
    blocks.insert(blocks.end(), children.begin(), children.end());
  }
  return blocks;
}

// The step as overlapping AMR: every block's box on every process, the cells of this process's.
vtkSmartPointer<vtkOverlappingAMR> toAMR(const std::vector<Block>& blocks, double t, int rank, int size) {
  std::vector<int> perLevel(kLevels, 0);
  for (const Block& b : blocks)
    ++perLevel[size_t(b.level)];
  auto amr = vtkSmartPointer<vtkOverlappingAMR>::New();
  amr->Initialize(kLevels, perLevel.data());
  const double origin[3] = {0.0, 0.0, 0.0};
  amr->SetOrigin(origin);
  amr->SetGridDescription(VTK_XYZ_GRID);
  for (int level = 0; level < kLevels; ++level) {
    const double h[3] = {spacing(level), spacing(level), spacing(level)};
    amr->SetSpacing(unsigned(level), h);
  }
  std::vector<int> next(kLevels, 0);
  for (size_t i = 0; i < blocks.size(); ++i) {
    const Block& b = blocks[i];
    const unsigned id = unsigned(next[size_t(b.level)]++);
    const int lo[3] = {b.lower[0], b.lower[1], b.lower[2]};
    const int hi[3] = {lo[0] + kBlock - 1, lo[1] + kBlock - 1, lo[2] + kBlock - 1};
    amr->SetAMRBox(unsigned(b.level), id, vtkAMRBox(lo, hi));
    if (int(i % size_t(size)) != rank) continue;
    const double h = spacing(b.level);
    vtkNew<vtkUniformGrid> grid;
    grid->SetOrigin(lo[0] * h, lo[1] * h, lo[2] * h);
    grid->SetSpacing(h, h, h);
    grid->SetDimensions(kBlock + 1, kBlock + 1, kBlock + 1);
    vtkNew<vtkDoubleArray> values;
    values->SetName("density");
    values->SetNumberOfTuples(kBlock * kBlock * kBlock);
    vtkIdType c = 0;
    for (int z = 0; z < kBlock; ++z)
      for (int y = 0; y < kBlock; ++y)
        for (int x = 0; x < kBlock; ++x)
          values->SetValue(c++, field({(lo[0] + x + 0.5) * h, (lo[1] + y + 0.5) * h, (lo[2] + z + 0.5) * h}, t));
    grid->GetCellData()->AddArray(values);
    amr->SetDataSet(unsigned(b.level), id, grid);
  }
  return amr;
}

void run(const std::string& script, int steps, int every, int rank, int size);

int usage(const char* message) {
  std::fprintf(stderr,
               "exabricks_insitu_blobs: error: %s\n"
               "usage: exabricks_insitu_blobs SCRIPT.py [--steps N] [--regrid K] [--out DIR]\n",
               message);
  return 2;
}

} // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::string script, out = ".";
  int steps = 10, every = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--steps" || a == "--regrid" || a == "--out") && i + 1 < argc) {
      const char* v = argv[++i];
      if (a == "--out") {
        out = v;
        continue;
      }
      int& n = a == "--steps" ? steps : every;
      n = std::atoi(v);
      if (n < 1) {
        if (rank == 0) usage((a + " must be a whole number above 0, not '" + v + "'").c_str());
        MPI_Finalize();
        return 2;
      }
    } else if (script.empty() && a.rfind("--", 0) != 0) {
      script = a;
    } else {
      if (rank == 0) usage(("unknown argument '" + a + "'").c_str());
      MPI_Finalize();
      return 2;
    }
  }
  if (script.empty()) {
    if (rank == 0) usage("no Catalyst script given");
    MPI_Finalize();
    return 2;
  }
  // Where the script writes its images and data.
  setenv("EXABRICKS_INSITU_OUT", out.c_str(), 1);

  run(script, steps, every, rank, size);
  MPI_Finalize();
  return 0;
}

namespace {

void run(const std::string& script, int steps, int every, int rank, int size) {
  // Catalyst's objects end before MPI does.
  vtkNew<vtkCPProcessor> catalyst;
  catalyst->Initialize();
  vtkNew<vtkCPPythonScriptV2Pipeline> pipeline;
  if (!pipeline->Initialize(script.c_str())) {
    if (rank == 0)
      std::fprintf(stderr, "exabricks_insitu_blobs: Catalyst cannot load '%s'; simulating without it\n",
                   script.c_str());
  } else {
    catalyst->AddPipeline(pipeline);
  }

  std::vector<Block> blocks;
  double simulate = 0.0, analyse = 0.0;
  for (int step = 0; step < steps; ++step) {
    const double t = 0.25 * step;
    const auto t0 = std::chrono::steady_clock::now();
    if (step % every == 0) blocks = regrid(t);
    vtkSmartPointer<vtkOverlappingAMR> amr = toAMR(blocks, t, rank, size);
    const auto t1 = std::chrono::steady_clock::now();
    vtkNew<vtkCPDataDescription> description;
    description->AddInput("input");
    description->SetTimeData(t, step);
    int ok = 1;
    if (catalyst->RequestDataDescription(description)) {
      description->GetInputDescriptionByName("input")->SetGrid(amr);
      ok = catalyst->CoProcess(description);
    }
    const auto t2 = std::chrono::steady_clock::now();
    simulate += std::chrono::duration<double>(t1 - t0).count();
    analyse += std::chrono::duration<double>(t2 - t1).count();
    if (rank == 0) {
      std::printf("step %d: t %.2f, %zu blocks (%d levels), simulation %.3f s, Catalyst %.3f s%s\n", step, t,
                  blocks.size(), kLevels, std::chrono::duration<double>(t1 - t0).count(),
                  std::chrono::duration<double>(t2 - t1).count(), ok ? "" : " (the script failed; going on)");
      std::fflush(stdout);
    }
  }
  if (rank == 0) std::printf("%d steps: simulation %.3f s, Catalyst %.3f s\n", steps, simulate, analyse);
  catalyst->Finalize();
}

} // namespace
