// Pinhole (perspective) and orthographic cameras in world space.
#pragma once

#include "exabricks/core/math.h"

namespace exa {

/// Radians per degree.
constexpr double kDegree = 0.017453292519943295;

struct Camera {
  vec3d position{0.0, 0.0, 1.0};
  vec3d lookAt{0.0};
  vec3d up{0.0, 1.0, 0.0};
  double fovy = 40.0; ///< vertical field of view in degrees (perspective)
  bool orthographic = false;
  double orthoHeight = 1.0; ///< world height of the view (orthographic)

  /// A camera that frames the box from the direction given by azimuth (degrees, around +z from
  /// +x) and elevation (degrees above the x-y plane), with the whole box in view.
  static Camera frame(const box3d& worldBox, double azimuthDeg, double elevationDeg, double fovyDeg, bool orthographic);

  /// World-space ray through the image point (u, v) in [0, 1]^2, v = 0 at the top.
  EXA_HOST_DEVICE void ray(double u, double v, double aspect, vec3d& org, vec3d& dir) const {
    const vec3d forward = normalize(lookAt - position);
    const vec3d right = normalize(cross(forward, up));
    const vec3d trueUp = cross(right, forward);
    const double x = (2.0 * u - 1.0), y = (1.0 - 2.0 * v);
    if (orthographic) {
      const double h = 0.5 * orthoHeight;
      org = position + right * (x * h * aspect) + trueUp * (y * h);
      dir = forward;
      return;
    }
    const double t = std::tan(0.5 * fovy * kDegree);
    org = position;
    dir = normalize(forward + right * (x * t * aspect) + trueUp * (y * t));
  }
  /// The image point (u, v) of a world point, the inverse of ray(); false for points behind a
  /// perspective camera.
  bool project(const vec3d& point, double aspect, double& u, double& v) const;
};

} // namespace exa
