#include "exabricks/render/camera_path.h"

#include "exabricks/core/error.h"
#include "exabricks/render/scene.h"

#include <algorithm>
#include <cmath>

namespace exa {

namespace {

/// Index of the segment [k, k+1] holding t (keyframes has at least two entries).
size_t segmentOf(const std::vector<CameraKeyframe>& keys, double t) {
  const auto it =
      std::upper_bound(keys.begin(), keys.end(), t, [](double v, const CameraKeyframe& k) { return v < k.time; });
  const size_t k = size_t(std::max<std::ptrdiff_t>(1, it - keys.begin()));
  return std::min(k, keys.size() - 1) - 1;
}

/// Catmull-Rom tangent for uneven times at keyframe k of a quantity; one-sided at the ends.
template <typename Get> vec3d tangent(const std::vector<CameraKeyframe>& keys, size_t k, Get get) {
  const size_t a = k == 0 ? 0 : k - 1, b = std::min(k + 1, keys.size() - 1);
  return (get(keys[b]) - get(keys[a])) / (keys[b].time - keys[a].time);
}

/// Cubic Hermite interpolation of a quantity on segment k at time t.
template <typename Get> vec3d hermite(const std::vector<CameraKeyframe>& keys, size_t k, double t, Get get) {
  const double t0 = keys[k].time, t1 = keys[k + 1].time, h = t1 - t0;
  const double s = std::clamp((t - t0) / h, 0.0, 1.0);
  const double s2 = s * s, s3 = s2 * s;
  const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
  return get(keys[k]) * h00 + tangent(keys, k, get) * (h10 * h) + get(keys[k + 1]) * h01 +
         tangent(keys, k + 1, get) * (h11 * h);
}

double lerp(double a, double b, double s) { return a + (b - a) * s; }

} // namespace

void CameraPath::validate() const {
  for (size_t i = 0; i < keyframes.size(); ++i) {
    const CameraKeyframe& k = keyframes[i];
    const Camera& c = k.camera;
    if (!std::isfinite(k.time)) fail("camera path: keyframe ", i, ": the time must be a finite number");
    if (i > 0 && !(k.time > keyframes[i - 1].time))
      fail("camera path: keyframe ", i, ": times must increase (", keyframes[i - 1].time, " then ", k.time, ")");
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(c.position[a]) || !std::isfinite(c.lookAt[a]) || !std::isfinite(c.up[a]))
        fail("camera path: keyframe ", i, ": position, look-at and up must be finite");
    if (length(c.lookAt - c.position) == 0 || length(cross(c.lookAt - c.position, c.up)) == 0)
      fail("camera path: keyframe ", i, ": degenerate camera (position equals look-at, or up is parallel to the view)");
    if (!(c.fovy > 0 && c.fovy < 180)) fail("camera path: keyframe ", i, ": the field of view must be in (0, 180)");
    if (k.range && !(k.range->lower < k.range->upper))
      fail("camera path: keyframe ", i, ": the range needs LOW < HIGH");
    if (k.opacityScale && !(*k.opacityScale > 0.f && std::isfinite(*k.opacityScale)))
      fail("camera path: keyframe ", i, ": the opacity scale must be positive");
    const CameraKeyframe& first = keyframes.front();
    if (k.range.has_value() != first.range.has_value() ||
        k.opacityScale.has_value() != first.opacityScale.has_value() ||
        k.isoValues.has_value() != first.isoValues.has_value())
      fail("camera path: keyframe ", i, ": a setting keyframed by one keyframe must be given by all of them");
    if (k.isoValues && k.isoValues->size() != first.isoValues->size())
      fail("camera path: keyframe ", i, ": every keyframe needs the same number of iso-values");
  }
}

Camera CameraPath::cameraAt(double t) const {
  if (keyframes.empty()) fail("camera path: no keyframes");
  if (keyframes.size() == 1) return keyframes[0].camera;
  const size_t k = segmentOf(keyframes, t);
  const CameraKeyframe &a = keyframes[k], &b = keyframes[k + 1];
  Camera c = a.camera;
  c.position = hermite(keyframes, k, t, [](const CameraKeyframe& f) { return f.camera.position; });
  c.lookAt = hermite(keyframes, k, t, [](const CameraKeyframe& f) { return f.camera.lookAt; });
  c.up = hermite(keyframes, k, t, [](const CameraKeyframe& f) { return f.camera.up; });
  const double s = std::clamp((t - a.time) / (b.time - a.time), 0.0, 1.0);
  c.fovy = lerp(a.camera.fovy, b.camera.fovy, s);
  c.orthoHeight = lerp(a.camera.orthoHeight, b.camera.orthoHeight, s);
  if (length(c.up) > 0) c.up = normalize(c.up);
  return c;
}

void CameraPath::applySettings(double t, Scene& scene) const {
  if (keyframes.empty()) return;
  size_t k = 0;
  double s = 0;
  if (keyframes.size() > 1) {
    k = segmentOf(keyframes, t);
    s = std::clamp((t - keyframes[k].time) / (keyframes[k + 1].time - keyframes[k].time), 0.0, 1.0);
  }
  const CameraKeyframe& a = keyframes[k];
  const CameraKeyframe& b = keyframes[std::min(k + 1, keyframes.size() - 1)];
  if (a.range && !scene.layers.empty())
    scene.layers[0].tf.valueRange =
        range1f{float(lerp(a.range->lower, b.range->lower, s)), float(lerp(a.range->upper, b.range->upper, s))};
  if (a.opacityScale && !scene.layers.empty())
    scene.layers[0].tf.opacityScale = float(lerp(*a.opacityScale, *b.opacityScale, s));
  if (a.isoValues) {
    scene.iso.values.resize(a.isoValues->size());
    for (size_t i = 0; i < a.isoValues->size(); ++i)
      scene.iso.values[i] = float(lerp((*a.isoValues)[i], (*b.isoValues)[i], s));
  }
}

double CameraPath::frameTime(int i, int n) const {
  if (keyframes.empty()) return 0;
  const double t0 = keyframes.front().time, t1 = keyframes.back().time;
  if (n <= 1 || keyframes.size() == 1) return t0;
  const double u = double(i) / double(n - 1);
  if (!constantSpeed) return lerp(t0, t1, u);
  // Arc length of the position, tabulated finely per segment, then inverted.
  constexpr int kSteps = 256;
  std::vector<double> times{t0}, lengths{0.0};
  vec3d previous = cameraAt(t0).position;
  for (size_t k = 0; k + 1 < keyframes.size(); ++k)
    for (int j = 1; j <= kSteps; ++j) {
      const double t = lerp(keyframes[k].time, keyframes[k + 1].time, double(j) / kSteps);
      const vec3d p = cameraAt(t).position;
      times.push_back(t);
      lengths.push_back(lengths.back() + length(p - previous));
      previous = p;
    }
  if (!(lengths.back() > 0)) return lerp(t0, t1, u);
  const double target = u * lengths.back();
  const size_t j = size_t(std::lower_bound(lengths.begin(), lengths.end(), target) - lengths.begin());
  if (j == 0) return times.front();
  if (j >= lengths.size()) return times.back();
  const double span = lengths[j] - lengths[j - 1];
  return lerp(times[j - 1], times[j], span > 0 ? (target - lengths[j - 1]) / span : 0.0);
}

Camera orbitCamera(const box3d& worldBox, double startAzimuthDeg, double elevationDeg, double fovyDeg,
                   bool orthographic, int frame, int frames) {
  const double azimuth = startAzimuthDeg + 360.0 * double(frame) / double(std::max(frames, 1));
  return Camera::frame(worldBox, azimuth, elevationDeg, fovyDeg, orthographic);
}

CameraPath flyInPath(const box3d& worldBox, double azimuthDeg, double elevationDeg, double fovyDeg, bool orthographic) {
  CameraPath path;
  const Camera end = Camera::frame(worldBox, azimuthDeg, elevationDeg, fovyDeg, orthographic);
  const double distances[3] = {3.0, 1.8, 1.0};
  const double azimuths[3] = {azimuthDeg - 60.0, azimuthDeg - 25.0, azimuthDeg};
  for (int i = 0; i < 3; ++i) {
    CameraKeyframe k;
    k.time = 0.5 * i;
    k.camera = Camera::frame(worldBox, azimuths[i], elevationDeg, fovyDeg, orthographic);
    k.camera.position = k.camera.lookAt + (k.camera.position - k.camera.lookAt) * distances[i];
    k.camera.orthoHeight = end.orthoHeight * distances[i];
    path.keyframes.push_back(k);
  }
  return path;
}

} // namespace exa
