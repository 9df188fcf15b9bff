#include "rll/lights/tree_sampler.h"

#include "rll/core/error.h"
#include "rll/lighttree/light_tree.h"
#include "rll/scene/scene.h"

namespace rll {

TreeLightSampler::TreeLightSampler(const Scene& scene) : m_tree(light_tree_of(scene)) {
  if (m_tree.depth() >= kMaxTreeDepth)
    fail("{}: light tree too deep ({})", scene.source, m_tree.depth());
}

SampledLight TreeLightSampler::sample(const LightContext& ctx, double u) const {
  return sampled_light(tree_descend(m_tree, LightTree::kRoot, ctx.p, ctx.n, u));
}

float TreeLightSampler::pmf(const LightContext& ctx, uint32_t light) const {
  return tree_descend_pmf(m_tree, LightTree::kRoot, light, ctx.p, ctx.n);
}

nlohmann::json TreeLightSampler::describe() const {
  return {{"name", name()},
          {"nodes", m_tree.node_count()},
          {"depth", m_tree.depth()},
          {"bytes", m_tree.bytes()}};
}

}  // namespace rll
