// Surface materials as loaded from scene files; a Bsdf is built from one at every hit.
#pragma once

#include <string>

#include "rll/core/math.h"

namespace rll {

enum class MaterialType : uint8_t {
  Diffuse,     // Lambertian
  Conductor,   // rough GGX metal with complex Fresnel
  Plastic,     // rll's own: rough dielectric coating (GGX, dielectric Fresnel) over a Lambertian
               // base, without light exchanged between them (brighter than pbrt-v4's coateddiffuse)
  Dielectric,  // glass: smooth (roughness < 1e-3: Dirac lobes) or rough GGX, reflection and
               // refraction, `ior` = inside over outside, the outside being the side the
               // geometric normal points to as wound (docs/materials.md)
  ThinDielectric,  // a thin pane (pbrt-v4's thindielectric): Fresnel reflection, straight
                   // transmission
  CoatedDiffuse,   // pbrt-v4's coateddiffuse: the layered model (a dielectric coating of `ior`,
                  // `roughness` and `thickness` over a Lambertian `albedo`, light bouncing between)
};

// What a Bsdf is built from: a material without its name, trivially copyable, so that kernels
// read an array of them (SceneView::materials).
struct MaterialData {
  MaterialType type = MaterialType::Diffuse;
  Rgb albedo{0.8f};            // Lambertian reflectance (Diffuse, Plastic base)
  int albedo_texture = -1;     // index into Scene::textures; multiplies albedo
  Rgb specular{1.0f};          // tint of the specular lobe (Conductor, Plastic)
  Rgb eta{0.2f, 0.92f, 1.1f};  // conductor: real part of the index of refraction (default: copper)
  Rgb k{3.9f, 2.45f, 2.14f};   //            imaginary part
  float ior = 1.5f;            // index of refraction: plastic and coated coatings, glass
  float roughness = 0.3f;  // GGX alpha (isotropic; pbrt-v4's remapped alpha, not its "roughness"),
                           // clamped to >= 1e-3 (Dielectric, CoatedDiffuse: below 1e-3 = smooth)
  int roughness_texture = -1;  // index into Scene::textures (its first channel): replaces roughness
  float thickness = 0.01f;     // CoatedDiffuse: the coating's thickness (pbrt-v4's default)
  Rgb emission{0.0f};          // emitted radiance; nonzero makes each triangle a light
  // Index into Scene::textures: the emitted radiance at a point is emission times this
  // texture's bilinear lookup there (emission_at, scene_view.h); -1: none.
  int emission_texture = -1;
  bool two_sided_emission = false;
  RLL_HD bool is_emissive() const { return emission.x > 0 || emission.y > 0 || emission.z > 0; }
};

// A material as the loaders write it: its data and the name messages give.
struct Material : MaterialData {
  std::string name;
};

// Aluminium's complex index of refraction: a near-white metal that `specular` tints, for the
// formats that describe a metal by its colour alone (MTL, glTF, pbrt's "reflectance").
inline const Rgb kTintableEta{1.66f, 0.88f, 0.52f}, kTintableK{9.22f, 6.27f, 4.84f};

const char* material_type_name(MaterialType t);

}  // namespace rll
