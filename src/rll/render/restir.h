// ReSTIR DI (Bitterli, Wyman, Pharr, Shirley, Lefohn & Jarosz 2020; docs/restir.md) at the first
// vertex of each camera path that samples light (the ReSTIR vertex): M candidates of a light
// sampler (the source) resampled into one reservoir per pixel by their unshadowed contribution,
// the kept sample's shadow ray (visibility reuse), temporal reuse of the pixel's reservoir of the
// sample before (where the hit reprojects), spatial reuse of k neighbours', and the final shading.
// Everything a pixel does is an RLL_HD function over flat views (DESIGN 6): the CPU wavefront and
// cuda/wavefront.cu run the same ones (wavefront/driver.h launches them over the pixels after the
// batches of one sample of every pixel).
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "rll/core/device.h"
#include "rll/core/param_table.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/lights/light_context.h"
#include "rll/render/film.h"
#include "rll/scene/bsdf.h"
#include "rll/scene/camera.h"
#include "rll/scene/interaction.h"
#include "rll/scene/scene_view.h"

namespace rll {

class Params;

// How reservoirs of other pixels (and of the sample before) are combined: Bitterli 2020's Alg. 6
// (1/Z, Z the candidates of the reservoirs whose surface could have drawn the kept sample, each
// tested with a shadow ray from that surface), or the plain 1/sum M (biased: darker at edges of
// shadows and geometry).
enum class RestirWeights { Unbiased, Biased };

// The restir.* keys (restir_params()); the defaults are Bitterli 2020's where it gives one.
struct RestirSettings {
  bool on = false;  // a restir sampler renders
  int source = 2;   // the candidates' sampler, an index of light_sampler_names() ("tree")
  int candidates = 32;
  bool temporal = true;
  float history = 20;  // the sample before's M is capped at history x candidates
  int spatial = 5;     // neighbours; 0: no spatial reuse
  float radius = 30;   // pixels
  RestirWeights weights = RestirWeights::Unbiased;
  float normal = 25;   // the largest angle between two reused surfaces' normals, degrees
  float depth = 0.1f;  // the largest relative difference of their distances to the camera
};

// The restir.* keys as one table (core/param_table.h); `rll samplers --params restir` lists them.
const std::vector<ParamSpec<RestirSettings>>& restir_params();
// The restir.* keys in `params`, checked (naming the key), for a render with a restir sampler;
// `filter` the --filter (psf is refused). Throws rll::Error.
RestirSettings make_restir_settings(const Params& params, const std::string& filter);
// The name of the candidates' sampler (restir.source).
const std::string& restir_source_name(const RestirSettings& s);

inline constexpr int kMaxRestirCandidates = 256;
inline constexpr int kMaxRestirNeighbours = 32;

// What every pixel's ReSTIR work reads of the settings (in PathConstants).
struct RestirConstants {
  bool on = false;
  int candidates = 32;
  bool temporal = true;
  float history_cap = 640;  // history x candidates
  int spatial = 5;
  float radius = 30;
  bool unbiased = true;
  float cos_normal = 0.9063f;  // cos(normal)
  float depth = 0.1f;
};
RestirConstants make_restir_constants(const RestirSettings& s);

// The numbers ReSTIR draws, at dimensions of the pixel's sample far past the path's, resampled
// NEE's (1 << 24) and the filter's (1 << 25): 4 per candidate (light, point, keep), then the
// temporal merge's one, then 3 per neighbour (offset, keep).
inline constexpr uint32_t kRestirBase = 1u << 26;
inline constexpr uint32_t kRestirCandidateDims = 4;
inline constexpr uint32_t kRestirTemporalDim = kRestirBase + kRestirCandidateDims * 256;
inline constexpr uint32_t kRestirSpatialBase = kRestirTemporalDim + 16;

// A reservoir's sample: a point on a light, stored so that any receiver and the next frame (where
// the light may have moved) can evaluate it: the light and, on a triangle, the point's
// barycentrics (its weights of the second and third vertex); a point or spot light is its
// position, a directional light its direction.
inline constexpr uint32_t kRestirNoLight = 0xffffffffu;
struct RestirSample {
  uint32_t light = kRestirNoLight;
  float b1 = 0, b2 = 0;
};

// A reservoir (Bitterli 2020's): its sample, the target of the sample at its own pixel, the sum
// of the resampling weights, the candidates it stands for (M) and its unbiased contribution
// weight W = w_sum / (Z p_hat), Z = M where every reservoir combined could have drawn the sample.
struct Reservoir {
  RestirSample y;
  float p_hat = 0;
  float w_sum = 0;
  float M = 0;
  float W = 0;
};

// The ReSTIR vertex of a pixel's path: what the target needs there (the light context's point,
// normals and wo; the Bsdf is kept beside it), the path throughput and the distance to the camera
// (the similarity test). `valid` 0: the path has no ReSTIR vertex in this sample.
struct RestirVertex {
  LightContext ctx;
  Rgb beta{0};
  float depth = 0;
  uint32_t valid = 0;
};

// The kept candidate as the source drew it, for a learning source's record after the shadow ray.
struct RestirKept {
  SampledLight light;
  NeeRecord record;  // as if unoccluded: the visibility test zeroes what V takes
};

// What the rest of a pixel's path brought back (everything but the ReSTIR vertex's direct
// light), and whether a path of this sample reached the pixel (a stopped pass leaves some out).
struct RestirPixel {
  Rgb L{0};
  uint32_t reached = 0;
};

// The bytes ReSTIR takes per pixel: two vertex records and Bsdfs (this sample's and the one
// before's), three reservoirs (the sample's, the final one and the one before's), the kept
// candidate and the pixel's radiance record.
inline constexpr double kRestirBytesPerPixel = 2.0 * (sizeof(RestirVertex) + sizeof(Bsdf)) +
                                               3.0 * sizeof(Reservoir) + sizeof(RestirKept) +
                                               sizeof(RestirPixel);
inline constexpr const char* kRestirPixelText = "ReSTIR's reservoirs and vertex records";
// Throws rll::Error where ReSTIR's arrays for `pixels` pixels do not fit the memory budget
// (core/memory_budget.h), before they are allocated.
void check_restir_memory(size_t pixels);

// One sample's per-pixel arrays, in the memory of the device that renders (views), and what the
// per-pixel steps need besides the path constants.
struct RestirBuffers {
  View<RestirVertex> vertex, prev_vertex;  // this sample's vertex records, the sample before's
  View<Bsdf> bsdf, prev_bsdf;
  View<Reservoir> reservoir;  // the sample's: initial, after visibility, after temporal reuse
  View<Reservoir> final_, prev_final;  // after spatial reuse: this sample's, the one before's
  View<RestirKept> kept;
  View<RestirPixel> pixel;
  Camera prev_camera;  // the sample before's
  bool has_prev = false;
  int width = 0, height = 0;
  // The sample whose pixels are resolved: its streams' keys.
  uint64_t frame_seed = 0, sample = 0;
  PointSet points = PointSet::Sobol;
};

// ReSTIR's history in the host's memory (the CPU wavefront's), kept by the session from render
// to render: the vertex records, Bsdfs and final reservoirs of the last sample rendered (and the
// arrays of the next), so that a render that follows a frame reuses the frame before's.
struct RestirFrames {
  View<RestirVertex> vertex[2];
  View<Bsdf> bsdf[2];
  View<Reservoir> final_[2];
  int last = 0;        // [last]: the last sample's, where `holds`
  bool holds = false;  // a sample was resolved into [last]
  size_t pixels = 0;
  Camera camera;  // the last sample's
};

class RestirHistory {
 public:
  // Checks the memory (check_restir_memory) before allocating.
  explicit RestirHistory(size_t pixels);
  ~RestirHistory();
  RestirHistory(const RestirHistory&) = delete;
  RestirHistory& operator=(const RestirHistory&) = delete;
  RestirFrames& frames() { return m_frames; }
  size_t bytes() const { return m_bytes; }

 private:
  std::vector<RestirVertex> m_vertex[2];
  std::vector<Reservoir> m_final[2];
  void* m_bsdf[2] = {nullptr, nullptr};
  size_t m_bytes = 0;
  RestirFrames m_frames;
};

}  // namespace rll
