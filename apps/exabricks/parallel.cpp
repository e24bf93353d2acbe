#include "parallel.h"

#include "exabricks/core/error.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>

#ifdef EXABRICKS_HAVE_MPI
#include <mpi.h>
#endif

namespace exa::cli::parallel {

namespace {

Processes& state() {
  static Processes p;
  return p;
}

#ifdef EXABRICKS_HAVE_MPI
bool started = false;

/// Whether an MPI launcher started this process (Open MPI, MPICH/Hydra, PMIx, Slurm's PMI).
bool launchedByMpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "PMI_RANK"})
    if (std::getenv(name)) return true;
  return false;
}
#endif

} // namespace

Session::Session(int& argc, char**& argv) {
#ifdef EXABRICKS_HAVE_MPI
  if (!launchedByMpi()) return;
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  started = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &state().rank);
  MPI_Comm_size(MPI_COMM_WORLD, &state().size);
#else
  (void)argc;
  (void)argv;
#endif
}

Session::~Session() {
#ifdef EXABRICKS_HAVE_MPI
  if (started) MPI_Finalize();
#endif
}

const Processes& processes() { return state(); }

bool everyone(bool ok) {
#ifdef EXABRICKS_HAVE_MPI
  if (state().size > 1) {
    int mine = ok ? 1 : 0, all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    return all == 1;
  }
#endif
  return ok;
}

void combineOnRoot(FrameBuffer& buffer) {
#ifdef EXABRICKS_HAVE_MPI
  if (state().size <= 1) return;
  const FrameBuffer::Sums s = buffer.sums();
  const bool root = state().root();
  auto reduce = [&](void* data, size_t count, MPI_Datatype type, MPI_Op op) {
    // In pieces, so that counts stay within int.
    const size_t chunk = size_t(1) << 28;
    const size_t bytes = type == MPI_FLOAT ? sizeof(float) : type == MPI_UINT32_T ? 4 : 8;
    for (size_t at = 0; at < count; at += chunk) {
      const int n = int(std::min(chunk, count - at));
      char* p = static_cast<char*>(data) + at * bytes;
      MPI_Reduce(root ? MPI_IN_PLACE : p, p, n, type, op, 0, MPI_COMM_WORLD);
    }
  };
  reduce(s.colors, 4 * s.pixels, MPI_FLOAT, MPI_SUM);
  reduce(s.steps, s.pixels, MPI_FLOAT, MPI_SUM);
  reduce(s.tilePasses, s.tiles, MPI_UINT32_T, MPI_SUM);
  RenderStats& st = *s.stats;
  uint64_t counts[7] = {st.rays, st.samples, st.regionsVisited, st.surfaceHits, st.isoSamples, st.aoRays, st.tiles};
  reduce(counts, 7, MPI_UINT64_T, MPI_SUM);
  reduce(&st.seconds, 1, MPI_DOUBLE, MPI_MAX);
  if (root) {
    st.rays = counts[0];
    st.samples = counts[1];
    st.regionsVisited = counts[2];
    st.surfaceHits = counts[3];
    st.isoSamples = counts[4];
    st.aoRays = counts[5];
    st.tiles = counts[6];
  }
#else
  (void)buffer;
#endif
}

bool renderFrame(const Renderer& renderer, const Frame& frame, FrameBuffer& buffer, PassControl control) {
  if (state().size <= 1) return renderer.renderPasses(frame, buffer, frame.samplesPerPixel, control);
  // Image-parallel: process r renders tiles r, r + N, r + 2N, ... of every pass; the root adds
  // the shares (random numbers depend on pixel, pass and seed only, so the image is the serial one).
  control.tileBegin = state().rank;
  control.tileStride = state().size;
  Frame pass = frame;
  bool complete = true;
  for (int k = 0; k < frame.samplesPerPixel && complete; ++k) {
    pass.frameIndex = k;
    complete = renderer.renderPass(pass, buffer, control);
  }
  const auto start = std::chrono::steady_clock::now();
  combineOnRoot(buffer);
  lastCombineSeconds() = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return complete;
}

double& lastCombineSeconds() {
  static double seconds = 0;
  return seconds;
}

void barrier() {
#ifdef EXABRICKS_HAVE_MPI
  if (state().size > 1) MPI_Barrier(MPI_COMM_WORLD);
#endif
}

void requireOneProcess(const char* command) {
  if (state().size > 1)
    fail(command, " runs in one process (it has no parallel mode); run it without mpirun or with -np 1");
}

} // namespace exa::cli::parallel
