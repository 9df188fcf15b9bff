#include "rll/lights/rll_settings.h"

#include <nlohmann/json.hpp>

#include "rll/core/error.h"
#include "rll/core/params.h"

namespace rll {

const std::vector<ParamSpec<RllSettings>>& rll_params() {
  using S = RllSettings;
  using R = ParamRange;
  static const std::vector<ParamSpec<S>> table = {
      choice_param("within", {"uniform", "power", "tree", "hybrid"}, field<S, &S::within>()),
      int_param("descend_above", R::closed(1, 1 << 30), field<S, &S::descend_above>()),
      choice_param("defensive", {"cell", "tree"}, field<S, &S::defensive>()),
      choice_param("reward", {"cluster", "fullpdf", "fermat"}, field<S, &S::reward>()),
      int_param("capacity", R::closed(1, 1 << 24), field<S, &S::capacity>()),
      choice_param("cold", {"tree", "uniform"}, field<S, &S::cold_uniform>()),
      float_param("sample_jitter", R::closed(0, 4), field<S, &S::sample_jitter>()),
      int_param("reset_every", R::closed(0, 1 << 30), field<S, &S::reset_every>()),
      int_param("refine", R::closed(0, 8), field<S, &S::cut, &CutSettings::refine>(),
                "0: off; levels below a point's own"),
      float_param("refine_gain", R::closed(0, 1), field<S, &S::cut, &CutSettings::refine_gain>()),
      int_param("refine_min", R::closed(1, 1 << 30), field<S, &S::cut, &CutSettings::refine_min>()),
  };
  return table;
}

const std::vector<ParamSpec<RllStudy>>& rll_study_params() {
  using S = RllStudy;
  using R = ParamRange;
  static const std::vector<ParamSpec<S>> table = {
      int_param("ideal_cluster", R::closed(0, 1), field<S, &S::cluster>()),
      int_param("ideal_light", R::closed(0, 4096), field<S, &S::light>()),
      choice_param("ideal_light_at", {"anchor", "point"}, field<S, &S::light_at_point>()),
      int_param("ideal_point", R::closed(0, 4096), field<S, &S::point>()),
      int_param("ideal_bsdf", R::closed(0, 4096), field<S, &S::bsdf>()),
  };
  return table;
}

RllStudy rll_study_from(const Params& p) {
  RllStudy s;
  read_params(rll_study_params(), p, "rll", s);
  return s;
}

RllSettings rll_settings_from(const Params& p, const std::string& prefix, RllSettings s) {
  auto key = [&](const char* k) { return prefix + "." + k; };
  auto bad = [&](const char* k, const char* what) { fail("--set {}: {}", key(k), what); };
  // The initial cut follows the cut size unless the base starts smaller.
  const bool initial_is_whole = s.cut.initial_size == s.cut.cut_size;
  for_each_rll_table(s,
                     [&](const auto& table, auto& part) { read_params(table, p, prefix, part); });
  if (initial_is_whole && !p.has(key("initial_cut"))) s.cut.initial_size = s.cut.cut_size;
  s.cut.prior_in_cdf = s.defensive == Defensive::Cell;
  if (s.cut.guided) {
    if (s.defensive != Defensive::Cell)
      bad("sampling", "guided needs defensive=cell (its factors hold the defensive term)");
    if (s.reward != RewardKind::Cluster) bad("sampling", "guided needs reward=cluster");
    if (s.cold_uniform) bad("sampling", "guided needs cold=tree");
  }
  // Pooling needs the cut every cell shares: with growing cuts or the guided descent it is off
  // unless asked for (then an error).
  if (s.cut.pool_levels > 0 && (s.cut.splits > 0 || s.cut.guided)) {
    if (p.has(key("pool")))
      bad("pool", "needs splits=0 and sampling=table (a cut every cell shares)");
    s.cut.pool_levels = 0;
  }
  if (s.cut.pool_levels == 0) {
    if (p.has(key("pool_up")) && s.cut.pool_up > 0) bad("pool_up", "needs pooling (pool > 0)");
    s.cut.pool_up = 0;
  }
  if (s.cold_uniform && s.defensive == Defensive::Tree) bad("cold", "uniform needs defensive=cell");
  // Every key again (the base's too) and the rules between the cut's keys.
  check_params(cell_grid_params(), prefix, s.grid);
  check_params(rll_params(), prefix, s);
  check_cut_settings(s.cut, prefix);
  return s;
}

std::vector<std::string> describe_rll_params(const RllSettings& s, const std::string& prefix) {
  std::vector<std::string> out;
  for_each_rll_table(s, [&](const auto& table, const auto& part) {
    for (auto& line : describe_params(table, prefix, part)) out.push_back(std::move(line));
  });
  return out;
}

nlohmann::json rll_parameters_json(const RllSettings& s) {
  nlohmann::json out = nlohmann::json::object();
  for_each_rll_table(s,
                     [&](const auto& table, const auto& part) { params_json(table, part, out); });
  return out;
}

RllSettings fermat_settings() {
  RllSettings s;
  s.name = "fermat";
  s.cut.cut_size = s.cut.initial_size = 256;  // initial_cut() splits the node with most lights
  s.cut.target = LearnTarget::Mean;
  s.cut.rule = LearningRule::Exponential;
  s.cut.alpha = 0.05f;
  s.cut.threshold = 1;
  s.cut.splits = 1;
  s.cut.epsilon = 0.75f;  // P(s) = 0.75 / K + 0.25 Q(s) / sum Q from the first reward on
  s.cut.trust = 0;
  s.cut.pool_levels = 0;
  s.cut.pool_up = 0;
  s.cut.prior = ClusterWeight::Uniform;
  s.cut.split = ClusterWeight::Uniform;
  s.cut.q_init = 0.01f;
  s.within = WithinCluster::Power;  // for uniform among equal-energy virtual lights
  s.reward = RewardKind::Fermat;
  s.defensive = Defensive::Cell;
  s.cold_uniform = true;
  s.grid.footprint_scale = 32;  // cell radius min(32 R, 0.05 scene size)
  s.grid.max_cell = 0.05f;
  s.grid.level_rounding = CellGridSettings::LevelRounding::Stochastic;  // DESIGN 2, as PEERS says
  s.sample_jitter = 1.5f;
  s.reset_every = 32;
  return s;
}

}  // namespace rll
