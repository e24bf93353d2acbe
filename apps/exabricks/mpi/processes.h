// The MPI drivers of the command line (apps/exabricks/mpi, namespace exa::mpi): processes of an
// MPI run (`mpirun -np N exabricks render|movie ...`), or one process. Built with
// MPI only when EXABRICKS_MPI finds it; MPI starts only when the program was launched by an MPI
// launcher, so a plain run never initialises it.
#pragma once

#include "exabricks/render/renderer.h"

#include <string>
#include <vector>

namespace exa::mpi {

struct Processes {
  int rank = 0, size = 1;
  bool root() const { return rank == 0; }
};

/// Starts MPI when launched by mpirun (and built with MPI); ends it when destroyed.
class Session {
public:
  Session(int& argc, char**& argv);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
};

const Processes& processes();

/// True when every process passes true. Every process must call it (a collective), so that a
/// process that failed makes all of them stop instead of waiting for it.
bool everyone(bool ok);

/// A collective like everyone(): returns when every process's `error` is empty; else fails with
/// this process's error, or on the others with "another process could not WHAT".
void agreeOrFail(const std::string& error, const std::string& what);

/// Adds every process's share of the tiles into the root's buffer (the root then holds the
/// whole image's sums; statistics summed, seconds the slowest process's).
void combineOnRoot(FrameBuffer& buffer);

/// A frame's samplesPerPixel passes into a cleared buffer: in one process all of them; under MPI
/// each process renders an interleaved share of the tiles and the root receives the whole image.
/// `estimate` (may be null) measures the tiles' noise against a noise target over the whole image
/// (wholeImage()).
bool renderFrame(const Renderer& renderer, const Frame& frame, FrameBuffer& buffer, PassControl control = {},
                 const TileNoiseEstimate* estimate = nullptr);

/// An estimate made over the whole image: under MPI every process's share of the tiles is added
/// into a copy of the buffer on every process first (a collective, in every round), so that an
/// estimate that reads neighbouring tiles (the denoised picture's) sees what one process sees.
TileNoiseEstimate wholeImage(TileNoiseEstimate estimate);

/// Data-parallel rendering: every process holds one part of the data and its renderer is
/// restricted to the part's box (null: the process holds nothing). Each pass is rendered by every
/// process and the parts' images are composited front to back in `order` (parts front first, one
/// per process) by direct send: process j receives every process's pixels of the j-th slice of the
/// image, composites them and sends the slice to the root, whose buffer adds the composited
/// passes (statistics summed over the processes, seconds the frame's wall time on the root).
bool renderFrameComposited(const Renderer* renderer, const Frame& frame, FrameBuffer& buffer,
                           const std::vector<int>& order, PassControl control = {});

enum class Reduce { Sum, Min, Max };
/// Combines every process's values element by element; every process receives the result.
void allReduce(std::vector<double>& values, Reduce op);
/// The root's values on every process (sizes may differ before the call).
void broadcast(std::vector<int64_t>& values);
/// One value per process, on every process (rank order).
std::vector<double> allGather(double value);

/// Seconds the last renderFrameComposited waited for the slowest process before its exchanges.
double& lastWaitSeconds();

/// Seconds the last renderFrame spent adding the shares on the root (0 in one process).
double& lastCombineSeconds();

void barrier();

/// Refuses to run a command that has no parallel mode under more than one process.
void requireOneProcess(const char* command);

/// Runs `work` on every process, a collective like agreeOrFail: when it fails on any process,
/// every process stops (with its own error, or "another process could not WHAT").
template <typename Work> void onEveryProcess(const std::string& what, Work&& work) {
  std::string error;
  try {
    work();
  } catch (const std::exception& e) {
    error = e.what();
  }
  agreeOrFail(error, what);
}

/// This process's share of a list of frames: every size-th from the rank-th (all in one process).
std::vector<int> shareOf(const std::vector<int>& frames);

} // namespace exa::mpi
