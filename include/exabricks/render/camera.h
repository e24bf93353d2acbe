// Pinhole (perspective) and orthographic cameras in world space.
#pragma once

#include "exabricks/core/math.h"

namespace exa {

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
  void ray(double u, double v, double aspect, vec3d& org, vec3d& dir) const;
  /// The image point (u, v) of a world point, the inverse of ray(); false for points behind a
  /// perspective camera.
  bool project(const vec3d& point, double aspect, double& u, double& v) const;
};

} // namespace exa
