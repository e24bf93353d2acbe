#include "processes.h"

#include "exabricks/core/error.h"
#include "exabricks/render/composite.h"
#include "exabricks/workflows/frame_plan.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>

#ifdef EXABRICKS_HAVE_MPI
#include <mpi.h>
#endif

namespace exa::mpi {

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

void agreeOrFail(const std::string& error, const std::string& what) {
  if (!everyone(error.empty()))
    fail(error.empty() ? strCat("another process could not ", what, " (its message names the problem)") : error);
}

namespace {

/// Sums the statistics over the processes onto the root (seconds: the slowest process's).
void reduceStats(RenderStats& st) {
#ifdef EXABRICKS_HAVE_MPI
  if (state().size <= 1) return;
  const bool root = state().root();
  uint64_t counts[7] = {st.rays, st.samples, st.regionsVisited, st.surfaceHits, st.isoSamples, st.aoRays, st.tiles};
  MPI_Reduce(root ? MPI_IN_PLACE : counts, counts, 7, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
  MPI_Reduce(root ? MPI_IN_PLACE : &st.seconds, &st.seconds, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
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
  (void)st;
#endif
}

} // namespace

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
  reduce(s.squares, 4 * s.pixels, MPI_FLOAT, MPI_SUM);
  reduce(s.steps, s.pixels, MPI_FLOAT, MPI_SUM);
  reduce(s.tilePasses, s.tiles, MPI_UINT32_T, MPI_SUM);
  reduceStats(*s.stats);
#else
  (void)buffer;
#endif
}

TileNoiseEstimate wholeImage(TileNoiseEstimate estimate) {
#ifdef EXABRICKS_HAVE_MPI
  if (state().size <= 1) return estimate;
  TileNoiseEstimate whole;
  whole.agree = [](bool more) {
    int mine = more ? 1 : 0, any = 0;
    MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return any != 0;
  };
  whole.measure = [measure = estimate.measure](const FrameBuffer& share, std::vector<float>& tileNoise) {
    FrameBuffer all = share;
    const FrameBuffer::Sums s = all.sums();
    auto sum = [](void* data, size_t count, MPI_Datatype type) {
      const size_t chunk = size_t(1) << 28, bytes = type == MPI_FLOAT ? sizeof(float) : 4;
      for (size_t at = 0; at < count; at += chunk)
        MPI_Allreduce(MPI_IN_PLACE, static_cast<char*>(data) + at * bytes, int(std::min(chunk, count - at)), type,
                      MPI_SUM, MPI_COMM_WORLD);
    };
    sum(s.colors, 4 * s.pixels, MPI_FLOAT);
    sum(s.squares, 4 * s.pixels, MPI_FLOAT);
    sum(s.tilePasses, s.tiles, MPI_UINT32_T);
    measure(all, tileNoise);
  };
  return whole;
#else
  return estimate;
#endif
}

bool renderFrame(const Renderer& renderer, const Frame& frame, FrameBuffer& buffer, PassControl control,
                 const TileNoiseEstimate* estimate) {
  if (state().size <= 1) return renderer.renderSampled(frame, buffer, control, estimate);
  // Image-parallel: process r renders tiles r, r + N, r + 2N, ... of every pass (a noise target
  // is met tile by tile, so each process's tiles take the passes they would alone); the root adds
  // the shares (random numbers depend on pixel, pass and seed only, so the image is the serial one).
  control.tileBegin = state().rank;
  control.tileStride = state().size;
  const bool complete = renderer.renderSampled(frame, buffer, control, estimate);
  const auto start = std::chrono::steady_clock::now();
  combineOnRoot(buffer);
  lastCombineSeconds() = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return complete;
}

bool renderFrameComposited(const Renderer* renderer, const Frame& frame, FrameBuffer& buffer,
                           const std::vector<int>& order, PassControl control) {
  const int n = state().size;
  if (int(order.size()) != n) fail("compositing order names ", order.size(), " parts for ", n, " processes");
  const auto start = std::chrono::steady_clock::now();
  const size_t pixels = size_t(frame.width) * size_t(frame.height);
  if (pixels * kCompositeChannels > size_t(INT32_MAX))
    fail("data-parallel images hold at most ", size_t(INT32_MAX) / kCompositeChannels, " pixels");
  FrameBuffer pass(frame.width, frame.height);
  // This process's slice of the image, and everyone's.
  auto sliceBegin = [&](int j) { return pixels * size_t(j) / size_t(n); };
  const size_t mine = sliceBegin(state().rank + 1) - sliceBegin(state().rank);
  std::vector<float> local(pixels * kCompositeChannels), received(size_t(n) * mine * kCompositeChannels),
      composited(mine * kCompositeChannels), whole(state().root() ? pixels * kCompositeChannels : 0);
  RenderStats stats;
  bool complete = true, stepsView = false;
  double compositeSeconds = 0, waitSeconds = 0;
  Frame f = frame;
  for (int k = 0; k < frame.samplesPerPixel; ++k) {
    f.frameIndex = k;
    pass.clear();
    if (renderer && complete) complete = renderer->renderPass(f, pass, control);
    const FrameBuffer::Sums s = pass.sums();
    stepsView = *s.stepsView;
    stats += *s.stats;
    packForCompositing(s, pixels, local.data());
    const float* result = local.data();
#ifdef EXABRICKS_HAVE_MPI
    if (n > 1) {
      // Waiting for the slowest process is timed apart from the exchange.
      const auto w0 = std::chrono::steady_clock::now();
      MPI_Barrier(MPI_COMM_WORLD);
      waitSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    }
#endif
    const auto t0 = std::chrono::steady_clock::now();
#ifdef EXABRICKS_HAVE_MPI
    if (n > 1) {
      const size_t procs = size_t(n);
      std::vector<int> sendCounts(procs), sendDispl(procs), recvCounts(procs), recvDispl(procs);
      for (int j = 0; j < n; ++j) {
        sendCounts[size_t(j)] = int((sliceBegin(j + 1) - sliceBegin(j)) * kCompositeChannels);
        sendDispl[size_t(j)] = int(sliceBegin(j) * kCompositeChannels);
        recvCounts[size_t(j)] = int(mine * kCompositeChannels);
        recvDispl[size_t(j)] = int(size_t(j) * mine * kCompositeChannels);
      }
      MPI_Alltoallv(local.data(), sendCounts.data(), sendDispl.data(), MPI_FLOAT, received.data(), recvCounts.data(),
                    recvDispl.data(), MPI_FLOAT, MPI_COMM_WORLD);
      std::vector<const float*> parts;
      for (int r : order)
        parts.push_back(received.data() + size_t(r) * mine * kCompositeChannels);
      compositeFrontToBack(parts.data(), parts.size(), mine, composited.data());
      MPI_Gatherv(composited.data(), int(mine * kCompositeChannels), MPI_FLOAT, whole.data(), sendCounts.data(),
                  sendDispl.data(), MPI_FLOAT, 0, MPI_COMM_WORLD);
      result = whole.data();
    }
#endif
    compositeSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (state().root()) addComposited(result, pixels, buffer);
  }
  reduceStats(stats);
  complete = everyone(complete);
  if (state().root()) {
    const FrameBuffer::Sums out = buffer.sums();
    *out.stepsView = stepsView;
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    *out.stats += stats;
  }
  lastCombineSeconds() = compositeSeconds;
  lastWaitSeconds() = waitSeconds;
  return complete;
}

void allReduce(std::vector<double>& values, Reduce op) {
#ifdef EXABRICKS_HAVE_MPI
  if (state().size <= 1 || values.empty()) return;
  MPI_Op mop = op == Reduce::Sum ? MPI_SUM : op == Reduce::Min ? MPI_MIN : MPI_MAX;
  MPI_Allreduce(MPI_IN_PLACE, values.data(), int(values.size()), MPI_DOUBLE, mop, MPI_COMM_WORLD);
#else
  (void)values;
  (void)op;
#endif
}

void broadcast(std::vector<int64_t>& values) {
#ifdef EXABRICKS_HAVE_MPI
  if (state().size <= 1) return;
  int64_t count = int64_t(values.size());
  MPI_Bcast(&count, 1, MPI_INT64_T, 0, MPI_COMM_WORLD);
  values.resize(size_t(count));
  MPI_Bcast(values.data(), int(count), MPI_INT64_T, 0, MPI_COMM_WORLD);
#else
  (void)values;
#endif
}

std::vector<double> allGather(double value) {
  std::vector<double> out(size_t(state().size), value);
#ifdef EXABRICKS_HAVE_MPI
  if (state().size > 1) MPI_Allgather(&value, 1, MPI_DOUBLE, out.data(), 1, MPI_DOUBLE, MPI_COMM_WORLD);
#endif
  return out;
}

double& lastWaitSeconds() {
  static double seconds = 0;
  return seconds;
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

std::vector<int> shareOf(const std::vector<int>& frames) { return frameShare(frames, state().rank, state().size); }

} // namespace exa::mpi
