// CoatedDiffuse against pbrt-v4's measured directional albedo of `coateddiffuse` over reflectance,
// roughness (remapped and not) and view angle (issue 32): every entry within 1% plus the two
// standard errors.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <string>
#include <tuple>
#include <utility>

#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/scene/bsdf.h"

using namespace rll;

namespace {

// One figure of pbrt-v4's table: a(theta) = E[f |cos| / pdf] of its Sample_f walk (a uniform
// infinite light, which pbrt-v4 never light-samples), eta 1.5, thickness 0.01, medium albedo 0,
// maxdepth 10. From ../shared/coateddiffuse-pbrt-v4.md (pbrt-v4 at commit 5f7a606, 2^20 paths
// per figure; albedo = mean of R, G, B, se its standard error).
struct PbrtFigure {
  float reflectance, roughness;
  bool remap;
  float theta_deg;
  double albedo, se;
};

constexpr PbrtFigure kPbrt[] = {
    {0.1f, 0, true, 0, 0.08027, 0.00006},       {0.1f, 0, true, 45, 0.09009, 0.00006},
    {0.1f, 0, true, 70, 0.20588, 0.00011},      {0.1f, 0.025f, true, 0, 0.07910, 0.00007},
    {0.1f, 0.025f, true, 45, 0.08927, 0.00010}, {0.1f, 0.025f, true, 70, 0.15872, 0.00019},
    {0.1f, 0.05f, true, 0, 0.07751, 0.00007},   {0.1f, 0.05f, true, 45, 0.08647, 0.00011},
    {0.1f, 0.05f, true, 70, 0.13719, 0.00018},  {0.1f, 0.15f, true, 0, 0.07090, 0.00009},
    {0.1f, 0.15f, true, 45, 0.07631, 0.00011},  {0.1f, 0.15f, true, 70, 0.10345, 0.00016},
    {0.1f, 0.3f, true, 0, 0.06279, 0.00010},    {0.1f, 0.3f, true, 45, 0.06618, 0.00011},
    {0.1f, 0.3f, true, 70, 0.08401, 0.00014},   {0.1f, 0.5f, true, 0, 0.05476, 0.00010},
    {0.1f, 0.5f, true, 45, 0.05726, 0.00010},   {0.1f, 0.5f, true, 70, 0.07070, 0.00013},
    {0.1f, 0.15f, false, 0, 0.07926, 0.00007},  {0.1f, 0.15f, false, 45, 0.08953, 0.00010},
    {0.1f, 0.15f, false, 70, 0.16178, 0.00019}, {0.1f, 0.3f, false, 0, 0.07480, 0.00008},
    {0.1f, 0.3f, false, 45, 0.08197, 0.00011},  {0.1f, 0.3f, false, 70, 0.11879, 0.00016},
    {0.5f, 0, true, 0, 0.30435, 0.00023},       {0.5f, 0, true, 45, 0.31142, 0.00025},
    {0.5f, 0, true, 70, 0.39867, 0.00022},      {0.5f, 0.025f, true, 0, 0.29255, 0.00023},
    {0.5f, 0.025f, true, 45, 0.29863, 0.00024}, {0.5f, 0.025f, true, 70, 0.34478, 0.00027},
    {0.5f, 0.05f, true, 0, 0.28318, 0.00024},   {0.5f, 0.05f, true, 45, 0.28749, 0.00025},
    {0.5f, 0.05f, true, 70, 0.31718, 0.00027},  {0.5f, 0.15f, true, 0, 0.25657, 0.00023},
    {0.5f, 0.15f, true, 45, 0.25514, 0.00023},  {0.5f, 0.15f, true, 70, 0.26405, 0.00023},
    {0.5f, 0.3f, true, 0, 0.23048, 0.00023},    {0.5f, 0.3f, true, 45, 0.22486, 0.00021},
    {0.5f, 0.3f, true, 70, 0.22410, 0.00020},   {0.5f, 0.5f, true, 0, 0.20691, 0.00022},
    {0.5f, 0.5f, true, 45, 0.19825, 0.00019},   {0.5f, 0.5f, true, 70, 0.19299, 0.00018},
    {0.5f, 0.15f, false, 0, 0.29363, 0.00023},  {0.5f, 0.15f, false, 45, 0.29983, 0.00025},
    {0.5f, 0.15f, false, 70, 0.34844, 0.00027}, {0.5f, 0.3f, false, 0, 0.27113, 0.00023},
    {0.5f, 0.3f, false, 45, 0.27270, 0.00023},  {0.5f, 0.3f, false, 70, 0.29041, 0.00025},
    {0.9f, 0, true, 0, 0.71338, 0.00037},       {0.9f, 0, true, 45, 0.71493, 0.00034},
    {0.9f, 0, true, 70, 0.75110, 0.00032},      {0.9f, 0.025f, true, 0, 0.64968, 0.00039},
    {0.9f, 0.025f, true, 45, 0.64885, 0.00038}, {0.9f, 0.025f, true, 70, 0.65638, 0.00039},
    {0.9f, 0.05f, true, 0, 0.60884, 0.00042},   {0.9f, 0.05f, true, 45, 0.60601, 0.00041},
    {0.9f, 0.05f, true, 70, 0.60327, 0.00040},  {0.9f, 0.15f, true, 0, 0.51589, 0.00040},
    {0.9f, 0.15f, true, 45, 0.50530, 0.00039},  {0.9f, 0.15f, true, 70, 0.48869, 0.00038},
    {0.9f, 0.3f, true, 0, 0.44410, 0.00040},    {0.9f, 0.3f, true, 45, 0.42727, 0.00036},
    {0.9f, 0.3f, true, 70, 0.40265, 0.00033},   {0.9f, 0.5f, true, 0, 0.38883, 0.00037},
    {0.9f, 0.5f, true, 45, 0.36680, 0.00032},   {0.9f, 0.5f, true, 70, 0.33900, 0.00029},
    {0.9f, 0.15f, false, 0, 0.65444, 0.00038},  {0.9f, 0.15f, false, 45, 0.65430, 0.00038},
    {0.9f, 0.15f, false, 70, 0.66319, 0.00039}, {0.9f, 0.3f, false, 0, 0.56341, 0.00042},
    {0.9f, 0.3f, false, 45, 0.55691, 0.00044},  {0.9f, 0.3f, false, 70, 0.54622, 0.00039},
};

struct Estimate {
  double mean = 0, se = 0;
};

// The mean of `n` draws of `draw(u_lobe, u)` (grey values), from kReplicas independent replicas
// with u_lobe stratified within each (the coating's Fresnel choice between reflection and the walk
// is most of the variance at a dark base); the standard error from the scatter of the replicas'
// means, which are independent.
template <typename Draw>
Estimate replicated_mean(int n, uint64_t seed, const Draw& draw) {
  constexpr int kReplicas = 32;
  const int m = n / kReplicas;
  Pcg32 rng(seed);
  double sum = 0, sum2 = 0;
  for (int r = 0; r < kReplicas; ++r) {
    double s = 0;
    for (int i = 0; i < m; ++i) {
      const float u_lobe = std::min(0.99999994f, (float(i) + rng.next_float()) / float(m));
      const Vec2 u{rng.next_float(), rng.next_float()};
      s += draw(u_lobe, u);
    }
    s /= m;
    sum += s;
    sum2 += s * s;
  }
  Estimate e;
  e.mean = sum / kReplicas;
  e.se = std::sqrt(std::max(0.0, sum2 / kReplicas - e.mean * e.mean) / (kReplicas - 1));
  return e;
}

double grey(const Rgb& c) {
  return (double(c.x) + c.y + c.z) / 3;
}

// rll's directional albedo as pbrt-v4's furnace sees it: f |cos| / pdf over the BSDF's own
// samples.
Estimate sampled_albedo(const Bsdf& bsdf, const Vec3& wo, int n, uint64_t seed) {
  return replicated_mean(n, seed, [&](float u_lobe, Vec2 u) {
    BsdfSample s;
    if (!bsdf.sample(wo, u_lobe, u, s)) return 0.0;
    return grey(s.f) * std::abs(s.wi.z) / s.pdf;
  });
}

// The same from eval() (what next-event estimation sees): the integral of f cos over directions
// drawn half from the cosine and half from the coating's GGX reflection lobe (so that a glossy
// coating's highlight is not left to chance), with that exact mixture density; plus the smooth
// coating's mirror reflection, a delta that eval() never sees.
Estimate evaluated_albedo(const Bsdf& bsdf, const Vec3& wo, float alpha, int n, uint64_t seed) {
  const bool smooth = alpha < kSmoothAlpha;
  const Ggx ggx{std::max(alpha, kSmoothAlpha)};
  Estimate e = replicated_mean(n, seed, [&](float u_lobe, Vec2 u) {
    const Vec3 wi = smooth || u_lobe < 0.5f ? sample_cosine_hemisphere(u)
                                            : reflect(wo, ggx.sample_visible(wo, u));
    if (!(wi.z > 0)) return 0.0;
    double pdf = cosine_hemisphere_pdf(wi.z);
    if (!smooth) {
      const Vec3 wm = normalize(wo + wi);
      pdf = 0.5 * pdf + 0.5 * ggx.visible_d(wo, wm) / (4 * dot(wo, wm));
    }
    return grey(bsdf.eval(wo, wi)) * wi.z / pdf;
  });
  if (smooth) e.mean += fresnel_dielectric(wo.z, 1.5f);
  return e;
}

// Both of rll's estimators: sample() is what pbrt-v4's table measures (its uniform sky is never
// light-sampled); eval() must agree with it, or next-event estimation renders another material.
// pbrt-v4's own f() does not: its MIS weight for the base's sample leaving through the coating
// takes the exit interface's pdf in the reverse direction (PDF(-w, wi), where the competing
// next-event strategy samples -w from wi), so the two weights do not sum to one. With that weight
// eval() is 1.3-11% high at every rough entry (failing 59 of 63); under MIS with a light-sampled
// sky it gives the excess that ../shared/coateddiffuse-pbrt-v4.md measures for pbrt-v4
// (docs/materials.md).
TEST(CoatedDiffusePbrtTable, EveryEntryWithinOnePercentOfPbrtV4) {
  // Enough that rll's standard error is below 0.3% of the figure for sample() (a dark base's
  // figure is mostly the coating's noisy reflection: twice the samples) and 0.5% for eval()
  // (its own walk's noise dominates, most over a bright base; a 5% error is still 10 sigma).
  int index = 0;
  for (const PbrtFigure& p : kPbrt) {
    Material m;
    m.type = MaterialType::CoatedDiffuse;
    m.albedo = Rgb(p.reflectance);
    // pbrt-v4's remapping (its RoughnessToAlpha), as rll's pbrt reader applies it.
    m.roughness = p.remap ? std::sqrt(p.roughness) : p.roughness;
    m.ior = 1.5f;
    m.thickness = 0.01f;
    const float t = p.theta_deg * kPi / 180;
    const Vec3 wo(std::sin(t), 0, std::cos(t)), n(0, 0, 1);
    const Bsdf bsdf(m, m.albedo, n, n, wo, -1, 1000 + uint64_t(index));
    const int sampled = p.reflectance < 0.3f ? 1 << 19 : 1 << 18;
    const Estimate s = sampled_albedo(bsdf, wo, sampled, 77 + uint64_t(index));
    const int evaluated = p.reflectance > 0.7f ? 1 << 16 : 1 << 15;
    const Estimate e = evaluated_albedo(bsdf, wo, m.roughness, evaluated, 991 + uint64_t(index));
    ++index;
    const std::string what =
        fmt::format("reflectance {} roughness {} remap {} theta {}: pbrt {:.5f} +- {:.5f}",
                    p.reflectance, p.roughness, p.remap, p.theta_deg, p.albedo, p.se);
    RecordProperty(fmt::format("r{}_rough{}_{}_t{}", p.reflectance, p.roughness,
                               p.remap ? "remap" : "alpha", p.theta_deg),
                   fmt::format("sample {:.5f} +- {:.5f}, eval {:.5f} +- {:.5f}, pbrt {:.5f} +- "
                               "{:.5f}",
                               s.mean, s.se, e.mean, e.se, p.albedo, p.se));
    for (const auto& [name, r, noise] :
         {std::tuple{"sample", s, 0.003}, std::tuple{"eval", e, 0.005}}) {
      // rll's own noise must be well below the 1% asked for, or the bound means little.
      EXPECT_LT(r.se, noise * p.albedo) << what << ", " << name;
      EXPECT_LE(std::abs(r.mean - p.albedo), 0.01 * p.albedo + 3 * std::hypot(p.se, r.se))
          << fmt::format("{}, {} {:.5f} +- {:.5f} ({:+.2f}%)", what, name, r.mean, r.se,
                         100 * (r.mean / p.albedo - 1));
    }
  }
}

}  // namespace
