// The frames of a movie: which time step and which camera each frame shows, and the share of the
// frames one of several processes renders. A plan knows nothing of files or processes; the front
// ends choose the frames and where they go.
#pragma once

#include "exabricks/render/camera_path.h"
#include "exabricks/render/scene.h"

#include <optional>
#include <string>
#include <vector>

namespace exa {

/// A camera circling a box (orbitCamera), one turn over the movie's frames.
struct OrbitView {
  box3d target;
  double azimuth = 30.0, elevation = 25.0, fov = 40.0;
  bool orthographic = false;
};

struct FramePlan {
  int steps = 1;         ///< time steps of the series
  int frames = 1;        ///< frames of the movie
  int framesPerStep = 1; ///< frames each step holds (when the steps are not spread)
  /// The steps spread evenly over the frames (a camera path or orbit with a series: the camera
  /// moves while the steps play); otherwise step k holds frames k * framesPerStep onwards.
  bool spreadSteps = false;
  CameraPath path;                ///< the camera and keyframed settings along the frames (or empty)
  std::optional<OrbitView> orbit; ///< an orbit instead of a path

  /// One frame per step (times framesPerStep).
  static FramePlan perStep(int steps, int framesPerStep = 1);
  /// `frames` frames with the steps spread over them (frames >= steps; throws exa::Error otherwise).
  static FramePlan spread(int steps, int frames);

  /// The step frame `frame` shows.
  int stepOf(int frame) const;
  /// The frames that show `step`, in order.
  std::vector<int> framesOf(int step) const;
  /// Frame `frame`'s scene and camera: the orbit's camera, or the path's camera and keyframed
  /// settings, over the given scene and frame (which stay as given without either).
  void view(int frame, Scene& scene, Frame& out) const;
};

/// Process `index` of `count`'s share of `frames`: every count-th frame from the index-th
/// (interleaved, so that each process meets the steps in order and the loads overlap).
std::vector<int> frameShare(const std::vector<int>& frames, int index, int count);

/// The file name of frame `frame` in `folder`: FOLDER/frame_00042.png.
std::string framePath(const std::string& folder, int frame);

} // namespace exa
