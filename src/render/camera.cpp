#include "exabricks/render/camera.h"

#include "exabricks/core/error.h"

namespace exa {

Camera Camera::frame(const box3d& box, double azimuthDeg, double elevationDeg, double fovyDeg, bool orthographic) {
  const double deg = M_PI / 180.0;
  const vec3d centre = (box.lower + box.upper) * 0.5;
  const double radius = 0.5 * length(box.upper - box.lower);
  const vec3d dir(std::cos(elevationDeg * deg) * std::cos(azimuthDeg * deg),
                  std::cos(elevationDeg * deg) * std::sin(azimuthDeg * deg), std::sin(elevationDeg * deg));
  Camera c;
  c.fovy = fovyDeg;
  c.orthographic = orthographic;
  c.lookAt = centre;
  // The bounding sphere fits the vertical field of view (the narrower one for wide images).
  const double distance = radius / std::sin(0.5 * fovyDeg * deg);
  c.position = centre + dir * (orthographic ? 3.0 * radius : distance);
  c.orthoHeight = 2.0 * radius;
  c.up = std::abs(dir.z) > 0.999 ? vec3d(0.0, 1.0, 0.0) : vec3d(0.0, 0.0, 1.0);
  return c;
}

bool Camera::project(const vec3d& point, double aspect, double& u, double& v) const {
  const vec3d forward = normalize(lookAt - position);
  const vec3d right = normalize(cross(forward, up));
  const vec3d trueUp = cross(right, forward);
  const vec3d d = point - position;
  double x, y;
  if (orthographic) {
    const double h = 0.5 * orthoHeight;
    x = dot(d, right) / (h * aspect);
    y = dot(d, trueUp) / h;
  } else {
    const double z = dot(d, forward);
    if (!(z > 0.0)) return false;
    const double t = std::tan(0.5 * fovy * M_PI / 180.0);
    x = dot(d, right) / (z * t * aspect);
    y = dot(d, trueUp) / (z * t);
  }
  u = 0.5 * (x + 1.0);
  v = 0.5 * (1.0 - y);
  return true;
}

} // namespace exa
