// Next-event estimation with several weighted samples per vertex, each with its own shadow ray:
// the resampled hierarchical tree's two reservoir stages over the split descent's candidates
// (lights/rht_view.h; docs/rht.md). RLL_HD, with fixed-size arrays and nothing allocated: every
// renderer runs it through draw_nee (render/nee_draw.h).
#pragma once

#include <bit>
#include <cstdint>

#include "rll/lights/rht_view.h"
#include "rll/render/path_vertex.h"

namespace rll {

// The numbers of rht's draw beyond the vertex's own light numbers (which choose a directional
// light or the descent's children, and the first light point): the split number and a key for
// the hashed numbers (the descent's scrambles, the reservoirs' slots and decisions). They lie at
// the dimensions of resampled NEE's first extra candidate (rht runs with nee.candidates = 1).
struct RhtNumbers {
  LightNumbers light;
  float u_split = 0;
  uint64_t key = 0;
};
RLL_HD inline RhtNumbers rht_numbers(SampleStream& stream, int depth) {
  RhtNumbers u;
  u.light = light_numbers(stream, depth);
  stream.seek(candidate_dimension(depth, 1));
  u.u_split = stream.next();
  const uint32_t a = std::bit_cast<uint32_t>(stream.next());
  const uint32_t b = std::bit_cast<uint32_t>(stream.next());
  u.key = mix64((uint64_t(a) << 32 | b) + 0x9e3779b97f4a7c15ull * uint64_t(depth + 1));
  return u;
}

namespace detail {
// A set of `count` streaming weighted reservoirs: the k-th item of each batch of `count` goes to
// reservoir (k + offset) mod count, the batch's offset hashed from the key, and a reservoir keeps
// an item with probability weight / (its weights' sum so far), by a number hashed from the key
// and the item's index. Which reservoir an item goes to never depends on its weight, and the
// decisions' numbers are independent, so each reservoir ends with one item of its share, kept
// with probability weight / its weight sum. (The public code steps one number along the
// golden-ratio sequence for every decision: the decisions of a reservoir then depend on each
// other, and with three or more items the kept one's probability is not weight / sum.)
struct RhtReservoirs {
  int count = 1, local = 0;
  uint64_t key = 0, batch = 0, items = 0;
  uint32_t offset = 0;
  RLL_HD RhtReservoirs(int n, uint64_t k) : count(n), key(k) {
    offset = uint32_t(mix64(key) % uint64_t(count));
  }
  // The reservoir of the next item.
  RLL_HD int slot() {
    if (local == count) {
      local = 0;
      offset = uint32_t(mix64(key + ++batch) % uint64_t(count));
    }
    return int((uint32_t(local++) + offset) % uint32_t(count));
  }
  // Adds an item of weight w > 0 to a reservoir whose weight sum is `sum`: whether it replaces
  // the one kept there.
  RLL_HD bool keeps(float w, float& sum) {
    sum += w;
    const uint64_t h = mix64(key ^ (0xd1b54a32d192ed03ull * ++items));
    return u32_to_unit_float(uint32_t(h >> 32)) * sum < w;  // never 1: a first item is kept
  }
};
// The public code's offsets between the light points of the first stage's reservoirs (the R2
// sequence).
inline constexpr float kR2x = 0.75487767f, kR2y = 0.56984029f;
}  // namespace detail

// The two stages' reservoirs of one vertex's draw (672 bytes): on the thread's stack on the CPU,
// in the path slot's memory on the GPU (the wavefront's PathSlots::rht), where a thread's stack
// holding them took the next-event stage over its budgets (tests/unit/kernel_budgets.h).
struct RhtReservoirMemory {
  struct Kept {  // a first-stage survivor
    uint32_t light;
    float pdf, weight, sum;
  };
  struct Second {
    Vec2 u;     // the kept survivor's light point numbers
    int first;  // its first-stage reservoir
    float weight, sum;
  };
  Kept first[kRhtMaxReservoirs];
  Second second[kRhtMaxSamples];
};

// Draws the vertex's samples, calling emit(const NeeDraw&) for each (at most v.samples): with
// probability rht_directional_probability a
// directional light (one sample), else the split descent's candidates, kept by the first stage's
// reservoirs by tree importance over candidate probability, each survivor's light sample weighed
// by its unshadowed contribution with the MIS weight against BSDF sampling folded in, and kept by
// the second stage's reservoirs (v.samples of them). The second stage keeps which survivor each
// reservoir holds and makes its light sample again at the end (the same function of the same
// numbers): a GPU thread's stack holds no light samples. The reservoirs are `memory`'s.
template <class Emit>
RLL_HD inline void rht_nee(const PathConstants& c, const RhtView& v, const LightContext& ctx,
                           const Bsdf& bsdf, const Vec3& wo, SampleStream& stream, int depth,
                           RhtReservoirMemory& memory, Emit&& emit) {
  const RhtNumbers u = rht_numbers(stream, depth);
  const float p_dir = rht_directional_probability(v);
  double u_light = u.light.u_light;
  if (u_light < p_dir) {
    const uint32_t i = std::min(v.dir_count - 1, uint32_t(u_light / p_dir * v.dir_count));
    NeeDraw s;
    s.light.light = v.dir_begin + i;
    s.light.pmf = p_dir / float(v.dir_count);
    s.setup = nee_setup(c, ctx, bsdf, wo, s.light.light, u.light.u_pos);
    emit(s);
    return;
  }
  if (!v.has_tree_lights) return;
  u_light = std::min((u_light - p_dir) / (1 - p_dir), double(detail::kBelowOne));

  // First stage: the descent's candidates by tree importance over candidate probability.
  using Kept = RhtReservoirMemory::Kept;
  Kept* const first = memory.first;
  for (int i = 0; i < v.reservoirs; ++i) first[i] = Kept{0, 0, 0, 0};
  detail::RhtReservoirs h(v.reservoirs, mix64(u.key + 1));
  rht_descend(v, ctx.p, ctx.n, u_light, u.u_split, u.key, 1 - p_dir,
              [&](uint32_t light, float pdf, float importance) {
                const float w = importance / pdf;
                if (!(w > 0) || !(w < 3e38f)) return;
                Kept& k = first[h.slot()];
                if (h.keeps(w, k.sum)) {
                  k.light = light;
                  k.pdf = pdf;
                  k.weight = w;
                }
              });

  // Second stage: each survivor's light sample, weighed by f Le G / (its density as the light
  // strategy draws it + the BSDF's pdf), the balance heuristic's MIS weight folded in.
  const bool mis = c.strategy == LightStrategy::Mis;
  using Second = RhtReservoirMemory::Second;
  Second* const second = memory.second;
  for (int i = 0; i < v.samples; ++i) second[i].weight = second[i].sum = 0;
  detail::RhtReservoirs f(v.samples, mix64(u.key + 2));
  Vec2 u_pos = u.light.u_pos;
  for (int i = 0; i < v.reservoirs; ++i) {
    const Vec2 u_here = u_pos;
    u_pos.x += detail::kR2x;
    u_pos.y += detail::kR2y;
    if (u_pos.x >= 1) u_pos.x -= 1;
    if (u_pos.y >= 1) u_pos.y -= 1;
    const Kept& k = first[i];
    if (!(k.weight > 0)) continue;
    const float h_prob = k.weight / k.sum;
    const NeeSetup n = nee_setup(c, ctx, bsdf, wo, k.light, u_here);
    if (!n.traces) continue;
    const float bsdf_pdf = mis && !n.light_delta ? bsdf.pdf(wo, n.wi) : 0.0f;
    const float w = max_component(n.unoccluded) * n.light_pdf /
                    std::max(k.pdf * n.light_pdf * h_prob + bsdf_pdf, 1e-30f);
    if (!(w > 0) || !(w < 3e38f)) continue;
    Second& s = second[f.slot()];
    if (f.keeps(w, s.sum)) {
      s.u = u_here;
      s.first = i;
      s.weight = w;
    }
  }
  for (int i = 0; i < v.samples; ++i) {
    if (!(second[i].weight > 0)) continue;
    const Kept& k = first[second[i].first];
    NeeDraw s;
    s.setup = nee_setup(c, ctx, bsdf, wo, k.light, second[i].u);
    s.light.light = k.light;
    s.light.pmf = k.pdf;
    s.scale = 1 / (k.weight / k.sum);
    s.scale /= second[i].weight / second[i].sum;
    emit(s);
  }
}

}  // namespace rll
