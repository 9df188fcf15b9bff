// Loop subdivision (see subdivide.h for the rules).
#include "rll/scene/subdivide.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "rll/core/error.h"

namespace rll {
namespace {

uint64_t edge_key(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (uint64_t(a) << 32) | b;
}

struct Edge {
  uint32_t a = 0, b = 0;          // as the first triangle traverses it (a to b)
  uint32_t opposite[2] = {0, 0};  // the third vertex of each triangle
  int count = 0;                  // triangles using it (1: boundary, 2: interior)
  uint32_t odd = 0;               // index of its new vertex
};

// One corner of a triangle as seen from its vertex v: the triangle is (v, next, prev).
struct Wedge {
  uint32_t next, prev;
};

struct Topology {
  std::unordered_map<uint64_t, Edge> edges;
  std::vector<uint32_t> wedge_start;  // per vertex, into wedges (CSR), size positions + 1
  std::vector<Wedge> wedges;
  // Per vertex: its one ring in order around it (counter-clockwise seen from the front of its
  // triangles); boundary vertices' rings start and end at their two boundary neighbours.
  std::vector<uint32_t> ring_start;  // CSR, size positions + 1
  std::vector<uint32_t> rings;
  std::vector<uint8_t> boundary;
};

Topology topology(const SubdivisionMesh& m) {
  const size_t nv = m.positions.size();
  Topology t;
  t.edges.reserve(m.triangles.size() * 2);
  for (size_t f = 0; f < m.triangles.size(); ++f) {
    const auto& tri = m.triangles[f];
    for (int k = 0; k < 3; ++k) {
      if (tri[size_t(k)] >= nv)
        fail("triangle {} uses vertex {}, but there are {} vertices", f, tri[size_t(k)], nv);
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0])
      fail("triangle {} uses vertex {} twice", f, tri[0] == tri[1] ? tri[0] : tri[2]);
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tri[size_t(k)], b = tri[size_t((k + 1) % 3)], c = tri[size_t((k + 2) % 3)];
      Edge& e = t.edges[edge_key(a, b)];
      if (e.count == 2)
        fail("edge ({}, {}) is shared by more than two triangles: the mesh is not a manifold", a,
             b);
      if (e.count == 1 && e.a == a)
        fail(
            "the two triangles sharing edge ({}, {}) are wound the same way round: the mesh is "
            "not consistently oriented",
            a, b);
      if (e.count == 0) {
        e.a = a;
        e.b = b;
      }
      e.opposite[e.count++] = c;
    }
  }
  // Wedges per vertex.
  t.wedge_start.assign(nv + 1, 0);
  for (const auto& tri : m.triangles)
    for (uint32_t v : tri) ++t.wedge_start[v + 1];
  for (size_t i = 0; i < nv; ++i) t.wedge_start[i + 1] += t.wedge_start[i];
  t.wedges.resize(t.wedge_start[nv]);
  {
    std::vector<uint32_t> fill(t.wedge_start.begin(), t.wedge_start.end() - 1);
    for (const auto& tri : m.triangles)
      for (int k = 0; k < 3; ++k)
        t.wedges[fill[tri[size_t(k)]]++] = {tri[size_t((k + 1) % 3)], tri[size_t((k + 2) % 3)]};
  }
  // Rings: walk each vertex's fan, from a wedge whose (v, next) edge is a boundary if any.
  t.ring_start.assign(nv + 1, 0);
  t.boundary.assign(nv, 0);
  t.rings.reserve(t.wedges.size() + nv);
  std::vector<Wedge> by_next;
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t w0 = t.wedge_start[v], w1 = t.wedge_start[v + 1], n = w1 - w0;
    t.ring_start[v] = uint32_t(t.rings.size());
    if (n == 0) {
      t.ring_start[v + 1] = uint32_t(t.rings.size());
      continue;
    }
    by_next.assign(t.wedges.begin() + w0, t.wedges.begin() + w1);
    std::sort(by_next.begin(), by_next.end(),
              [](const Wedge& a, const Wedge& b) { return a.next < b.next; });
    auto find_next = [&](uint32_t x) -> const Wedge* {
      auto it = std::lower_bound(by_next.begin(), by_next.end(), x,
                                 [](const Wedge& w, uint32_t y) { return w.next < y; });
      return it != by_next.end() && it->next == x ? &*it : nullptr;
    };
    // A boundary fan starts at the wedge no other wedge leads to (its `next` is no `prev`).
    const Wedge* start = &by_next[0];
    bool is_boundary = false;
    for (const Wedge& w : by_next) {
      if (t.edges.at(edge_key(v, w.next)).count == 1) {
        start = &w;
        is_boundary = true;
        break;
      }
    }
    const Wedge* w = start;
    uint32_t visited = 0;
    for (;;) {
      t.rings.push_back(w->next);
      ++visited;
      const Wedge* s = find_next(w->prev);
      if (!s) {
        t.rings.push_back(w->prev);  // the fan's other boundary neighbour
        break;
      }
      if (s == start || visited > n) break;
      w = s;
    }
    if (visited != n)
      fail("vertex {} is where {} separate fans of triangles meet: the mesh is not a manifold", v,
           visited < n ? "several" : "overlapping");
    t.boundary[v] = is_boundary;
    t.ring_start[v + 1] = uint32_t(t.rings.size());
  }
  return t;
}

float loop_beta(size_t n) {
  return n == 3 ? 3.0f / 16.0f : 3.0f / (8.0f * float(n));
}

// pbrt's limit-surface weight for an interior vertex of valence n.
float loop_gamma(size_t n) {
  return 1.0f / (float(n) + 3.0f / (8.0f * loop_beta(n)));
}

void subdivide_once(SubdivisionMesh& m) {
  Topology t = topology(m);
  const size_t nv = m.positions.size();
  std::vector<Vec3> out(nv + t.edges.size());
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t r0 = t.ring_start[v], r1 = t.ring_start[v + 1];
    const size_t n = r1 - r0;
    const Vec3 p = m.positions[v];
    if (n == 0) {
      out[v] = p;
    } else if (t.boundary[v]) {
      out[v] = p * 0.75f + (m.positions[t.rings[r0]] + m.positions[t.rings[r1 - 1]]) * 0.125f;
    } else {
      const float beta = loop_beta(n);
      Vec3 sum(0);
      for (uint32_t i = r0; i < r1; ++i) sum += m.positions[t.rings[i]];
      out[v] = p * (1 - float(n) * beta) + sum * beta;
    }
  }
  uint32_t next = uint32_t(nv);
  // Odd vertices, numbered in the order of the triangles' edges (deterministic).
  for (const auto& tri : m.triangles)
    for (int k = 0; k < 3; ++k) {
      Edge& e = t.edges.at(edge_key(tri[size_t(k)], tri[size_t((k + 1) % 3)]));
      if (e.odd != 0) continue;
      e.odd = next++;
      const Vec3 a = m.positions[e.a], b = m.positions[e.b];
      out[e.odd] = e.count == 1
                       ? (a + b) * 0.5f
                       : (a + b) * 0.375f +
                             (m.positions[e.opposite[0]] + m.positions[e.opposite[1]]) * 0.125f;
    }
  std::vector<std::array<uint32_t, 3>> tris;
  tris.reserve(m.triangles.size() * 4);
  for (const auto& tri : m.triangles) {
    const uint32_t a = tri[0], b = tri[1], c = tri[2];
    const uint32_t ab = t.edges.at(edge_key(a, b)).odd, bc = t.edges.at(edge_key(b, c)).odd,
                   ca = t.edges.at(edge_key(c, a)).odd;
    tris.push_back({a, ab, ca});
    tris.push_back({b, bc, ab});
    tris.push_back({c, ca, bc});
    tris.push_back({ab, bc, ca});
  }
  m.positions = std::move(out);
  m.triangles = std::move(tris);
}

void push_to_limit(SubdivisionMesh& m) {
  Topology t = topology(m);
  const size_t nv = m.positions.size();
  std::vector<Vec3> limit(nv), normals(nv, Vec3(0));
  // The faces' winding decides which way the normals point.
  std::vector<Vec3> face_sum(nv, Vec3(0));
  for (const auto& tri : m.triangles) {
    const Vec3 n =
        cross(m.positions[tri[1]] - m.positions[tri[0]], m.positions[tri[2]] - m.positions[tri[0]]);
    for (uint32_t v : tri) face_sum[v] += n;
  }
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t r0 = t.ring_start[v], r1 = t.ring_start[v + 1];
    const size_t n = r1 - r0;
    const Vec3 p = m.positions[v];
    auto ring = [&](size_t i) { return m.positions[t.rings[r0 + i]]; };
    if (n == 0) {
      limit[v] = p;
      continue;
    }
    Vec3 s(0), tan(0);
    if (t.boundary[v]) {
      limit[v] = p * 0.6f + (ring(0) + ring(n - 1)) * 0.2f;
      s = ring(n - 1) - ring(0);
      if (n == 2) {
        tan = ring(0) + ring(1) - p * 2;
      } else if (n == 3) {
        tan = ring(1) - p;
      } else if (n == 4) {
        tan = ring(1) * 2 + ring(2) * 2 - ring(0) - ring(3) - p * 2;
      } else {
        const double th = kPi / double(n - 1);
        Vec3 sum = (ring(0) + ring(n - 1)) * float(std::sin(th));
        for (size_t k = 1; k + 1 < n; ++k)
          sum += ring(k) * float((2 * std::cos(th) - 2) * std::sin(double(k) * th));
        tan = -sum;
      }
    } else {
      const float gamma = loop_gamma(n);
      Vec3 sum(0);
      for (size_t i = 0; i < n; ++i) {
        sum += ring(i);
        const double a = 2 * kPi * double(i) / double(n);
        s += ring(i) * float(std::cos(a));
        tan += ring(i) * float(std::sin(a));
      }
      limit[v] = p * (1 - float(n) * gamma) + sum * gamma;
    }
    Vec3 nrm = cross(s, tan);
    if (!(length_sq(nrm) > 0) || !is_finite(nrm)) nrm = face_sum[v];
    if (dot(nrm, face_sum[v]) < 0) nrm = -nrm;
    normals[v] = length_sq(nrm) > 0 ? normalize(nrm) : Vec3(0);
  }
  m.positions = std::move(limit);
  m.normals = std::move(normals);
}

}  // namespace

void loop_subdivide(SubdivisionMesh& mesh, int levels, bool to_limit) {
  if (levels < 0) fail("the subdivision level must not be negative (got {})", levels);
  mesh.normals.clear();
  if (levels == 0 && !to_limit) {
    topology(mesh);  // the same checks as at any level
    return;
  }
  for (int i = 0; i < levels; ++i) subdivide_once(mesh);
  if (to_limit) push_to_limit(mesh);
}

}  // namespace rll
