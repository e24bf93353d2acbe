#include "exabricks/workflows/frame_plan.h"

#include "exabricks/core/error.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>

namespace exa {

FramePlan FramePlan::perStep(int steps, int framesPerStep) {
  if (steps < 1) fail("a series needs at least one step");
  if (framesPerStep < 1) fail("frames per step must be at least 1, not ", framesPerStep);
  FramePlan p;
  p.steps = steps;
  p.framesPerStep = framesPerStep;
  p.frames = steps * framesPerStep;
  return p;
}

FramePlan FramePlan::spread(int steps, int frames) {
  if (steps < 1) fail("a series needs at least one step");
  if (frames < steps)
    fail(frames, " frames are fewer than the series has steps (", steps, "): every step needs a frame");
  FramePlan p;
  p.steps = steps;
  p.frames = frames;
  p.spreadSteps = true;
  return p;
}

int FramePlan::stepOf(int frame) const {
  if (steps <= 1) return 0;
  if (spreadSteps) return std::min(steps - 1, int(int64_t(frame) * steps / frames));
  return std::min(steps - 1, frame / framesPerStep);
}

std::vector<int> FramePlan::framesOf(int step) const {
  std::vector<int> out;
  for (int i = 0; i < frames; ++i)
    if (stepOf(i) == step) out.push_back(i);
  return out;
}

void FramePlan::view(int frame, Scene& scene, Frame& out) const {
  if (orbit) {
    out.camera =
        orbitCamera(orbit->target, orbit->azimuth, orbit->elevation, orbit->fov, orbit->orthographic, frame, frames);
  } else if (!path.empty()) {
    const double t = path.frameTime(frame, frames);
    out.camera = path.cameraAt(t);
    path.applySettings(t, scene);
  }
}

std::vector<int> frameShare(const std::vector<int>& frames, int index, int count) {
  if (count <= 1) return frames;
  std::vector<int> mine;
  for (size_t n = 0; n < frames.size(); ++n)
    if (int(n % size_t(count)) == index) mine.push_back(frames[n]);
  return mine;
}

std::string framePath(const std::string& folder, int frame) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05d.png", frame);
  return (std::filesystem::path(folder) / name).string();
}

} // namespace exa
