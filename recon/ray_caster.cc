#include "recon/ray_caster.h"

#include <cmath>
#include <limits>
#include <string>

#include <embree3/rtcore.h>

#include "core/error.h"

namespace doasido::recon {

struct RayCaster::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
};

RayCaster::RayCaster(const Vertices& vertices, const Faces& faces) : impl_(std::make_unique<Impl>()) {
  const auto nv = static_cast<int>(vertices.rows());
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      if (faces(f, k) < 0 || faces(f, k) >= nv) {
        throw Error("bad_mesh", "face " + std::to_string(f) + " indexes a missing vertex",
                    {.field = "faces"});
      }
    }
  }
  impl_->device = rtcNewDevice("threads=1");
  if (!impl_->device) throw Error("embree", "rtcNewDevice failed");
  impl_->scene = rtcNewScene(impl_->device);
  RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                        RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                        std::max<size_t>(1, nv)));
  for (int i = 0; i < nv; ++i) {
    for (int k = 0; k < 3; ++k) v[3 * i + k] = static_cast<float>(vertices(i, k));
  }
  auto* idx = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), static_cast<size_t>(faces.rows())));
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    for (int k = 0; k < 3; ++k) idx[3 * f + k] = static_cast<unsigned>(faces(f, k));
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometry(impl_->scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(impl_->scene);
}

RayCaster::~RayCaster() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

std::optional<double> RayCaster::FirstHit(const Vec3& origin, const Vec3& direction,
                                          double t_min) const {
  const Vec3 d = direction.normalized();
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh{};
  rh.ray.org_x = static_cast<float>(origin.x());
  rh.ray.org_y = static_cast<float>(origin.y());
  rh.ray.org_z = static_cast<float>(origin.z());
  rh.ray.dir_x = static_cast<float>(d.x());
  rh.ray.dir_y = static_cast<float>(d.y());
  rh.ray.dir_z = static_cast<float>(d.z());
  rh.ray.tnear = static_cast<float>(t_min);
  rh.ray.tfar = std::numeric_limits<float>::infinity();
  rh.ray.mask = 0xFFFFFFFFu;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  return static_cast<double>(rh.ray.tfar);
}

int RayCaster::Crossings(const Vec3& origin, const Vec3& direction, double gap) const {
  int crossings = 0;
  double t = 0;
  while (const std::optional<double> hit = FirstHit(origin, direction, t)) {
    ++crossings;
    // Strictly past this hit even where float rounding swallows `gap`.
    t = std::nextafter(static_cast<float>(*hit + gap), std::numeric_limits<float>::infinity());
  }
  return crossings;
}

}  // namespace doasido::recon
