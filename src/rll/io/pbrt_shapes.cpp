// The pbrt reader's shapes (see pbrt_internal.h).
#include <array>
#include <cctype>

#include "rll/io/pbrt_internal.h"
#include "rll/scene/subdivide.h"

namespace rll::pbrt {

// The material of the next shape, with the active area light's emission times `k`.
uint32_t PbrtReader::shape_material(const Token& t, float k) {
  int base = m_state.material;
  if (base == -1) {
    if (m_default_material < 0) {
      Material m;
      m.name = "default";
      m.albedo = Rgb(0.5f);
      m_scene.materials.push_back(m);
      m_default_material = int(m_scene.materials.size() - 1);
    }
    base = m_default_material;
  }
  if (!m_state.emissive) return uint32_t(base);
  const Rgb e = m_state.emission * k;
  if (!is_finite(e))
    syntax(t, fmt::format("the area light's emission ({}, {}, {}) x {} (its \"power\" over the "
                          "shape's area) is not finite: the power is too large or the shape too "
                          "small",
                          m_state.emission.x, m_state.emission.y, m_state.emission.z, k));
  auto key = std::make_tuple(base, e.x, e.y, e.z, m_state.two_sided, m_state.emission_texture);
  auto it = m_emissive.find(key);
  if (it != m_emissive.end()) return it->second;
  if (m_emissive.size() >= kMaxEmissiveMaterials)
    fail("{}: more than {} different emissive materials (area lights normalized to a \"power\" "
         "give each triangle of a mesh of unequal triangles its own emission, as pbrt-v4 does)",
         m_names[0], kMaxEmissiveMaterials);
  Material m = m_scene.materials[size_t(base)];
  m.emission = e;
  m.emission_texture = m_state.emission_texture;
  m.two_sided_emission = m_state.two_sided;
  m.name += " (emitting)";
  m_scene.materials.push_back(m);
  return m_emissive[key] = uint32_t(m_scene.materials.size() - 1);
}

void PbrtReader::shape(const Token& t) {
  std::string type = expect_string(t);
  Params p(*this, t, fmt::format("Shape \"{}\"", type));
  Mesh mesh;
  m_shape_of_triangle.clear();
  bool quadric = false;  // pbrt orients quadrics by their parametrization, meshes by N
  if (type == "trianglemesh") {
    triangle_mesh(t, p, mesh);
  } else if (type == "plymesh") {
    auto file = p.get_string("filename");
    if (!file) syntax(t, "Shape \"plymesh\" needs a \"string filename\"");
    const fs::path path = referenced_file(t, "Shape \"plymesh\"", *file);
    try {
      mesh = read_ply_file(path);  // gzip-compressed (.ply.gz) or not
    } catch (const Error& e) {
      fail("{}: Shape \"plymesh\": {}", where(t), e.what());
    }
    for (const char* name : {"displacement", "edgelength"})
      if (p.find(name)) unsupported(t, "Shape \"plymesh\" displacement");
  } else if (type == "loopsubdiv") {
    loop_subdivision(t, p, mesh);
  } else if (type == "bilinearmesh") {
    bilinear_mesh(t, p, mesh);
  } else if (type == "sphere") {
    sphere(t, p, mesh);
    quadric = true;
  } else if (type == "disk") {
    disk(t, p, mesh);
    quadric = true;
  } else {
    unsupported(t, fmt::format("Shape \"{}\"", type));
    ++m_skipped_shapes[type];
    return;
  }
  for (const char* name : {"alpha", "emission"})
    if (p.find(name)) unsupported(t, fmt::format("Shape parameter \"{}\"", name));
  p.warn_unused();
  if (m_state.material == kInvisible) {
    ++m_skipped_shapes[type + " under an interface material"];
    return;
  }
  add_mesh(t, std::move(mesh), quadric);
}

void PbrtReader::add_mesh(const Token& t, Mesh mesh, bool quadric) {
  if (const std::string why = transform_problem(m_state.ctm); !why.empty())
    syntax(t, "Shape: " + why);
  const Affine x = to_affine(m_state.ctm);
  transform_mesh(mesh, x, 0, 0);
  const bool swaps = x.det() < 0;
  if (quadric ? (m_state.reverse_orientation != swaps) : m_state.reverse_orientation) {
    for (auto& tri : mesh.triangles) std::swap(tri[1], tri[2]);
    if (quadric)
      for (auto& n : mesh.normals) n = -n;
  }
  if (!quadric && !mesh.normals.empty()) {
    // pbrt's shading normals decide which side of a mesh triangle is its front.
    for (auto& tri : mesh.triangles) {
      const Vec3 n = mesh.normals[tri[0]] + mesh.normals[tri[1]] + mesh.normals[tri[2]];
      const Vec3 g = cross(mesh.positions[tri[1]] - mesh.positions[tri[0]],
                           mesh.positions[tri[2]] - mesh.positions[tri[0]]);
      if (dot(n, g) < 0) std::swap(tri[1], tri[2]);
    }
  }
  if (const std::string why =
          triangle_budget_problem(double(triangles_so_far() + mesh.triangle_count()), m_policy);
      !why.empty())
    syntax(t, why);
  mesh.light.assign(mesh.triangle_count(), -1);
  if (m_state.emissive && m_state.emission_texture >= 0 && mesh.uvs.empty())
    warn("image area light without uv",
         fmt::format("{}: a shape without \"uv\": its image area light is looked up at "
                     "each triangle's barycentrics (0,0), (1,0), (0,1), where pbrt-v4 uses (0,0), "
                     "(1,0), (1,1)",
                     where(t)));
  if (m_state.emissive && m_state.area_power > 0) {
    // pbrt-v4 normalizes each of its shapes to the power: a sphere or disk as a whole, each
    // triangle of a mesh on its own. k_e = pi A (x2 two-sided): the power of unit radiance.
    const double sides = m_state.two_sided ? 2.0 : 1.0;
    auto factor = [&](double area) {
      return area > 0 ? float(m_state.area_power /
                              (kPi * sides * area * double(m_state.texture_luminance)))
                      : 0.0f;
    };
    // pbrt-v4's shape of each triangle: the whole quadric, a bilinear patch, or itself.
    const uint32_t n = uint32_t(mesh.triangle_count());
    auto shape_of = [&](uint32_t i) {
      return quadric ? 0u : m_shape_of_triangle.size() == n ? m_shape_of_triangle[i] : i;
    };
    std::vector<double> area;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t k = shape_of(i);
      if (k >= area.size()) area.resize(k + 1, 0.0);
      area[k] += mesh.area(i);
    }
    mesh.material.resize(n);
    for (uint32_t i = 0; i < n; ++i)
      mesh.material[i] = shape_material(t, factor(area[shape_of(i)]));
  } else {
    mesh.material.assign(mesh.triangle_count(), shape_material(t));
  }
  m_scene.mesh.append(mesh, 0);
}

void PbrtReader::triangle_mesh(const Token& t, const Params& p, Mesh& mesh) {
  const auto* P = p.get_array("P", {"point3", "point"}, 3);
  if (!P || P->empty()) syntax(t, "Shape \"trianglemesh\" needs \"point3 P\"");
  const size_t nv = P->size() / 3;
  fill_vertices(t, p, mesh, *P, "trianglemesh");
  const auto* I = p.get_integers("indices", 3);
  if (!I) {
    if (nv != 3)
      syntax(t, fmt::format("Shape \"trianglemesh\": \"integer indices\" are needed unless there "
                            "are exactly 3 vertices (got {})",
                            nv));
    mesh.triangles.push_back({0, 1, 2});
    return;
  }
  mesh.triangles.reserve(I->size() / 3);
  for (size_t i = 0; i < I->size(); i += 3) {
    std::array<uint32_t, 3> tri;
    for (int k = 0; k < 3; ++k) tri[size_t(k)] = index(t, "trianglemesh", (*I)[i + size_t(k)], nv);
    mesh.triangles.push_back(tri);
  }
  for (const char* ignored : {"S", "faceIndices"}) p.find(ignored);
}

void PbrtReader::loop_subdivision(const Token& t, const Params& p, Mesh& mesh) {
  const auto* P = p.get_array("P", {"point3", "point"}, 3);
  if (!P || P->empty()) syntax(t, "Shape \"loopsubdiv\" needs \"point3 P\"");
  const auto* I = p.get_integers("indices", 3);
  if (!I || I->empty()) syntax(t, "Shape \"loopsubdiv\" needs \"integer indices\"");
  const int levels = p.get_int("levels", 3);
  if (levels < 0)
    syntax(t, fmt::format("Shape \"loopsubdiv\": levels must not be negative (got {})", levels));
  // Each level quadruples the triangles: 10 turn one triangle into a million, beyond any scene's
  // need, and the cap refuses a huge value before the triangle budget below is even consulted.
  constexpr int kMaxLevels = 10;
  if (levels > kMaxLevels)
    syntax(t, fmt::format("Shape \"loopsubdiv\": levels must be at most {} (got {})", kMaxLevels,
                          levels));
  const size_t nv = P->size() / 3;
  SubdivisionMesh sub;
  sub.positions.resize(nv);
  for (size_t i = 0; i < nv; ++i)
    sub.positions[i] = Vec3(float((*P)[3 * i]), float((*P)[3 * i + 1]), float((*P)[3 * i + 2]));
  for (size_t i = 0; i < I->size(); i += 3) {
    std::array<uint32_t, 3> tri;
    for (int k = 0; k < 3; ++k) tri[size_t(k)] = index(t, "loopsubdiv", (*I)[i + size_t(k)], nv);
    sub.triangles.push_back(tri);
  }
  // Each level multiplies the triangles by 4: refuse before allocating what would be refused.
  const double count = double(sub.triangles.size()) * std::pow(4.0, levels);
  if (const std::string why = triangle_budget_problem(double(triangles_so_far()) + count, m_policy);
      !why.empty())
    syntax(t, fmt::format("Shape \"loopsubdiv\": {} levels make {:.0f} triangles of {}: {}", levels,
                          count, sub.triangles.size(), why));
  try {
    loop_subdivide(sub, levels);
  } catch (const Error& e) {
    fail("{}: Shape \"loopsubdiv\": {}", where(t), e.what());
  }
  // pbrt-v4 ends at the limit surface, with its normals as shading normals.
  mesh.positions = std::move(sub.positions);
  mesh.normals = std::move(sub.normals);
  mesh.triangles = std::move(sub.triangles);
  for (const char* ignored : {"scheme"}) p.find(ignored);
}

uint32_t PbrtReader::index(const Token& t, const char* shape, int64_t v, size_t count) const {
  if (v < 0 || uint64_t(v) >= count)
    syntax(t, fmt::format("Shape \"{}\": index {} is out of range (there are {} vertices)", shape,
                          v, count));
  return uint32_t(v);
}

// P, and N and uv when given, which must have one entry per vertex.
void PbrtReader::fill_vertices(const Token& t, const Params& p, Mesh& mesh,
                               const std::vector<double>& P, const char* shape) {
  const size_t nv = P.size() / 3;
  mesh.positions.resize(nv);
  for (size_t i = 0; i < nv; ++i)
    mesh.positions[i] = Vec3(float(P[3 * i]), float(P[3 * i + 1]), float(P[3 * i + 2]));
  if (const auto* N = p.get_array("N", {"normal3", "normal"}, 3)) {
    if (N->size() != P.size())
      syntax(t, fmt::format("Shape \"{}\": {} normals for {} vertices", shape, N->size() / 3, nv));
    mesh.normals.resize(nv);
    for (size_t i = 0; i < nv; ++i)
      mesh.normals[i] = Vec3(float((*N)[3 * i]), float((*N)[3 * i + 1]), float((*N)[3 * i + 2]));
  }
  const std::vector<double>* uv = p.get_array("uv", {"point2", "float"}, 2);
  if (!uv) uv = p.get_array("st", {"point2", "float"}, 2);
  if (uv) {
    if (uv->size() / 2 != nv)
      syntax(t, fmt::format("Shape \"{}\": {} uvs for {} vertices", shape, uv->size() / 2, nv));
    mesh.uvs.resize(nv);
    for (size_t i = 0; i < nv; ++i)
      mesh.uvs[i] = Vec2{float((*uv)[2 * i]), float((*uv)[2 * i + 1])};
  }
}

void PbrtReader::bilinear_mesh(const Token& t, const Params& p, Mesh& mesh) {
  const auto* P = p.get_array("P", {"point3", "point"}, 3);
  if (!P || P->empty()) syntax(t, "Shape \"bilinearmesh\" needs \"point3 P\"");
  const size_t nv = P->size() / 3;
  Mesh corners;
  fill_vertices(t, p, corners, *P, "bilinearmesh");
  std::vector<int64_t> default_indices = {0, 1, 2, 3};
  const auto* I = p.get_integers("indices", 4);
  if (!I) {
    if (nv != 4)
      syntax(t, fmt::format("Shape \"bilinearmesh\": \"integer indices\" are needed unless there "
                            "are exactly 4 vertices (got {})",
                            nv));
    I = &default_indices;
  }
  const bool has_n = !corners.normals.empty(), has_uv = !corners.uvs.empty();
  for (size_t i = 0; i < I->size(); i += 4) {
    uint32_t v[4];
    for (int k = 0; k < 4; ++k) v[k] = index(t, "bilinearmesh", (*I)[i + size_t(k)], nv);
    // pbrt's patch: p(u, v) = lerp over p00 = v0, p10 = v1, p01 = v2, p11 = v3.
    const Vec3 p00 = corners.positions[v[0]], p10 = corners.positions[v[1]],
               p01 = corners.positions[v[2]], p11 = corners.positions[v[3]];
    const Vec3 e1 = p10 - p00, e2 = p01 - p00;
    const float size = std::max({length(e1), length(e2), length(p11 - p00), 1e-30f});
    const bool planar = std::abs(dot(p11 - p00, cross(e1, e2))) <= 1e-5f * size * size * size;
    const int n = planar ? 1 : kBilinearGrid;
    if (const std::string why = triangle_budget_problem(
            double(triangles_so_far() + mesh.triangle_count() + size_t(2 * n * n)), m_policy);
        !why.empty())
      syntax(t, fmt::format("Shape \"bilinearmesh\": {}", why));
    const uint32_t base = uint32_t(mesh.positions.size());
    auto bilerp = [](float u, float w, auto a, auto b, auto c, auto d) {
      return a * ((1 - u) * (1 - w)) + b * (u * (1 - w)) + c * ((1 - u) * w) + d * (u * w);
    };
    for (int j = 0; j <= n; ++j)
      for (int k = 0; k <= n; ++k) {
        const float u = float(k) / n, w = float(j) / n;
        mesh.positions.push_back(bilerp(u, w, p00, p10, p01, p11));
        if (has_n)
          mesh.normals.push_back(bilerp(u, w, corners.normals[v[0]], corners.normals[v[1]],
                                        corners.normals[v[2]], corners.normals[v[3]]));
        if (has_uv) {
          const Vec2 a = corners.uvs[v[0]], b = corners.uvs[v[1]], c = corners.uvs[v[2]],
                     d = corners.uvs[v[3]];
          mesh.uvs.push_back(
              Vec2{bilerp(u, w, a.x, b.x, c.x, d.x), bilerp(u, w, a.y, b.y, c.y, d.y)});
        } else {
          mesh.uvs.push_back(Vec2{u, w});  // pbrt's default (u, v) over the patch
        }
      }
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const uint32_t a = base + uint32_t(j * (n + 1) + k), b = a + 1, c = a + uint32_t(n + 1),
                       d = c + 1;
        // Front face along dp/du x dp/dv, as pbrt's patch normal.
        mesh.triangles.push_back({a, b, d});
        mesh.triangles.push_back({a, d, c});
        m_shape_of_triangle.insert(m_shape_of_triangle.end(), 2, uint32_t(i / 4));
      }
  }
  if (!has_n) mesh.normals.clear();
}

void PbrtReader::sphere(const Token& t, const Params& p, Mesh& mesh) {
  const float r = p.get_float("radius", 1);
  const float z0 = p.get_float("zmin", -r), z1 = p.get_float("zmax", r);
  const float phimax = p.get_float("phimax", 360);
  if (!(r > 0)) syntax(t, "Shape \"sphere\": radius must be positive");
  if (!(phimax > 0 && phimax <= 360)) syntax(t, "Shape \"sphere\": phimax must be in (0, 360]");
  const float zmin = clamp(std::min(z0, z1), -r, r), zmax = clamp(std::max(z0, z1), -r, r);
  const float th0 = std::acos(zmax / r), th1 = std::acos(zmin / r);
  if (!(th1 > th0)) syntax(t, "Shape \"sphere\": zmin and zmax leave nothing");
  const float phi_max = radians(phimax);
  const int segs = std::max(3, int(std::ceil(kSphereSegments * phimax / 360))),
            rings = std::max(1, int(std::ceil(kSphereRings * (th1 - th0) / kPi)));
  const bool full = phimax >= 360;
  const int cols = full ? segs : segs + 1;  // a full sphere shares its seam
  // Poles (when reached) are single vertices; rings in between have `cols` vertices.
  const bool top = th0 <= 0, bottom = th1 >= kPi;
  auto vertex = [&](float th, float ph) {
    const Vec3 n(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    mesh.positions.push_back(n * r);
    mesh.normals.push_back(n);
    mesh.uvs.push_back(Vec2{ph / phi_max, (th - th0) / (th1 - th0)});
  };
  std::vector<uint32_t> ring_start;
  for (int i = 0; i <= rings; ++i) {
    const float th = th0 + (th1 - th0) * float(i) / rings;
    ring_start.push_back(uint32_t(mesh.positions.size()));
    if ((i == 0 && top) || (i == rings && bottom)) {
      vertex(th, 0);
      continue;
    }
    for (int j = 0; j < cols; ++j) vertex(th, phi_max * float(j) / segs);
  }
  auto at = [&](int i, int j) {
    if ((i == 0 && top) || (i == rings && bottom)) return ring_start[size_t(i)];
    return ring_start[size_t(i)] + uint32_t(full ? j % segs : j);
  };
  // Wound outwards below, as pbrt's sphere faces (before ReverseOrientation).
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segs; ++j) {
      const uint32_t a = at(i, j), b = at(i, j + 1), c = at(i + 1, j), d = at(i + 1, j + 1);
      if (a != b) mesh.triangles.push_back({a, c, b});
      if (c != d) mesh.triangles.push_back({b, c, d});
    }
  orient_outward(mesh);
}

void PbrtReader::disk(const Token& t, const Params& p, Mesh& mesh) {
  const float r = p.get_float("radius", 1), ri = p.get_float("innerradius", 0),
              h = p.get_float("height", 0), phimax = p.get_float("phimax", 360);
  if (!(r > 0) || !(ri >= 0) || !(ri < r))
    syntax(t, "Shape \"disk\": needs 0 <= innerradius < radius");
  if (!(phimax > 0 && phimax <= 360)) syntax(t, "Shape \"disk\": phimax must be in (0, 360]");
  const float phi_max = radians(phimax);
  const int segs = std::max(3, int(std::ceil(kDiskSegments * phimax / 360)));
  const bool full = phimax >= 360;
  const int cols = full ? segs : segs + 1;
  for (int ring = 0; ring < 2; ++ring)
    for (int j = 0; j < cols; ++j) {
      const float ph = phi_max * float(j) / segs, rad = ring == 0 ? r : ri;
      mesh.positions.push_back(Vec3(rad * std::cos(ph), rad * std::sin(ph), h));
      mesh.uvs.push_back(Vec2{ph / phi_max, float(ring)});
    }
  for (int j = 0; j < segs; ++j) {
    const uint32_t a = uint32_t(j), b = uint32_t(full ? (j + 1) % segs : j + 1),
                   c = uint32_t(cols) + a, d = uint32_t(cols) + b;
    mesh.triangles.push_back({a, b, d});  // normal +z, as pbrt's disk
    if (ri > 0) mesh.triangles.push_back({a, d, c});
  }
  if (ri == 0) {
    // The inner ring collapsed to the centre: keep one vertex there.
    for (auto& tri : mesh.triangles)
      for (auto& v : tri)
        if (v >= uint32_t(cols)) v = uint32_t(cols);
    mesh.positions.resize(size_t(cols) + 1);
    mesh.uvs.resize(size_t(cols) + 1);
  }
}

// Winds every triangle of a closed convex-ish shape around the origin with its normal out.
void PbrtReader::orient_outward(Mesh& mesh) {
  for (auto& tri : mesh.triangles) {
    const Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]], c = mesh.positions[tri[2]];
    if (dot(cross(b - a, c - a), a + b + c) < 0) std::swap(tri[1], tri[2]);
  }
}

}  // namespace rll::pbrt
