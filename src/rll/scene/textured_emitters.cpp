#include "rll/scene/textured_emitters.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>

#include "rll/core/memory_budget.h"
#include "rll/core/parallel.h"
#include "rll/scene/scene.h"

namespace rll {

namespace {

using D2 = std::array<double, 2>;

// A convex polygon of at most 3 + 4 vertices (a triangle clipped by a cell's four sides).
struct Polygon {
  D2 v[8];
  int n = 0;
};

// Keeps the part of `p` where sign * (coordinate `axis` - value) >= 0.
Polygon clip(const Polygon& p, int axis, double value, double sign) {
  Polygon out;
  for (int i = 0; i < p.n; ++i) {
    const D2 &a = p.v[i], &b = p.v[(i + 1) % p.n];
    const double da = sign * (a[axis] - value), db = sign * (b[axis] - value);
    if (da >= 0) out.v[out.n++] = a;
    if ((da >= 0) != (db >= 0)) {
      const double t = da / (da - db);
      D2 c{a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])};
      c[axis] = value;  // exactly on the line
      out.v[out.n++] = c;
    }
  }
  return out;
}

double tri_area(const D2& a, const D2& b, const D2& c) {
  return 0.5 * std::abs((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
}

// About how many cells the exact integration's loop visits for the triangle P (in texel
// coordinates): per row of cells, the row's extent and two more, and the rows' extents add up to
// at most about the area plus the edges' horizontal lengths. Known before the loop runs, so that
// a triangle tiling its texture a thousand times is never walked cell by cell.
double exact_cost(const D2 P[3]) {
  double dx = 0, ymin = P[0][1], ymax = P[0][1];
  for (int k = 0; k < 3; ++k) {
    dx += std::abs(P[k][0] - P[(k + 1) % 3][0]);
    ymin = std::min(ymin, P[k][1]);
    ymax = std::max(ymax, P[k][1]);
  }
  const double cost =
      tri_area(P[0], P[1], P[2]) + dx + 2 * (std::floor(ymax) - std::floor(ymin) + 1);
  return std::isfinite(cost) ? cost : std::numeric_limits<double>::infinity();
}

// The triangle with texture coordinates uv in texel coordinates (X = u W - 1/2, Y = (1 - v) H -
// 1/2).
void to_texels(const TexelView& tex, const std::array<D2, 3>& uv, D2 P[3]) {
  const double W = tex.width, H = tex.height;
  for (int k = 0; k < 3; ++k) P[k] = {uv[k][0] * W - 0.5, (1 - uv[k][1]) * H - 0.5};
}

// The integrals of 1, x, y and xy over polygon p (x, y relative to the cell's corner (x0, y0)):
// over each triangle of a fan, the edge-midpoint rule, exact for polynomials of degree 2.
std::array<double, 4> moments(const Polygon& p, double x0, double y0) {
  std::array<double, 4> m{};
  for (int k = 1; k + 1 < p.n; ++k) {
    const D2 &a = p.v[0], &b = p.v[k], &c = p.v[k + 1];
    const double A = tri_area(a, b, c) / 3;
    const D2 mids[3] = {{0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])},
                        {0.5 * (b[0] + c[0]), 0.5 * (b[1] + c[1])},
                        {0.5 * (c[0] + a[0]), 0.5 * (c[1] + a[1])}};
    for (const D2& q : mids) {
      const double x = q[0] - x0, y = q[1] - y0;
      m[0] += A;
      m[1] += A * x;
      m[2] += A * y;
      m[3] += A * x * y;
    }
  }
  return m;
}

int wrap(int64_t i, int n) {
  const int64_t r = i % n;
  return int(r < 0 ? r + n : r);
}

// The reconstruction at texel coordinates (X, Y) (X = u W - 1/2, Y = (1 - v) H - 1/2), in double.
std::array<double, 3> bilinear(const TexelView& tex, double X, double Y) {
  const double fx0 = std::floor(X), fy0 = std::floor(Y), fx = X - fx0, fy = Y - fy0;
  const int64_t x0 = int64_t(fx0), y0 = int64_t(fy0);
  std::array<double, 3> r{};
  for (int k = 0; k < 4; ++k) {
    const int dx = k & 1, dy = k >> 1;
    const double w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy);
    const Rgb& t = tex.at(wrap(x0 + dx, tex.width), wrap(y0 + dy, tex.height));
    r[0] += w * t.x;
    r[1] += w * t.y;
    r[2] += w * t.z;
  }
  return r;
}

// The mean over the triangle from points: the centroids of its 64 x 64 sub-triangles of equal
// area (exact for a linear function).
std::array<double, 3> sampled_mean(const TexelView& tex, const D2 P[3]) {
  constexpr int g = 64;
  std::array<double, 3> sum{};
  auto add = [&](double b1, double b2) {
    const double b0 = 1 - b1 - b2;
    const auto v = bilinear(tex, P[0][0] * b0 + P[1][0] * b1 + P[2][0] * b2,
                            P[0][1] * b0 + P[1][1] * b1 + P[2][1] * b2);
    for (int c = 0; c < 3; ++c) sum[c] += v[c];
  };
  for (int i = 0; i < g; ++i)
    for (int j = 0; i + j < g; ++j) {
      add((i + 1.0 / 3) / g, (j + 1.0 / 3) / g);
      if (i + j + 1 < g) add((i + 2.0 / 3) / g, (j + 2.0 / 3) / g);
    }
  for (double& s : sum) s /= double(g) * g;
  return sum;
}

}  // namespace

Rgb TextureIntegral::mean() const {
  if (!(uv_area > 0)) return Rgb(float(sum[0]), float(sum[1]), float(sum[2]));
  return Rgb(float(sum[0] / uv_area), float(sum[1] / uv_area), float(sum[2] / uv_area));
}

TextureIntegral integrate_texture(const TexelView& tex, const std::array<D2, 3>& uv,
                                  size_t max_cells) {
  TextureIntegral r;
  const double W = tex.width, H = tex.height;
  D2 P[3];
  to_texels(tex, uv, P);
  const double area = tri_area(P[0], P[1], P[2]);  // in texel units
  r.uv_area = tri_area(uv[0], uv[1], uv[2]);
  if (tex.width <= 0 || tex.height <= 0) {  // sample_texture's "no texture": 1
    r.sum = {r.uv_area, r.uv_area, r.uv_area};
    return r;
  }
  double extent = 0;
  for (int k = 0; k < 3; ++k)
    extent = std::max({extent, std::abs(P[k][0] - P[(k + 1) % 3][0]),
                       std::abs(P[k][1] - P[(k + 1) % 3][1])});
  // The sum is kept as a mean times the area below, so that a triangle of (nearly) no uv area
  // still has its mean (mean() divides by uv_area).
  auto from_mean = [&](const std::array<double, 3>& m) {
    const double a = r.uv_area > 0 ? r.uv_area : 1;
    r.sum = {m[0] * a, m[1] * a, m[2] * a};
  };
  if (extent == 0) {  // every vertex at one point: the value there, exactly
    from_mean(bilinear(tex, P[0][0], P[0][1]));
    return r;
  }
  if (!(area > 1e-9 * extent * extent) || !std::isfinite(area)) {  // collinear uvs
    r.exact = false;
    from_mean(sampled_mean(tex, P));
    return r;
  }
  // The cost checked first: the count below only stops a loop whose estimate was wrong.
  if (exact_cost(P) > double(max_cells)) {
    r.exact = false;
    from_mean(sampled_mean(tex, P));
    return r;
  }
  const double ymin = std::min({P[0][1], P[1][1], P[2][1]}),
               ymax = std::max({P[0][1], P[1][1], P[2][1]});
  Polygon tri;
  tri.n = 3;
  for (int k = 0; k < 3; ++k) tri.v[k] = P[k];
  std::array<double, 3> sum{};
  size_t cells = 0;
  for (double j = std::floor(ymin); j <= ymax; ++j) {
    const Polygon row = clip(clip(tri, 1, j, 1), 1, j + 1, -1);
    if (row.n < 3) continue;
    double xmin = row.v[0][0], xmax = xmin;
    for (int k = 1; k < row.n; ++k) {
      xmin = std::min(xmin, row.v[k][0]);
      xmax = std::max(xmax, row.v[k][0]);
    }
    const int y0 = wrap(int64_t(j), tex.height), y1 = wrap(int64_t(j) + 1, tex.height);
    for (double i = std::floor(xmin); i <= xmax; ++i) {
      if (++cells > max_cells) {
        r.exact = false;
        from_mean(sampled_mean(tex, P));
        return r;
      }
      const Polygon cell = clip(clip(row, 0, i, 1), 0, i + 1, -1);
      if (cell.n < 3) continue;
      const auto m = moments(cell, i, j);
      const int x0 = wrap(int64_t(i), tex.width), x1 = wrap(int64_t(i) + 1, tex.width);
      // f = t00 (1 - x)(1 - y) + t10 x (1 - y) + t01 (1 - x) y + t11 x y
      const double w00 = m[0] - m[1] - m[2] + m[3], w10 = m[1] - m[3], w01 = m[2] - m[3],
                   w11 = m[3];
      const Rgb &t00 = tex.at(x0, y0), &t10 = tex.at(x1, y0), &t01 = tex.at(x0, y1),
                &t11 = tex.at(x1, y1);
      sum[0] += w00 * t00.x + w10 * t10.x + w01 * t01.x + w11 * t11.x;
      sum[1] += w00 * t00.y + w10 * t10.y + w01 * t01.y + w11 * t11.y;
      sum[2] += w00 * t00.z + w10 * t10.z + w01 * t01.z + w11 * t11.z;
    }
  }
  // From texel area to uv area.
  for (int c = 0; c < 3; ++c) r.sum[c] = sum[c] / (W * H);
  return r;
}

TextureIntegral integrate_texture(const TexelView& tex, const std::array<Vec2, 3>& uv,
                                  size_t max_cells) {
  std::array<D2, 3> d;
  for (int k = 0; k < 3; ++k) d[k] = {double(uv[k].x), double(uv[k].y)};
  return integrate_texture(tex, d, max_cells);
}

double exact_integration_cost(const TexelView& tex, const std::array<D2, 3>& uv) {
  if (tex.width <= 0 || tex.height <= 0) return 0;
  D2 P[3];
  to_texels(tex, uv, P);
  return exact_cost(P);
}

double exact_integration_cost(const TexelView& tex, const std::array<Vec2, 3>& uv) {
  std::array<D2, 3> d;
  for (int k = 0; k < 3; ++k) d[k] = {double(uv[k].x), double(uv[k].y)};
  return exact_integration_cost(tex, d);
}

std::array<Vec2, 3> triangle_uvs(const Scene& scene, uint32_t tri) {
  const Mesh& m = scene.mesh;
  if (m.uvs.empty()) return {Vec2{0, 0}, Vec2{1, 0}, Vec2{0, 1}};
  const Triangle& t = m.triangles[tri];
  return {m.uvs[t[0]], m.uvs[t[1]], m.uvs[t[2]]};
}

namespace {

// A piece of a triangle being split: its corners as barycentrics (b1, b2) of the triangle.
struct Piece {
  std::array<D2, 3> bary;
  TextureIntegral integral;
  double key = 0;  // its luminance power, up to the triangle's constant factor
  bool operator<(const Piece& o) const { return key < o.key; }
};

// What the exact integrations of a scene's load may still cost, in cells (exact_cost's estimate).
struct CellBudget {
  double left = 0;
  // The max_cells of an integration of `cost`: kMaxExactTextureCells where it is at most
  // kAlwaysExactTextureCells (no dearer than the points), or at most that and what is left (then
  // spent); else 0 (from points).
  size_t take(double cost) {
    if (cost <= double(kAlwaysExactTextureCells)) return kMaxExactTextureCells;
    if (cost > double(kMaxExactTextureCells) || cost > left) return 0;
    left -= cost;
    return kMaxExactTextureCells;
  }
};

// Splits triangle `tri` into at most `count` pieces, the brightest first, each in two across
// its longest edge (in the world), down to pieces of about one texel cell. Each piece is
// integrated exactly while `budget` lasts, from points after.
std::vector<Piece> split_triangle(const Scene& scene, uint32_t tri, const TexelView& tex,
                                  const Rgb& factor, size_t count, CellBudget& budget) {
  const std::array<Vec2, 3> uv = triangle_uvs(scene, tri);
  const Vec3 p[3] = {scene.mesh.vertex(tri, 0), scene.mesh.vertex(tri, 1),
                     scene.mesh.vertex(tri, 2)};
  auto make = [&](const std::array<D2, 3>& bary) {
    Piece piece;
    piece.bary = bary;
    std::array<D2, 3> puv;
    for (int k = 0; k < 3; ++k) {
      const double b1 = bary[k][0], b2 = bary[k][1], b0 = 1 - b1 - b2;
      puv[k] = {uv[0].x * b0 + uv[1].x * b1 + uv[2].x * b2,
                uv[0].y * b0 + uv[1].y * b1 + uv[2].y * b2};
    }
    piece.integral = integrate_texture(tex, puv, budget.take(exact_integration_cost(tex, puv)));
    const auto& s = piece.integral.sum;
    piece.key = 0.2126 * factor.x * s[0] + 0.7152 * factor.y * s[1] + 0.0722 * factor.z * s[2];
    return piece;
  };
  auto world = [&](const D2& b) {
    const double b0 = 1 - b[0] - b[1];
    return std::array<double, 3>{p[0].x * b0 + p[1].x * b[0] + p[2].x * b[1],
                                 p[0].y * b0 + p[1].y * b[0] + p[2].y * b[1],
                                 p[0].z * b0 + p[1].z * b[0] + p[2].z * b[1]};
  };
  const double cells_per_uv = double(tex.width) * double(tex.height);
  std::priority_queue<Piece> open;
  std::vector<Piece> done;
  open.push(make({D2{0, 0}, D2{1, 0}, D2{0, 1}}));
  while (!open.empty() && open.size() + done.size() < count) {
    Piece q = open.top();
    open.pop();
    if (q.integral.uv_area * cells_per_uv <= 1 || !(q.key > 0)) {
      done.push_back(q);
      continue;
    }
    int longest = 0;
    double best = -1;
    for (int k = 0; k < 3; ++k) {
      const auto a = world(q.bary[k]), b = world(q.bary[(k + 1) % 3]);
      const double l = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                       (a[2] - b[2]) * (a[2] - b[2]);
      if (l > best) best = l, longest = k;
    }
    const D2 &a = q.bary[longest], &b = q.bary[(longest + 1) % 3], &c = q.bary[(longest + 2) % 3];
    const D2 m{0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])};
    open.push(make({a, m, c}));  // both keep the triangle's winding
    open.push(make({m, b, c}));
  }
  for (; !open.empty(); open.pop()) done.push_back(open.top());
  return done;
}

bool textured_emitter(const Scene& scene, uint32_t t) {
  const Material& m = scene.materials[scene.mesh.material[t]];
  return m.emission_texture >= 0 && m.is_emissive() && !scene.is_sky_triangle(t) &&
         scene.mesh.area(t) > 0;
}

}  // namespace

std::vector<Rgb> prepare_textured_emitters(Scene& scene) {
  if (std::none_of(scene.materials.begin(), scene.materials.end(), [](const Material& m) {
        return m.emission_texture >= 0 && m.is_emissive();
      }))
    return {};
  Mesh& mesh = scene.mesh;
  std::vector<uint32_t> textured;
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
    if (textured_emitter(scene, t)) textured.push_back(t);
  auto texture_of = [&](uint32_t t) {
    return scene.textures[size_t(scene.materials[mesh.material[t]].emission_texture)].texel_view();
  };
  // Every exact integration's cost is estimated first and the load's are held to a budget,
  // the cheapest first (a deterministic choice): a mesh of many triangles that each tile their
  // texture a thousand times is integrated from points, not walked for hours cell by cell.
  std::vector<double> cost(textured.size());
  for (size_t i = 0; i < textured.size(); ++i)
    cost[i] = exact_integration_cost(texture_of(textured[i]), triangle_uvs(scene, textured[i]));
  std::vector<size_t> order(textured.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return cost[a] < cost[b]; });
  CellBudget budget{double(kMaxExactTextureCellsPerLoad)};
  std::vector<size_t> max_cells(textured.size());
  for (size_t i : order) max_cells[i] = budget.take(cost[i]);
  std::vector<TextureIntegral> integrals(textured.size());
  parallel_for(textured.size(), 64, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      integrals[i] = integrate_texture(texture_of(textured[i]), triangle_uvs(scene, textured[i]),
                                       max_cells[i]);
  });
  std::vector<Rgb> means(mesh.triangle_count(), Rgb(0));
  size_t inexact = 0;
  for (size_t i = 0; i < textured.size(); ++i) {
    means[textured[i]] = integrals[i].mean();
    inexact += !integrals[i].exact;
  }
  auto warn = [&](size_t triangles, size_t pieces) {
    if (triangles + pieces == 0) return;
    std::string what;
    if (triangles > 0)
      what = fmt::format("{} textured emissive triangle{}", triangles, triangles == 1 ? "" : "s");
    if (pieces > 0)
      what += fmt::format("{}{} of the lights they were split into", what.empty() ? "" : " and ",
                          pieces);
    std::string w = fmt::format(
        "{}: {} have collinear uvs, cover more than {} texel cells each (a texture tiled many "
        "times) or go beyond the {} cells of exact integration a load may spend: their mean "
        "emission is measured at 64 x 64 points, not integrated exactly",
        scene.source, what, kMaxExactTextureCells, kMaxExactTextureCellsPerLoad);
    if (std::find(scene.warnings.begin(), scene.warnings.end(), w) == scene.warnings.end())
      scene.warnings.push_back(std::move(w));  // finalize() may run twice
  };
  if (scene.textured_emitters_split || mesh.uvs.empty()) {
    warn(inexact, 0);
    return means;
  }
  scene.textured_emitters_split = true;

  // Lights of nearly equal power: each triangle gets pieces in proportion to its power, at most
  // one per texel cell it covers.
  std::vector<double> power(textured.size());
  double total = 0;
  for (size_t i = 0; i < textured.size(); ++i) {
    const uint32_t t = textured[i];
    const Material& m = scene.materials[mesh.material[t]];
    total += power[i] = double(mesh.area(t)) * double(luminance(m.emission * means[t]));
  }
  if (!(total > 0)) {
    warn(inexact, 0);
    return means;
  }
  std::vector<size_t> pieces(textured.size(), 1);
  size_t new_triangles = 0;
  for (size_t i = 0; i < textured.size(); ++i) {
    const TexelView tex = texture_of(textured[i]);
    const double cells = integrals[i].uv_area * double(tex.width) * double(tex.height);
    const double share = std::floor(double(kTexturedEmitterLights) * power[i] / total + 0.5);
    pieces[i] = size_t(std::clamp(std::min(share, std::ceil(cells)), 1.0,
                                  double(kMaxPiecesPerTriangle)));
    new_triangles += pieces[i] - 1;
  }
  if (new_triangles == 0) {
    warn(inexact, 0);
    return means;
  }
  const size_t vertex_bytes =
      sizeof(Vec3) + sizeof(Vec2) + (mesh.normals.empty() ? 0 : sizeof(Vec3));
  check_memory_budget(double(new_triangles + textured.size()) * 3 * double(vertex_bytes) +
                          double(new_triangles) *
                              double(sizeof(Triangle) + 2 * sizeof(uint32_t) + sizeof(Rgb)),
                      fmt::format("{}: splitting the textured emitters into lights", scene.source));
  mesh.triangles.reserve(mesh.triangles.size() + new_triangles);
  mesh.material.reserve(mesh.material.size() + new_triangles);
  means.reserve(means.size() + new_triangles);
  size_t inexact_pieces = 0;
  for (size_t i = 0; i < textured.size(); ++i) {
    if (pieces[i] <= 1) continue;
    const uint32_t t = textured[i];
    const Material& m = scene.materials[mesh.material[t]];
    const std::vector<Piece> split =
        split_triangle(scene, t, texture_of(t), m.emission, pieces[i], budget);
    const Triangle original = mesh.triangles[t];
    for (size_t k = 0; k < split.size(); ++k) {
      Triangle nt;
      for (int c = 0; c < 3; ++c) {
        const double b1 = split[k].bary[c][0], b2 = split[k].bary[c][1], b0 = 1 - b1 - b2;
        auto lerp3 = [&](const std::vector<Vec3>& a) {
          const Vec3 &x = a[original[0]], &y = a[original[1]], &z = a[original[2]];
          return Vec3(float(x.x * b0 + y.x * b1 + z.x * b2), float(x.y * b0 + y.y * b1 + z.y * b2),
                      float(x.z * b0 + y.z * b1 + z.z * b2));
        };
        const Vec2 &ua = mesh.uvs[original[0]], &ub = mesh.uvs[original[1]],
                   &uc = mesh.uvs[original[2]];
        nt[c] = uint32_t(mesh.positions.size());
        mesh.positions.push_back(lerp3(mesh.positions));
        if (!mesh.normals.empty()) mesh.normals.push_back(lerp3(mesh.normals));
        mesh.uvs.push_back(Vec2{float(ua.x * b0 + ub.x * b1 + uc.x * b2),
                                float(ua.y * b0 + ub.y * b1 + uc.y * b2)});
      }
      const Rgb mean = split[k].integral.mean();
      inexact_pieces += !split[k].integral.exact;
      if (k == 0) {
        mesh.triangles[t] = nt;
        means[t] = mean;
      } else {
        mesh.triangles.push_back(nt);
        mesh.material.push_back(mesh.material[t]);
        means.push_back(mean);
      }
    }
  }
  warn(inexact, inexact_pieces);
  return means;
}

}  // namespace rll
