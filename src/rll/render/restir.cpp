#include "rll/render/restir.h"

#include <fmt/format.h>

#include <algorithm>
#include <new>

#include "rll/core/error.h"
#include "rll/core/memory_budget.h"
#include "rll/core/params.h"
#include "rll/lights/light_sampler.h"

namespace rll {

const std::vector<ParamSpec<RestirSettings>>& restir_params() {
  using S = RestirSettings;
  static const std::vector<ParamSpec<S>> table = {
      choice_param("source", light_sampler_names(), field<S, &S::source>()),
      int_param("candidates", ParamRange::closed(1, kMaxRestirCandidates),
                field<S, &S::candidates>(), "the initial candidates M of each pixel"),
      choice_param("temporal", {"off", "on"}, field<S, &S::temporal>()),
      float_param("history", ParamRange::closed(0, 1e6), field<S, &S::history>(),
                  "the cap of the sample before's M, in multiples of restir.candidates"),
      int_param("spatial", ParamRange::closed(0, kMaxRestirNeighbours), field<S, &S::spatial>(),
                "the neighbours of spatial reuse; 0 is off"),
      float_param("radius", ParamRange::open_closed(0, 1e4), field<S, &S::radius>(),
                  "the spatial neighbours' disk radius in pixels"),
      choice_param("weights", {"unbiased", "biased"}, field<S, &S::weights>()),
      float_param("normal", ParamRange::closed(0, 180), field<S, &S::normal>(),
                  "the largest angle between reused surfaces' normals, degrees"),
      float_param("depth", ParamRange::at_least(0), field<S, &S::depth>(),
                  "the largest relative difference of reused surfaces' distances to the camera"),
  };
  return table;
}

const std::string& restir_source_name(const RestirSettings& s) {
  return light_sampler_names().at(size_t(s.source));
}

RestirSettings make_restir_settings(const Params& params, const std::string& filter) {
  RestirSettings s;
  s.on = true;
  read_params(restir_params(), params, "restir", s);
  if (filter == "psf")
    fail(
        "--filter psf with a restir sampler: ReSTIR owns the camera vertex's direct light, which "
        "the filter would average; render restir with --filter none");
  const std::string& source = restir_source_name(s);
  if (source == "rht")
    fail(
        "--set restir.source=rht: rht keeps several light samples a vertex of its own; ReSTIR's "
        "candidates come from a sampler that draws one (uniform, power, tree, rll, ...)");
  return s;
}

RestirConstants make_restir_constants(const RestirSettings& s) {
  RestirConstants c;
  if (!s.on) return c;
  c.on = true;
  c.candidates = s.candidates;
  c.temporal = s.temporal;
  c.history_cap = s.history * float(s.candidates);
  c.spatial = s.spatial;
  c.radius = s.radius;
  c.unbiased = s.weights == RestirWeights::Unbiased;
  c.cos_normal = std::cos(s.normal * float(kPi) / 180.0f);
  c.depth = s.depth;
  return c;
}

void check_restir_memory(size_t pixels) {
  check_memory_budget(double(pixels) * kRestirBytesPerPixel,
                      fmt::format("{} for {} pixels ({} bytes a pixel)", kRestirPixelText, pixels,
                                  kRestirBytesPerPixel));
}

RestirHistory::RestirHistory(size_t pixels) {
  check_restir_memory(pixels);
  for (int i = 0; i < 2; ++i) {
    m_vertex[i].resize(pixels);
    m_final[i].resize(pixels);
    // A Bsdf has no default constructor: its records are constructed in place by the stage that
    // writes them (and read only where their vertex record is valid).
    m_bsdf[i] =
        ::operator new(std::max<size_t>(1, pixels * sizeof(Bsdf)), std::align_val_t(alignof(Bsdf)));
    m_frames.vertex[i] = view_of(m_vertex[i]);
    m_frames.final_[i] = view_of(m_final[i]);
    m_frames.bsdf[i] = {static_cast<Bsdf*>(m_bsdf[i]), pixels};
  }
  m_frames.pixels = pixels;
  m_bytes = 2 * pixels * (sizeof(RestirVertex) + sizeof(Reservoir) + sizeof(Bsdf));
}

RestirHistory::~RestirHistory() {
  for (void* p : m_bsdf)
    if (p) ::operator delete(p, std::align_val_t(alignof(Bsdf)));
}

}  // namespace rll
