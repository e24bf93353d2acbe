// Internal helpers shared by the library's Embree users (region traversal, triangle meshes):
// one way to create a device that reports its errors, and one way to fill a ray.
#pragma once

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/core/math.h"

#include <embree3/rtcore.h>

namespace exa::embree {

/// A new Embree device whose errors are logged as warnings; throws when none can be created.
inline RTCDevice newDevice() {
  RTCDevice device = rtcNewDevice("");
  if (!device) fail("cannot create an Embree device (error ", int(rtcGetDeviceError(nullptr)), ")");
  rtcSetDeviceErrorFunction(
      device,
      [](void*, RTCError code, const char* message) {
        logWarning(strCat("embree error ", int(code), ": ", message ? message : ""));
      },
      nullptr);
  return device;
}

/// An Embree ray from org along dir over [tnear, tfar].
inline RTCRay makeRay(const vec3f& org, const vec3f& dir, float tnear, float tfar) {
  RTCRay ray;
  ray.org_x = org.x, ray.org_y = org.y, ray.org_z = org.z;
  ray.dir_x = dir.x, ray.dir_y = dir.y, ray.dir_z = dir.z;
  ray.tnear = tnear;
  ray.tfar = tfar;
  ray.time = 0.f;
  ray.mask = ~0u;
  ray.id = 0;
  ray.flags = 0;
  return ray;
}

/// The same ray with an empty hit, for rtcIntersect1.
inline RTCRayHit makeRayHit(const vec3f& org, const vec3f& dir, float tnear, float tfar) {
  RTCRayHit rh;
  rh.ray = makeRay(org, dir, tnear, tfar);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

} // namespace exa::embree
