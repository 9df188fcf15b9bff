#include "rll/scene/scene.h"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>

#include "rll/core/error.h"
#include "rll/core/hash.h"
#include "rll/scene/interaction.h"
#include "rll/scene/textured_emitters.h"

namespace rll {

Vec3 equal_area_square_to_sphere(Vec2 p) {
  const float u = 2 * p.x - 1, v = 2 * p.y - 1, au = std::abs(u), av = std::abs(v);
  const float signed_distance = 1 - (au + av), r = 1 - std::abs(signed_distance);
  const float phi = (r == 0 ? 1 : (av - au) / r + 1) * (kPi / 4);
  const float z = std::copysign(1 - r * r, signed_distance);
  const float cos_phi = std::copysign(std::cos(phi), u), sin_phi = std::copysign(std::sin(phi), v);
  const float s = r * safe_sqrt(2 - r * r);
  return Vec3(cos_phi * s, sin_phi * s, z);
}

Rgb EnvironmentMap::lookup(const Vec3& world_direction) const {
  const float(&m)[3][3] = world_to_map;
  const Vec3& w = world_direction;
  Vec3 d = normalize(Vec3(m[0][0] * w.x + m[0][1] * w.y + m[0][2] * w.z,
                          m[1][0] * w.x + m[1][1] * w.y + m[1][2] * w.z,
                          m[2][0] * w.x + m[2][1] * w.y + m[2][2] * w.z));
  float u = 0, v = 0;  // image coordinates in [0, 1], v down the image
  if (mapping == Mapping::Equirect) {
    float phi = std::atan2(d.y, d.x);
    u = (phi < 0 ? phi + 2 * kPi : phi) / (2 * kPi);
    v = safe_acos(d.z) / kPi;
  } else {
    const Vec2 p = equal_area_sphere_to_square(d);
    u = p.x;
    v = p.y;
  }
  // sample_texture reads v up the image.
  return sample_texture(image, Vec2{u, 1 - v});
}

const char* material_type_name(MaterialType t) {
  switch (t) {
    case MaterialType::Diffuse: return "diffuse";
    case MaterialType::Conductor: return "conductor";
    case MaterialType::Plastic: return "plastic";
    case MaterialType::Dielectric: return "dielectric";
    case MaterialType::ThinDielectric: return "thindielectric";
    case MaterialType::CoatedDiffuse: return "coateddiffuse";
  }
  return "?";
}

void Mesh::append(const Mesh& o, uint32_t material_offset) {
  uint32_t base = uint32_t(positions.size());
  // Keep the per-vertex arrays either empty or full: pad with "none" where one side lacks them.
  if (!o.normals.empty() && normals.empty() && !positions.empty()) normals.assign(positions.size(), Vec3(0));
  if (!o.uvs.empty() && uvs.empty() && !positions.empty()) uvs.assign(positions.size(), Vec2{});
  positions.insert(positions.end(), o.positions.begin(), o.positions.end());
  if (!o.normals.empty()) normals.insert(normals.end(), o.normals.begin(), o.normals.end());
  else if (!normals.empty()) normals.resize(positions.size(), Vec3(0));
  if (!o.uvs.empty()) uvs.insert(uvs.end(), o.uvs.begin(), o.uvs.end());
  else if (!uvs.empty()) uvs.resize(positions.size(), Vec2{});
  for (const auto& t : o.triangles) triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  for (uint32_t m : o.material) material.push_back(m + material_offset);
  light.insert(light.end(), o.light.begin(), o.light.end());
  light.resize(triangles.size(), -1);
}

void add_sky_dome(Scene& scene, const SkyDome& sky, const Vec3& center, float radius) {
  if (!(sky.radius_scale > 2)) fail("{}: sky radius scale must be greater than 2", scene.source);
  if (sky.triangles < (sky.full_sphere ? 8 : 4) || (sky.full_sphere && sky.triangles % 2 != 0))
    fail("{}: sky.triangles must be at least 4 (a full sphere: even and at least 8; got {})",
         scene.source, sky.triangles);
  // Rings of vertices at polar angles theta_i = i * (pi/2) / R around the zenith; ring i has
  // s_i vertices, and the strip between rings i and i+1 holds s_i + s_{i+1} triangles, the
  // polar fan s_1. Total = 2 * sum(s_i) - s_R, so any count >= 4 is reachable with s_i
  // roughly proportional to sin(theta_i), giving triangles of similar solid angle.
  const int n = sky.full_sphere ? sky.triangles / 2 : sky.triangles;  // per hemisphere
  int rings = std::max(1, int(std::round(std::sqrt(n / kPi))));
  // Rings have at least 3 vertices each, so R rings make at least 6R - 3 triangles.
  rings = std::max(1, std::min(rings, (n + 3) / 6));
  std::vector<int> s(rings + 1, 0);
  auto total = [&] {
    int t = 0;
    for (int i = 1; i <= rings; ++i) t += 2 * s[i];
    return t - s[rings];
  };
  double wsum = 0;
  for (int i = 1; i <= rings; ++i) wsum += std::sin((i - 0.5) * (kPi / 2) / rings);
  for (int i = 1; i <= rings; ++i) {
    double w = std::sin((i - 0.5) * (kPi / 2) / rings) / wsum;
    s[i] = std::max(3, int(std::round(w * n / 2.0)));
  }
  // Adjust: a vertex on the outermost ring changes the total by 1, on an inner ring by 2.
  for (int guard = 0; total() != n && guard < 1000000; ++guard) {
    int diff = n - total();
    int i = rings;
    if (std::abs(diff) >= 2 && rings > 1) {
      i = 1;  // the inner ring whose change keeps the rings closest to proportional
      for (int k = 2; k < rings; ++k)
        if (diff > 0 ? s[k] < s[i] * 0.999 : s[k] > s[i]) i = k;
    }
    if (diff > 0) s[i] += 1;
    else if (s[i] > 3) s[i] -= 1;
    else break;
  }
  if (total() != n) fail("{}: cannot triangulate a sky dome with {} triangles", scene.source, n);

  Frame frame(normalize(sky.up));
  Mesh dome;
  dome.positions.push_back(center + frame.n * radius);  // zenith
  std::vector<uint32_t> ring_start(rings + 1, 0);
  for (int i = 1; i <= rings; ++i) {
    ring_start[i] = uint32_t(dome.positions.size());
    float theta = i * (kPi / 2) / rings;
    float offset = (i % 2) * 0.5f;  // stagger rings for better-shaped triangles
    for (int j = 0; j < s[i]; ++j) {
      float phi = 2 * kPi * (j + offset) / s[i];
      Vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      dome.positions.push_back(center + frame.to_world(d) * radius);
    }
  }
  // Triangles wound so that their normal points inwards (towards the centre).
  auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
    Vec3 nrm = cross(dome.positions[b] - dome.positions[a], dome.positions[c] - dome.positions[a]);
    Vec3 mid = (dome.positions[a] + dome.positions[b] + dome.positions[c]) / 3.0f;
    if (dot(nrm, center - mid) < 0) std::swap(b, c);
    dome.triangles.push_back({a, b, c});
  };
  for (int j = 0; j < s[1]; ++j) add(0, ring_start[1] + j, ring_start[1] + (j + 1) % s[1]);
  for (int i = 1; i < rings; ++i) {
    // Merge-walk two rings by angle: each step advances one of them, emitting one triangle.
    int a = 0, b = 0, na = s[i], nb = s[i + 1];
    float oa = (i % 2) * 0.5f, ob = ((i + 1) % 2) * 0.5f;
    while (a < na || b < nb) {
      float next_a = (a + 1 + oa) / na, next_b = (b + 1 + ob) / nb;
      uint32_t va = ring_start[i] + a % na, vb = ring_start[i + 1] + b % nb;
      if (b >= nb || (a < na && next_a < next_b)) {
        add(va, ring_start[i] + (a + 1) % na, vb);
        ++a;
      } else {
        add(va, ring_start[i + 1] + (b + 1) % nb, vb);
        ++b;
      }
    }
  }
  if (sky.full_sphere) {
    // The lower hemisphere mirrors the upper one through the equator, whose ring it shares so
    // that the sphere is closed.
    const uint32_t equator = ring_start[rings], upper_vertices = uint32_t(dome.positions.size());
    std::vector<uint32_t> mirror(upper_vertices);
    for (uint32_t v = 0; v < upper_vertices; ++v) {
      if (v >= equator) {
        mirror[v] = v;
        continue;
      }
      const Vec3 d = dome.positions[v] - center;
      mirror[v] = uint32_t(dome.positions.size());
      dome.positions.push_back(center + d - frame.n * (2 * dot(d, frame.n)));
    }
    const size_t upper_triangles = dome.triangles.size();
    for (size_t t = 0; t < upper_triangles; ++t) {
      const auto tri = dome.triangles[t];
      add(mirror[tri[0]], mirror[tri[1]], mirror[tri[2]]);
    }
  }
  Material m;
  m.name = "sky";
  m.albedo = Rgb(0);
  m.emission = sky.radiance;
  uint32_t mat = uint32_t(scene.materials.size());
  if (sky.map) {
    // One material per triangle, emitting the map's mean over the triangle's solid angle:
    // stratified points on the flat triangle, each weighted by the solid angle per unit area
    // it covers, cos / r^2.
    const int grid = 8;
    for (size_t t = 0; t < dome.triangles.size(); ++t) {
      const auto& tri = dome.triangles[t];
      const Vec3 a = dome.positions[tri[0]] - center, b = dome.positions[tri[1]] - center,
                 c = dome.positions[tri[2]] - center;
      const Vec3 nrm = normalize(cross(b - a, c - a));
      Rgb sum(0);
      float weight = 0;
      for (int i = 0; i < grid; ++i)
        for (int j = 0; j < grid; ++j) {
          float u = (i + 0.5f) / grid, v = (j + 0.5f) / grid;
          if (u + v > 1) {
            u = 1 - u;
            v = 1 - v;
          }
          const Vec3 p = a + (b - a) * u + (c - a) * v;
          const float r2 = length_sq(p), w = std::abs(dot(nrm, p)) / (r2 * std::sqrt(r2));
          sum += sky.map->lookup(p) * w;
          weight += w;
        }
      Material tm = m;
      tm.name = fmt::format("sky {}", t);
      tm.emission = sky.radiance * (sum / weight);
      scene.materials.push_back(tm);
      dome.material.push_back(uint32_t(t));
    }
  } else {
    scene.materials.push_back(m);
    dome.material.assign(dome.triangles.size(), 0);
  }
  dome.light.assign(dome.triangles.size(), -1);
  scene.sky_first_triangle = scene.mesh.triangle_count();
  scene.sky_triangle_count = dome.triangles.size();
  scene.mesh.append(dome, mat);
}

void Scene::finalize() {
  if (width <= 0 || height <= 0)
    fail("{}: film resolution must be positive (got {}x{})", source, width, height);
  if (size_t(width) * size_t(height) > (size_t(1) << 28))
    fail("{}: film resolution {}x{} is too large", source, width, height);
  const size_t nv = mesh.positions.size();
  for (size_t i = 0; i < nv; ++i)
    if (!is_finite(mesh.positions[i]))
      fail("{}: vertex {} has a non-finite coordinate ({}, {}, {})", source, i, mesh.positions[i].x,
           mesh.positions[i].y, mesh.positions[i].z);
  if (!mesh.normals.empty() && mesh.normals.size() != nv) fail("{}: normal count != vertex count", source);
  if (!mesh.uvs.empty() && mesh.uvs.size() != nv) fail("{}: uv count != vertex count", source);
  for (auto& nrm : mesh.normals)
    if (!is_finite(nrm)) nrm = Vec3(0);  // an unusable shading normal falls back to geometry
  if (mesh.material.size() != mesh.triangles.size())
    fail("{}: {} triangles but {} material ids", source, mesh.triangles.size(), mesh.material.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (uint32_t v : mesh.triangles[t])
      if (v >= nv) fail("{}: triangle {} uses vertex {} but there are only {}", source, t, v, nv);
    if (mesh.material[t] >= materials.size())
      fail("{}: triangle {} uses material {} but there are only {}", source, t, mesh.material[t], materials.size());
  }
  for (const auto& m : materials)
    if (m.albedo_texture >= int(textures.size()))
      fail("{}: material '{}' uses a texture that was not loaded", source, m.name);
  for (const auto& m : materials)
    if (m.emission_texture >= int(textures.size()))
      fail("{}: material '{}' uses an emission texture that was not loaded", source, m.name);
  for (const auto& m : materials)
    if (m.emission_texture >= 0 && m.is_emissive())
      if (const std::string bad = bad_emission_texel(textures[size_t(m.emission_texture)]);
          !bad.empty())
        fail(
            "{}: material '{}': its emission texture has a texel no light can emit: {} (texels "
            "must be finite and not negative)",
            source, m.name, bad);
  if (sky && sky->map)
    if (const std::string bad = bad_emission_texel(sky->map->image); !bad.empty())
      fail(
          "{}: the sky's environment map has a texel no light can emit: {} (texels must be "
          "finite and not negative)",
          source, bad);
  for (const auto& m : materials)
    if (m.roughness_texture >= int(textures.size()))
      fail("{}: material '{}' uses a roughness texture that was not loaded", source, m.name);
  for (size_t i = 0; i < lights.size(); ++i)
    if (const std::string why = light_parameter_problem(lights[i]); !why.empty())
      fail(
          "{}: light {} of {} (a {} light): {}; a light's parameters must be finite and its "
          "emission not negative",
          source, i, lights.size(), light_type_name(lights[i].type), why);
  for (const auto& l : lights)
    if (l.has_image() && l.triangle >= textures.size())
      fail("{}: an image light's image was not loaded", source);

  bounds = Bounds3{};
  if (sky_triangle_count == 0) {
    for (const auto& p : mesh.positions) bounds.expand(p);
  } else {  // finalized before: the dome is in the mesh but stays out of the bounds
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
      if (!is_sky_triangle(t))
        for (uint32_t v : mesh.triangles[t]) bounds.expand(mesh.positions[v]);
  }
  for (const auto& l : lights)
    if (l.type == LightType::Point || l.type == LightType::Spot) bounds.expand(l.p0);
  if (bounds.empty()) bounds.expand(Vec3(0));
  radius = std::max(1e-3f, 0.5f * length(bounds.diagonal()));

  if (sky && sky_triangle_count == 0) add_sky_dome(*this, *sky, bounds.center(), radius * sky->radius_scale);

  // Textured emitters: split where large, and each triangle's exact mean emission.
  const std::vector<Rgb> texture_means = prepare_textured_emitters(*this);
  mesh.light.assign(mesh.triangles.size(), -1);
  // Drop triangle lights from an earlier finalize() (finalize is idempotent).
  std::erase_if(lights, [](const Light& l) { return l.type == LightType::Triangle; });
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const Material& m = materials[mesh.material[t]];
    if (!m.is_emissive()) continue;
    if (mesh.area(t) <= 0) continue;  // degenerate: emits nothing, cannot be sampled
    const bool textured = m.emission_texture >= 0;
    // A textured triangle is a light of its mean emission (its power and bounds), and none
    // where the texture is black all over it.
    const Rgb radiance = textured ? m.emission * texture_means[t] : m.emission;
    if (textured && !(max_component(radiance) > 0)) continue;
    mesh.light[t] = int32_t(lights.size());
    lights.push_back(make_triangle_light(mesh.vertex(t, 0), mesh.vertex(t, 1), mesh.vertex(t, 2),
                                         radiance, m.two_sided_emission, t));
    lights.back().textured = textured;
  }
  // Before the lights: a mesh scaled to nothing has lost its emitters too, and is the cause.
  size_t surfaces = 0, visible = 0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (is_sky_triangle(t)) continue;
    ++surfaces;
    if (mesh.area(uint32_t(t)) > 0) ++visible;
  }
  if (surfaces > 0 && visible == 0)
    fail("{}: all {} triangles have zero area (is the geometry scaled to nothing?)", source,
         surfaces);
  // A sky is a light only where it emits: say so rather than that there is no sky.
  if (lights.empty() && sky)
    fail(
        "{}: the scene has no lights: it has a sky (an infinite light or environment), but {}, "
        "and nothing else emits; give the sky a positive radiance or add a light",
        source,
        sky->map && max_component(sky->radiance) > 0
            ? "its map is black over the dome"
            : fmt::format("the sky's radiance is ({}, {}, {})", sky->radiance.x, sky->radiance.y,
                          sky->radiance.z));
  if (lights.empty())
    fail("{}: the scene has no lights (no emissive material, light source or sky)", source);
  // A light of zero intensity or irradiance renders as black as no light at all, and is refused
  // the same way as a zero emission (which makes no light above). A scene whose every light is
  // enclosed by geometry renders black too, but telling that needs the visibility this check
  // cannot afford; it is not detected.
  if (std::none_of(lights.begin(), lights.end(),
                   [](const Light& l) { return max_component(l.radiance) > 0; }))
    fail("{}: the scene has no lights: its {} light {} nothing (zero intensity or irradiance)",
         source, lights.size(), lights.size() == 1 ? "source emits" : "sources emit");
  // Without geometry or a sky, point and directional lights have nothing to light; a warning,
  // as a scene made in code may hold lights alone on purpose.
  if (surfaces == 0 && !sky) {
    std::string w = fmt::format("{}: the scene has no geometry and no sky: it renders black", source);
    if (std::find(warnings.begin(), warnings.end(), w) == warnings.end())  // finalized twice
      warnings.push_back(std::move(w));
  }

  if (!has_camera) {
    Vec3 c = bounds.center();
    camera.target = c;
    camera.up = Vec3(0, 1, 0);
    camera.fov = 45;
    float dist = radius / std::tan(radians(camera.fov) * 0.5f) * 1.1f;
    camera.position = c + Vec3(0, 0, 1) * dist;
    has_camera = true;
  }
  if (!is_finite(camera.position) || !is_finite(camera.target) || length_sq(camera.target - camera.position) <= 0)
    fail("{}: camera position and target must be finite and distinct", source);
  if (length_sq(cross(camera.target - camera.position, camera.up)) <= 0)
    fail("{}: camera 'up' must not be parallel to the viewing direction", source);
  if (!(camera.fov > 0 && camera.fov < 180)) fail("{}: camera fov must be in (0, 180) degrees", source);
  camera.setup(width, height);
}

void Scene::reorder_lights(const std::vector<uint32_t>& order) {
  std::vector<Light> reordered(order.size());
  for (size_t i = 0; i < order.size(); ++i) reordered[i] = lights[order[i]];
  lights = std::move(reordered);
  for (auto& l : mesh.light) l = -1;
  for (size_t i = 0; i < lights.size(); ++i)
    if (lights[i].type == LightType::Triangle) mesh.light[lights[i].triangle] = int32_t(i);
}

void Scene::refresh_lights_from_mesh() {
  for (auto& l : lights) {
    if (l.type != LightType::Triangle) continue;
    l.p0 = mesh.vertex(l.triangle, 0);
    l.p1 = mesh.vertex(l.triangle, 1);
    l.p2 = mesh.vertex(l.triangle, 2);
    // A textured light's mean emission depends on its uvs, which do not move.
    if (!l.textured) l.radiance = materials[mesh.material[l.triangle]].emission;
    refresh_triangle_light(l);
  }
}

static_assert(sizeof(Vec3) == 12 && sizeof(Vec2) == 8, "hashed as packed floats");

uint64_t Scene::fingerprint() const {
  const Scene& s = *this;
  Hasher h;
  h.vector(s.mesh.positions);
  h.vector(s.mesh.normals);
  h.vector(s.mesh.uvs);
  h.vector(s.mesh.triangles);
  h.vector(s.mesh.material);
  h.vector(s.mesh.light);
  h.word(s.materials.size());
  for (const Material& m : s.materials) {
    h.word(uint64_t(m.type));
    h.add(m.albedo);
    h.add(int64_t(m.albedo_texture));
    h.add(m.specular);
    h.add(m.eta);
    h.add(m.k);
    h.add(m.ior);
    h.add(m.roughness);
    h.add(m.emission);
    h.word(m.two_sided_emission);
    // Fields added after the cache's first entries enter only where set, so that the key of a
    // scene without them (every scene then) stays what it was.
    if (m.roughness_texture >= 0 || m.thickness != 0.01f) {
      h.add(int64_t(m.roughness_texture));
      h.add(m.thickness);
    }
    if (m.emission_texture >= 0) h.add(int64_t(m.emission_texture) + 0x7e47);
  }
  h.word(s.textures.size());
  for (const Image& t : s.textures) {
    h.add(int64_t(t.width()));
    h.add(int64_t(t.height()));
    h.vector(t.pixels());
  }
  h.word(s.lights.size());
  for (const Light& l : s.lights) {
    h.word(uint64_t(l.type));
    h.add(l.p0);
    h.add(l.p1);
    h.add(l.p2);
    h.add(l.n);
    h.add(l.area);
    h.add(l.radiance);
    h.word(l.two_sided);
    h.word(l.triangle);
  }
  h.add(s.camera.position);
  h.add(s.camera.target);
  h.add(s.camera.up);
  h.add(s.camera.fov);
  // As the material fields above: a thin lens or a screen window enter only where set.
  if (s.camera.has_lens() || s.camera.screen_window != std::array<float, 4>{0, 0, 0, 0}) {
    h.add(s.camera.lens_radius);
    h.add(s.camera.focal_distance);
    for (float v : s.camera.screen_window) h.add(v);
  }
  h.add(int64_t(s.width));
  h.add(int64_t(s.height));
  h.word(s.sky.has_value());
  if (s.sky) {
    h.add(int64_t(s.sky->triangles));
    h.add(s.sky->radiance);
    h.add(s.sky->up);
    h.add(s.sky->radius_scale);
  }
  return h.value();
}

}  // namespace rll
