// Emissive triangles whose material has an emission texture: the texture integrated over a
// triangle exactly (the power, light-tree bounds and priors of its light come from it), and the
// splitting of large textured emitters into lights of nearly equal power (docs/scene-format.md,
// "Textured emitters").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rll/core/image.h"
#include "rll/core/math.h"

namespace rll {

struct Scene;

// The integral of a texture's bilinear reconstruction, exactly as sample_texture (scene_view.h)
// reads it (texel centres at half-integer texel coordinates, repeat wrapping, v up the image),
// over the triangle with texture coordinates uv[0..2].
struct TextureIntegral {
  std::array<double, 3> sum{};  // the integral per channel, over uv space (units of uv area)
  double uv_area = 0;           // the triangle's area in uv space
  // False where the uvs are (nearly) collinear or the triangle covers more texel cells than
  // max_cells: the mean then comes from 64 x 64 stratified points (a warning says so).
  bool exact = true;
  // The mean of the reconstruction over the triangle.
  Rgb mean() const;
};

// Cells of the reconstruction (the squares between four texel centres) one triangle may cover
// before its integral falls back to point samples: 2^26, a 8192^2 texture covered once.
inline constexpr size_t kMaxExactTextureCells = size_t(1) << 26;
// Cells all the exact integrations of one scene's load (its triangles, the cheapest first, then
// the pieces they are split into) may cover together, by exact_integration_cost, before the rest
// fall back to point samples: 2^26 too, a few seconds of work. Integrations of at most
// kAlwaysExactTextureCells, no dearer than the points, are exact whatever is left: the small
// pieces a split ends with (the lights) stay exact where only its larger, passing pieces were not.
inline constexpr size_t kMaxExactTextureCellsPerLoad = size_t(1) << 26;
inline constexpr size_t kAlwaysExactTextureCells = 4096;

// Where the estimate of the cells the exact integration would visit (exact_integration_cost)
// exceeds max_cells, the integral comes from points at once (exact = false).
TextureIntegral integrate_texture(const TexelView& tex, const std::array<Vec2, 3>& uv,
                                  size_t max_cells = kMaxExactTextureCells);
// The same over a triangle given in double-precision uvs (the splitter's pieces).
TextureIntegral integrate_texture(const TexelView& tex, const std::array<std::array<double, 2>, 3>& uv,
                                  size_t max_cells = kMaxExactTextureCells);
// About how many cells integrate_texture's exact integration visits over the triangle (its
// area in texels, the rows' ends), known before it runs (infinity where the uvs overflow).
double exact_integration_cost(const TexelView& tex, const std::array<Vec2, 3>& uv);
double exact_integration_cost(const TexelView& tex, const std::array<std::array<double, 2>, 3>& uv);

// The texture coordinates of mesh triangle `tri`'s vertices, as make_surface_hit reads them
// (its barycentrics (0, 0), (1, 0), (0, 1) where the mesh has no uvs).
std::array<Vec2, 3> triangle_uvs(const Scene& scene, uint32_t tri);

// How many lights, at most, the textured emitters of a scene are split into (beyond one per
// triangle), and how many one triangle may become.
inline constexpr size_t kTexturedEmitterLights = 16384;
inline constexpr size_t kMaxPiecesPerTriangle = 4096;

// Splits the large textured emissive triangles of `scene` (a mesh with uvs) into pieces of
// nearly equal power (appended to the mesh: each piece is a triangle of its own, with
// interpolated positions, normals and uvs), and returns the mean emission texture value of every
// mesh triangle (empty when no material has an emission texture; black for the others).
// Called by Scene::finalize; splits only once (Scene::textured_emitters_split).
std::vector<Rgb> prepare_textured_emitters(Scene& scene);

}  // namespace rll
