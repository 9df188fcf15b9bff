#include "rll/lights/rht_sampler.h"

#include "rll/core/error.h"
#include "rll/core/params.h"
#include "rll/lighttree/light_tree.h"
#include "rll/scene/scene.h"

namespace rll {

const std::vector<ParamSpec<RhtSettings>>& rht_params() {
  using S = RhtSettings;
  static const std::vector<ParamSpec<S>> table = {
      float_param("gamma", ParamRange::open_closed(0, 1000), field<S, &S::gamma>(),
                  "the split probability's width"),
      int_param("reservoirs", ParamRange::closed(1, kRhtMaxReservoirs), field<S, &S::reservoirs>()),
      int_param("samples", ParamRange::closed(1, kRhtMaxSamples), field<S, &S::samples>()),
  };
  return table;
}

RhtSettings rht_settings_from(const Params& p) {
  RhtSettings s;
  read_params(rht_params(), p, "rht", s);
  return s;
}

RhtLightSampler::RhtLightSampler(const Scene& scene, const LightTree& tree,
                                 const RhtSettings& settings)
    : LightSampler("rht"), m_s(settings) {
  if (tree.depth() >= kMaxTreeDepth)
    fail("{}: light tree too deep ({})", scene.source, tree.depth());
  m_view.tree = tree.view();
  m_view.gamma = settings.gamma;
  m_view.reservoirs = settings.reservoirs;
  m_view.samples = settings.samples;
  const uint32_t dir = tree.group_root(LightGroup::Directional);
  if (dir != LightTree::kNone) {
    m_view.dir_begin = tree.node(dir).begin;
    m_view.dir_count = tree.node(dir).light_count();
  }
  m_view.has_tree_lights = tree.light_count() > m_view.dir_count;
}

SamplerView RhtLightSampler::sampler_view() const {
  SamplerView v;
  v.kind = SamplerKind::Rht;
  v.rht = m_view;
  v.tree = m_view.tree;
  return v;
}

nlohmann::json RhtLightSampler::describe() const {
  nlohmann::json j = {{"name", name()}, {"directional_lights", m_view.dir_count}};
  params_json(rht_params(), m_s, j);
  return j;
}

}  // namespace rll
