// Surface materials as loaded from scene files; a Bsdf is built from one at every hit.
#pragma once

#include <string>

#include "rll/core/math.h"

namespace rll {

enum class MaterialType : uint8_t {
  Diffuse,    // Lambertian
  Conductor,  // rough GGX metal with complex Fresnel
  Plastic,    // rough dielectric coating (GGX, dielectric Fresnel) over a Lambertian base
};

struct Material {
  std::string name;
  MaterialType type = MaterialType::Diffuse;
  Rgb albedo{0.8f};          // Lambertian reflectance (Diffuse, Plastic base)
  int albedo_texture = -1;   // index into Scene::textures; multiplies albedo
  Rgb specular{1.0f};        // tint of the specular lobe (Conductor, Plastic)
  Rgb eta{0.2f, 0.92f, 1.1f};  // conductor: real part of the index of refraction (default: copper)
  Rgb k{3.9f, 2.45f, 2.14f};   //            imaginary part
  float ior = 1.5f;          // plastic coating's index of refraction
  float roughness = 0.3f;    // GGX alpha (isotropic), clamped to >= 1e-3
  Rgb emission{0.0f};        // emitted radiance; nonzero makes each triangle a light
  bool two_sided_emission = false;
  bool is_emissive() const { return emission.x > 0 || emission.y > 0 || emission.z > 0; }
};

// Aluminium's complex index of refraction: a near-white metal that `specular` tints, for the
// formats that describe a metal by its colour alone (MTL, glTF, pbrt's "reflectance").
inline const Rgb kTintableEta{1.66f, 0.88f, 0.52f}, kTintableK{9.22f, 6.27f, 4.84f};

const char* material_type_name(MaterialType t);

}  // namespace rll
