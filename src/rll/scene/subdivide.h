// Loop subdivision of a triangle mesh, with the rules pbrt-v4's "loopsubdiv" shape uses:
// - even (old) vertices: interior ones move to (1 - n beta) v + beta * (sum of the n one-ring
//   neighbours), beta = 3/16 for n = 3 and 3/(8n) otherwise; boundary ones to
//   3/4 v + 1/8 (the two boundary neighbours);
// - odd (new, one per edge) vertices: 3/8 (a + b) + 1/8 (c + d) on an interior edge ab with
//   opposite vertices c and d, the midpoint 1/2 (a + b) on a boundary edge;
// - each triangle becomes four, keeping its winding;
// - after the last level every vertex is moved to its limit position: interior ones to
//   (1 - n gamma) v + gamma * (sum of the one ring), gamma = 1 / (n + 3 / (8 beta)); boundary
//   ones to 3/5 v + 1/5 (the two boundary neighbours);
// - limit-surface normals from the two tangents of the one ring (interior: the cos- and
//   sin-weighted sums of the ring; boundary: the boundary chord and the boundary-curve rule),
//   oriented to agree with the faces' winding.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "rll/core/math.h"

namespace rll {

struct SubdivisionMesh {
  std::vector<Vec3> positions;
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<Vec3> normals;  // filled by loop_subdivide when push_to_limit is set
};

// Subdivides `mesh` `levels` times (levels >= 0; each level multiplies the triangle count by 4).
// With `push_to_limit` (pbrt's behaviour) the vertices end at their limit positions and get
// limit normals; without it, the result is the plain subdivided mesh (for tests). Vertices no
// triangle uses are kept where they are. Throws rll::Error when the mesh is not a manifold
// (an edge shared by more than two triangles, two triangles traversing a shared edge in the same
// direction, or a vertex whose triangles do not form a single fan) or an index is out of range.
void loop_subdivide(SubdivisionMesh& mesh, int levels, bool push_to_limit = true);

}  // namespace rll
