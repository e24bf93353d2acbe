// Camera paths for movies: keyframes (camera, and optionally the first layer's value range and
// opacity scale and the iso-values) at increasing times, interpolated by a C1 cubic spline that
// passes exactly through every keyframe; optionally at constant speed along the path.
#pragma once

#include "exabricks/render/camera.h"

#include <optional>
#include <vector>

namespace exa {

struct Scene;

struct CameraKeyframe {
  double time = 0;
  Camera camera;
  std::optional<range1f> range;      ///< the first layer's value range
  std::optional<float> opacityScale; ///< the first layer's opacity scale (> 0)
  std::optional<std::vector<float>> isoValues;
};

struct CameraPath {
  std::vector<CameraKeyframe> keyframes; ///< strictly increasing times
  /// Frames spaced evenly along the camera's path instead of evenly in time.
  bool constantSpeed = false;

  bool empty() const { return keyframes.empty(); }
  /// Throws exa::Error naming the first problem: times not increasing, a degenerate camera, a
  /// setting given by some keyframes and not others, iso-value counts that differ.
  void validate() const;

  /// The camera at path time t (clamped to the keyframes' times). Position, look-at and up
  /// follow cubic Hermite segments with Catmull-Rom tangents for uneven times (one-sided at the
  /// ends), so position and direction are continuous with continuous first derivatives and equal
  /// each keyframe at its time; field of view and ortho height are interpolated linearly.
  Camera cameraAt(double t) const;
  /// The keyframed settings at time t applied to a scene (linear between keyframes).
  void applySettings(double t, Scene& scene) const;
  /// The path time of frame i of n (n >= 1): evenly spaced in time from the first to the last
  /// keyframe, or in arc length of the camera position with constantSpeed.
  double frameTime(int i, int n) const;
};

/// N cameras around the box's centre at the given elevation (degrees), framing the box as
/// Camera::frame does; frame i is at azimuth start + 360 i / N, so frame N would be frame 0 again
/// (the loop closes).
Camera orbitCamera(const box3d& worldBox, double startAzimuthDeg, double elevationDeg, double fovyDeg,
                   bool orthographic, int frame, int frames);
/// A fly-in: from three times the framing distance, 60 degrees of azimuth away, to the framing
/// view at the given azimuth and elevation (three keyframes at times 0, 0.5 and 1).
CameraPath flyInPath(const box3d& worldBox, double azimuthDeg, double elevationDeg, double fovyDeg, bool orthographic);

} // namespace exa
