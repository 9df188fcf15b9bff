#include "rll/lights/tree_sampler.h"

#include "rll/core/error.h"
#include "rll/lighttree/light_tree.h"
#include "rll/scene/scene.h"

namespace rll {

TreeLightSampler::TreeLightSampler(const Scene& scene, const LightTree& tree)
    : LightSampler("tree"), m_tree(tree) {
  if (m_tree.depth() >= kMaxTreeDepth)
    fail("{}: light tree too deep ({})", scene.source, m_tree.depth());
}

SamplerView TreeLightSampler::sampler_view() const {
  SamplerView v;
  v.kind = SamplerKind::Tree;
  v.tree = m_tree.view();
  return v;
}

nlohmann::json TreeLightSampler::describe() const {
  return {{"name", name()},
          {"nodes", m_tree.node_count()},
          {"depth", m_tree.depth()},
          {"bytes", m_tree.bytes()}};
}

}  // namespace rll
