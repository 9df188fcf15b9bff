// The one source file that talks to Embree 3.
#include <embree3/rtcore.h>

#include <fmt/format.h>
#include <sys/types.h>

#include <atomic>
#include <cstring>
#include <mutex>
#include <string>

#include "rll/accel/accel.h"
#include "rll/core/error.h"
#include "rll/core/memory_budget.h"

namespace rll {

namespace {
// What Embree's callbacks record, for the messages of its failures.
struct DeviceState {
  RTCDevice device = nullptr;
  size_t vertex_count = 0, triangle_count = 0;
  // Embree's own message for its first error, and the bytes it holds (its memory monitor).
  std::mutex mutex;
  std::string message;
  std::atomic<int64_t> bytes{0};
};
}  // namespace

struct Accel::Impl : DeviceState {
  RTCScene scene = nullptr;
  RTCGeometry geometry = nullptr;
  // Released here rather than in ~Accel, so that a constructor that fails half way (Embree out of
  // memory) leaks nothing: the Impl is destroyed with the throw, the Accel never was.
  ~Impl() {
    if (geometry) rtcReleaseGeometry(geometry);
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

namespace {
const char* error_name(RTCError e) {
  switch (e) {
    case RTC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
      return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
      return "cancelled";
    default:
      return "unknown error";
  }
}

// An Embree failure says what was being built, over how much geometry, and why.
void check(DeviceState& m, const char* what) {
  const RTCError e = rtcGetDeviceError(m.device);
  if (e == RTC_ERROR_NONE) return;
  std::string why = error_name(e);
  {
    std::lock_guard lock(m.mutex);
    if (!m.message.empty() && m.message != why) why += ": " + m.message;
  }
  if (e == RTC_ERROR_OUT_OF_MEMORY)
    why += fmt::format(" (it held {} and asked for more than {})",
                       format_bytes(double(m.bytes.load())), memory_budget_phrase());
  fail(
      "Embree failed during the {} of the acceleration structure over {} triangles and {} "
      "vertices: {}",
      what, m.triangle_count, m.vertex_count, why);
}

void on_error(void* user, RTCError, const char* message) {
  auto& m = *static_cast<DeviceState*>(user);
  std::lock_guard lock(m.mutex);
  if (m.message.empty() && message) m.message = message;
}

// Embree's allocations count against the memory budget: one beyond it fails as out of memory
// (with the figures) rather than growing towards the out-of-memory killer.
bool on_memory(void* user, ssize_t bytes, bool post) {
  auto& m = *static_cast<DeviceState*>(user);
  if (bytes > 0 && !post && m.bytes.load() + bytes > int64_t(memory_budget_bytes())) return false;
  m.bytes += bytes;
  return true;
}

void copy_vertices(RTCGeometry geom, const Mesh& mesh) {
  // Embree's vertex buffer is padded so that the last vertex can be read with 16-byte loads.
  auto* v = static_cast<float*>(rtcGetGeometryBufferData(geom, RTC_BUFFER_TYPE_VERTEX, 0));
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    v[3 * i + 0] = mesh.positions[i].x;
    v[3 * i + 1] = mesh.positions[i].y;
    v[3 * i + 2] = mesh.positions[i].z;
  }
}
}  // namespace

Accel::Accel(const Mesh& mesh) : m_impl(std::make_unique<Impl>()) {
  Impl& m = *m_impl;
  m.device = rtcNewDevice("verbose=0");
  if (!m.device) fail("cannot create an Embree device (error {})", int(rtcGetDeviceError(nullptr)));
  rtcSetDeviceErrorFunction(m.device, on_error, static_cast<DeviceState*>(&m));
  rtcSetDeviceMemoryMonitorFunction(m.device, on_memory, static_cast<DeviceState*>(&m));
  m.scene = rtcNewScene(m.device);
  rtcSetSceneBuildQuality(m.scene, RTC_BUILD_QUALITY_HIGH);
  // Robust traversal: no rays slip through shared edges of the closed rooms and the sky dome.
  rtcSetSceneFlags(m.scene, RTC_SCENE_FLAG_ROBUST);
  m.vertex_count = mesh.positions.size();
  m.triangle_count = mesh.triangles.size();
  if (!mesh.triangles.empty()) {
    m.geometry = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    // One extra vertex of padding for Embree's wide loads.
    rtcSetNewGeometryBuffer(m.geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                            mesh.positions.size() + 1);
    check(m, "vertex buffer allocation");
    copy_vertices(m.geometry, mesh);
    auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        m.geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), mesh.triangles.size()));
    check(m, "index buffer allocation");
    std::memcpy(idx, mesh.triangles.data(), mesh.triangles.size() * 3 * sizeof(uint32_t));
    rtcSetGeometryBuildQuality(m.geometry, RTC_BUILD_QUALITY_HIGH);
    rtcCommitGeometry(m.geometry);
    rtcAttachGeometry(m.scene, m.geometry);
  }
  rtcCommitScene(m.scene);
  check(m, "build");
}

Accel::~Accel() = default;

void Accel::update_vertices(const Mesh& mesh) {
  Impl& m = *m_impl;
  if (!m.geometry) return;
  if (mesh.positions.size() != m.vertex_count) fail("Accel::update_vertices: vertex count changed");
  copy_vertices(m.geometry, mesh);
  rtcUpdateGeometryBuffer(m.geometry, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcSetGeometryBuildQuality(m.geometry, RTC_BUILD_QUALITY_REFIT);
  rtcCommitGeometry(m.geometry);
  rtcCommitScene(m.scene);
  check(m, "refit");
}

bool Accel::intersect(const Ray& ray, Hit& hit) const {
  if (m_log) [[unlikely]] m_log->closest.push_back(ray);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  rh.ray.org_x = ray.o.x;
  rh.ray.org_y = ray.o.y;
  rh.ray.org_z = ray.o.z;
  rh.ray.dir_x = ray.d.x;
  rh.ray.dir_y = ray.d.y;
  rh.ray.dir_z = ray.d.z;
  rh.ray.tnear = ray.tmin;
  rh.ray.tfar = ray.tmax;
  rh.ray.time = 0;
  rh.ray.mask = ~0u;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(m_impl->scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  hit.t = rh.ray.tfar;
  hit.tri = rh.hit.primID;
  hit.u = rh.hit.u;
  hit.v = rh.hit.v;
  return true;
}

bool Accel::occluded(const Ray& ray) const {
  if (m_log) [[unlikely]] m_log->shadow.push_back(ray);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r;
  r.org_x = ray.o.x;
  r.org_y = ray.o.y;
  r.org_z = ray.o.z;
  r.dir_x = ray.d.x;
  r.dir_y = ray.d.y;
  r.dir_z = ray.d.z;
  r.tnear = ray.tmin;
  r.tfar = ray.tmax;
  r.time = 0;
  r.mask = ~0u;
  r.id = 0;
  r.flags = 0;
  rtcOccluded1(m_impl->scene, &ctx, &r);
  return r.tfar < 0;  // Embree sets tfar to -inf on a hit
}

}  // namespace rll
