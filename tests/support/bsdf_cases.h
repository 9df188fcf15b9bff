// The BSDF configurations the unit and statistical tests sweep: every material type at several
// roughness values and incident angles down to grazing, and shading normals tilted off the
// geometric one.
#pragma once

#include <fmt/format.h>

#include <ostream>
#include <string>
#include <vector>

#include "rll/scene/bsdf.h"
#include "support/sphere_chi2.h"

namespace rll::test {

inline Material test_material(MaterialType type, float roughness) {
  Material m;
  m.type = type;
  m.roughness = roughness;
  switch (type) {
    case MaterialType::Diffuse:
      m.albedo = Rgb(0.5f, 0.4f, 0.3f);
      break;
    case MaterialType::Conductor:  // aluminium
      m.eta = Rgb(1.66f, 0.88f, 0.52f);
      m.k = Rgb(9.22f, 6.27f, 4.84f);
      break;
    case MaterialType::Plastic:
    case MaterialType::CoatedDiffuse:
      m.albedo = Rgb(0.5f, 0.4f, 0.3f);
      break;
    case MaterialType::Dielectric:  // glass: ior 1.5 (the default)
    case MaterialType::ThinDielectric:
      break;
  }
  return m;
}

struct BsdfCase {
  MaterialType type;
  float roughness;
  float theta_o;  // degrees from the geometric normal (0, 0, 1), towards +x
  float tilt;     // degrees the shading normal leans towards +x

  Vec3 ng() const { return {0, 0, 1}; }
  Vec3 ns() const { return {std::sin(radians(tilt)), 0, std::cos(radians(tilt))}; }
  Vec3 wo() const { return {std::sin(radians(theta_o)), 0, std::cos(radians(theta_o))}; }
  Bsdf bsdf() const {
    Material m = test_material(type, roughness);
    return Bsdf(m, m.albedo, ns(), ng(), wo());
  }
  friend void PrintTo(const BsdfCase& c, std::ostream* os) { *os << c.name(); }
  std::string name() const {
    return fmt::format("{}_r{:03d}_o{}{:02d}_t{:02d}", material_type_name(type),
                       int(std::lround(roughness * 100)), theta_o < 0 ? "m" : "",
                       int(std::lround(std::abs(theta_o))), int(std::lround(tilt)));
  }
};

inline std::vector<BsdfCase> bsdf_cases() {
  std::vector<BsdfCase> cases;
  const float angles[] = {0, 30, 60, 80, 89};
  for (float a : angles) cases.push_back({MaterialType::Diffuse, 1.0f, a, 0});
  for (MaterialType t : {MaterialType::Conductor, MaterialType::Plastic})
    for (float r : {0.05f, 0.15f, 0.4f, 1.0f})
      for (float a : angles) cases.push_back({t, r, a, 0});
  // Shading normals tilted away from the geometric one: directions below the geometric
  // surface must be rejected by sample() and have pdf 0 alike.
  for (MaterialType t : {MaterialType::Diffuse, MaterialType::Conductor, MaterialType::Plastic})
    for (float a : {-70.0f, 10.0f, 70.0f}) cases.push_back({t, 0.3f, a, 25});
  return cases;
}

// The chi-square test of a BSDF's sampled directions (u_lobe, then u) against its pdf.
inline SphereChi2 bsdf_chi2(const Bsdf& bsdf, const Vec3& wo, const SphereBins& bins, size_t samples,
                            uint64_t seed) {
  auto sample = [&](Pcg32& rng) -> std::optional<Vec3> {
    BsdfSample s;
    float u_lobe = rng.next_float();
    Vec2 u{rng.next_float(), rng.next_float()};
    if (!bsdf.sample(wo, u_lobe, u, s)) return std::nullopt;
    return s.wi;
  };
  return sphere_chi2(bins, samples, seed, sample, [&](const Vec3& wi) { return double(bsdf.pdf(wo, wi)); });
}

}  // namespace rll::test
