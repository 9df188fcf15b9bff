#include "rll/scene/builder.h"

#include <algorithm>
#include <map>

namespace rll {

uint32_t SceneBuilder::material(const Material& m) {
  m_scene.materials.push_back(m);
  return uint32_t(m_scene.materials.size() - 1);
}

uint32_t SceneBuilder::diffuse(const Rgb& albedo, const std::string& name) {
  Material m;
  m.name = name;
  m.albedo = albedo;
  return material(m);
}

uint32_t SceneBuilder::emitter(const Rgb& radiance, bool two_sided, const std::string& name) {
  Material m;
  m.name = name;
  m.albedo = Rgb(0);
  m.emission = radiance;
  m.two_sided_emission = two_sided;
  return material(m);
}

uint32_t SceneBuilder::vertex(const Vec3& p, const Vec3& n) {
  Mesh& mesh = m_scene.mesh;
  mesh.positions.push_back(p);
  if (!mesh.normals.empty() || n != Vec3(0)) {
    mesh.normals.resize(mesh.positions.size() - 1, Vec3(0));
    mesh.normals.push_back(n);
  }
  if (!mesh.uvs.empty()) mesh.uvs.push_back({});
  return uint32_t(mesh.positions.size() - 1);
}

void SceneBuilder::triangle(const Vec3& a, const Vec3& b, const Vec3& c, uint32_t material) {
  Mesh& mesh = m_scene.mesh;
  uint32_t i = vertex(a), j = vertex(b), k = vertex(c);
  mesh.triangles.push_back({i, j, k});
  mesh.material.push_back(material);
  mesh.light.push_back(-1);
}

void SceneBuilder::quad(const Vec3& p, const Vec3& e1, const Vec3& e2, uint32_t material) {
  Mesh& mesh = m_scene.mesh;
  uint32_t a = vertex(p), b = vertex(p + e1), c = vertex(p + e1 + e2), d = vertex(p + e2);
  bool has_uv = !mesh.uvs.empty();
  if (has_uv) {
    mesh.uvs[a] = {0, 0};
    mesh.uvs[b] = {1, 0};
    mesh.uvs[c] = {1, 1};
    mesh.uvs[d] = {0, 1};
  }
  mesh.triangles.push_back({a, b, c});
  mesh.triangles.push_back({a, c, d});
  mesh.material.insert(mesh.material.end(), 2, material);
  mesh.light.insert(mesh.light.end(), 2, -1);
}

void SceneBuilder::box(const Vec3& lo, const Vec3& hi, uint32_t material, bool inward, unsigned skip) {
  Vec3 d = hi - lo;
  // Each face as (origin, e1, e2) with e1 x e2 pointing outwards.
  struct Face {
    Vec3 p, e1, e2;
  };
  Face faces[6] = {
      {lo, Vec3(0, 0, d.z), Vec3(0, d.y, 0)},                        // -x
      {Vec3(hi.x, lo.y, lo.z), Vec3(0, d.y, 0), Vec3(0, 0, d.z)},    // +x
      {lo, Vec3(d.x, 0, 0), Vec3(0, 0, d.z)},                        // -y
      {Vec3(lo.x, hi.y, lo.z), Vec3(0, 0, d.z), Vec3(d.x, 0, 0)},    // +y
      {lo, Vec3(0, d.y, 0), Vec3(d.x, 0, 0)},                        // -z
      {Vec3(lo.x, lo.y, hi.z), Vec3(d.x, 0, 0), Vec3(0, d.y, 0)},    // +z
  };
  for (int f = 0; f < 6; ++f) {
    if (skip & (1u << f)) continue;
    if (inward) quad(faces[f].p, faces[f].e2, faces[f].e1, material);
    else quad(faces[f].p, faces[f].e1, faces[f].e2, material);
  }
}

void SceneBuilder::wall_with_holes(int axis, float offset, float u0, float v0, float u1, float v1,
                                   const std::vector<Hole>& holes, bool normal_positive, uint32_t material) {
  // Split the rectangle along u and v at every hole edge; emit the grid cells not inside a hole.
  std::vector<float> us = {u0, u1}, vs = {v0, v1};
  for (const auto& h : holes) {
    us.push_back(std::clamp(h.u0, u0, u1));
    us.push_back(std::clamp(h.u1, u0, u1));
    vs.push_back(std::clamp(h.v0, v0, v1));
    vs.push_back(std::clamp(h.v1, v0, v1));
  }
  auto uniq = [](std::vector<float>& x) {
    std::sort(x.begin(), x.end());
    x.erase(std::unique(x.begin(), x.end()), x.end());
  };
  uniq(us);
  uniq(vs);
  const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
  auto point = [&](float u, float v) {
    Vec3 p;
    p[axis] = offset;
    p[ua] = u;
    p[va] = v;
    return p;
  };
  for (size_t i = 0; i + 1 < us.size(); ++i)
    for (size_t j = 0; j + 1 < vs.size(); ++j) {
      float cu = 0.5f * (us[i] + us[i + 1]), cv = 0.5f * (vs[j] + vs[j + 1]);
      bool in_hole = std::any_of(holes.begin(), holes.end(), [&](const Hole& h) {
        return cu > h.u0 && cu < h.u1 && cv > h.v0 && cv < h.v1;
      });
      if (in_hole) continue;
      Vec3 p = point(us[i], vs[j]);
      Vec3 e1 = point(us[i + 1], vs[j]) - p, e2 = point(us[i], vs[j + 1]) - p;
      // e1 x e2 points along +axis for the cyclic (axis, ua, va) order.
      if (normal_positive) quad(p, e1, e2, material);
      else quad(p, e2, e1, material);
    }
}

void SceneBuilder::sphere(const Vec3& center, float radius, int subdivisions, uint32_t material, bool inward,
                          bool smooth) {
  const float t = (1 + std::sqrt(5.0f)) / 2;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p = normalize(p);
  std::vector<std::array<uint32_t, 3>> f = {
      {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
      {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(normalize(v[a] + v[b]));
      return mid[key] = uint32_t(v.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> g;
    for (auto& tri : f) {
      uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f = std::move(g);
  }
  Mesh& mesh = m_scene.mesh;
  uint32_t base = uint32_t(mesh.positions.size());
  for (const auto& p : v) vertex(center + p * radius, smooth ? (inward ? -p : p) : Vec3(0));
  for (auto tri : f) {
    if (inward) std::swap(tri[1], tri[2]);
    mesh.triangles.push_back({base + tri[0], base + tri[1], base + tri[2]});
    mesh.material.push_back(material);
    mesh.light.push_back(-1);
  }
}

}  // namespace rll
