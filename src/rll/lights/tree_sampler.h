// The visibility-blind light-tree sampler (Conty & Kulla 2018, as pbrt-v4's BVH light sampler):
// one stochastic descent of the reference tree, each child chosen in proportion to its
// importance at the shading point; above the group roots (local lights, sky dome, directional
// lights), each group that can contribute at the point gets an equal share.
#pragma once

#include "rll/lights/light_sampler.h"
#include "rll/lighttree/descent.h"

namespace rll {

class TreeLightSampler final : public LightSampler {
 public:
  TreeLightSampler(const Scene& scene, const LightTree& tree);
  nlohmann::json describe() const override;
  SamplerView sampler_view() const override;

 private:
  const LightTree& m_tree;  // the render session's (it outlives its samplers)
};

}  // namespace rll
