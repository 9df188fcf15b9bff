// What a light sampler is told of a shading point and of a next-event sample, and what it answers:
// plain structs that host and device code (DESIGN 6) pass alike.
#pragma once

#include <cstdint>
#include <cstring>

#include "rll/core/math.h"

namespace rll {

inline constexpr uint32_t kNoCell = ~0u;

// What a light sampler knows of a shading point.
struct LightContext {
  Vec3 p;
  Vec3 n;                   // geometric normal on the side the path arrived from (zero: no surface)
  Vec3 ns;                  // shading normal, same side as n
  Vec3 wo;                  // direction towards where the path came from (zero: unknown)
  bool glossy = false;      // the surface's BSDF is not Lambertian: its response depends on wo
  uint8_t half = 0;         // rll.refine: CellCoord::half of the point in its cell
  float footprint = 0;      // ray footprint radius at this vertex, world units
  uint32_t cell = kNoCell;  // per-point sampler state (an RLL cell), set by prepare_point
};

// What a sampler remembers of one of its draws, for its own record_nee and resampled NEE's learnt
// target (light_dispatch.h): four words whose meaning is the drawing sampler's (rll's and ltc's
// ClusterDraw, lights/cluster_draw.h). The renderers only carry it from the draw to the record.
struct SamplerRecord {
  uint32_t word[4] = {0, 0, 0, 0};
};

// A sampler's answer: the light, its probability, and the sampler's own record of the draw.
struct SampledLight {
  uint32_t light = 0;
  float pmf = 0;  // 0: nothing was sampled
  SamplerRecord record;
};

// A sampler's typed record as SamplerRecord's words and back (T trivially copyable, at most four
// words); memcpy, which host and device compile alike.
template <class T>
RLL_HD inline SamplerRecord pack_record(const T& r) {
  static_assert(sizeof(T) <= sizeof(SamplerRecord), "a sampler's record is four words at most");
  SamplerRecord out;
  memcpy(out.word, &r, sizeof(T));
  return out;
}
template <class T>
RLL_HD inline T unpack_record(const SamplerRecord& r) {
  T out;
  memcpy(&out, r.word, sizeof(T));
  return out;
}

// What the integrator reports of one next-event sample to a learning sampler. Each learner makes
// its own reward of these: rll the cluster's contribution (estimate / P(l | cluster)), Fermat's
// RLL the largest channel of the full weighted contribution over the full pdf, Wang et al. a
// second moment.
struct NeeRecord {
  // Luminance of f * Le * G * V / pdf(y | light): the sample's contribution before dividing by
  // the light's pmf, without the path throughput or the MIS weight.
  float estimate = 0;
  // The same without the shadow ray's verdict (V = 1): zero when the light cannot contribute
  // here at all (behind the surface, outside its emission cone, a black BSDF).
  float unoccluded = 0;
  // MIS weight of the light sample against the BSDF's (1 without MIS).
  float mis_weight = 1;
  // Largest RGB component of throughput * f * Le * G * V * mis_weight / pdf(y | light) (divide
  // by the light's pmf for the full pdf).
  float max_rgb = 0;
};

}  // namespace rll
