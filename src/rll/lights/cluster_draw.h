// The record (SamplerRecord, light_context.h) of the samplers that draw a cluster of a cut first
// and then a light inside it (rll, fermat, the oracle's frozen rll, ltc): what their record_nee
// needs of the draw, and resampled NEE's learnt target factor.
#pragma once

#include <cstdint>

#include "rll/core/device.h"
#include "rll/lights/light_context.h"

namespace rll {

struct ClusterDraw {
  uint32_t cluster = 0;   // index of the cluster in the cell's cut
  float cluster_pmf = 0;  // probability of that cluster
  float importance = 0;   // rll's guided descent: the tree's importance of the cluster at the point
  // A factor of resampled NEE's target for this light (nee.target=learnt, docs/nee.md): rll's
  // learnt visibility factor of the light's cluster in the cell (CutStore::target_factor); 1
  // where none is learnt. A function of the light and the shading point's cell only (never of the
  // draw), and > 0 wherever the light can be drawn.
  float target = 1;
};

RLL_HD inline ClusterDraw cluster_draw(const SampledLight& s) {
  return unpack_record<ClusterDraw>(s.record);
}
RLL_HD inline void set_cluster_draw(SampledLight& s, const ClusterDraw& d) {
  s.record = pack_record(d);
}

}  // namespace rll
