#include "rll/learn/cut_params.h"

#include "rll/core/error.h"

namespace rll {

const std::vector<ParamSpec<CutSettings>>& cut_params() {
  using S = CutSettings;
  using R = ParamRange;
  static const std::vector<ParamSpec<S>> table = {
      int_param("cut_size", R::closed(2, kMaxCutSize), field<S, &S::cut_size>()),
      int_param("initial_cut", R::closed(1, kMaxCutSize), field<S, &S::initial_size>()),
      int_param("splits", R::closed(0, kMaxCutSize), field<S, &S::splits>()),
      float_param("T", R::at_least(1), field<S, &S::threshold>()),
      choice_param("target", {"moment", "mean"}, field<S, &S::target>()),
      float_param("alpha", R::open_closed(0, 1), field<S, &S::alpha>()),
      choice_param("forget", {"changes", "floor"}, field<S, &S::forget>()),
      float_param("change_z", R::closed(0, 1000), field<S, &S::change_z>(), "0: no change test"),
      choice_param("learning", {"shrinkage", "exponential"}, field<S, &S::rule>()),
      float_param("prior_samples", R::positive(), field<S, &S::prior_samples>()),
      float_param("epsilon", R::open_closed(0, 1), field<S, &S::epsilon>(),
                  "it keeps the estimator unbiased"),
      int_param("pool", R::closed(0, 8), field<S, &S::pool_levels>()),
      float_param("pool_weight", R::at_least(0), field<S, &S::pool_weight>()),
      choice_param("pool_guess", {"share", "ratio"}, field<S, &S::pool_ratio>()),
      int_param("pool_up", R::closed(0, 8), field<S, &S::pool_up>()),
      float_param("trust", R::at_least(0), field<S, &S::trust>()),
      choice_param("prior", {"importance", "power", "uniform"}, field<S, &S::prior>()),
      choice_param("split_by", {"importance", "power", "uniform"}, field<S, &S::split>()),
      float_param("q_init", R::at_least(0).or_value(-1), field<S, &S::q_init>(),
                  "-1: the visited clusters' estimate"),
      choice_param("sampling", {"table", "guided"}, field<S, &S::guided>()),
  };
  return table;
}

const std::vector<ParamSpec<CellGridSettings>>& cell_grid_params() {
  using S = CellGridSettings;
  using R = ParamRange;
  static const std::vector<ParamSpec<S>> table = {
      float_param("footprint_scale", R::positive(), field<S, &S::footprint_scale>()),
      float_param("max_cell", R::open_closed(0, 1), field<S, &S::max_cell>()),
      choice_param("level_rounding", {"stochastic", "nearest"}, field<S, &S::level_rounding>()),
      int_param("normal_bins", R::closed(1, 64), field<S, &S::normal_bins>()),
      float_param("jitter", R::closed(0, 1), field<S, &S::jitter>()),
      int_param("direction_bins", R::closed(0, 16), field<S, &S::direction_bins>()),
  };
  return table;
}

void check_cut_settings(const CutSettings& s, const std::string& prefix) {
  check_params(cut_params(), prefix, s);
  auto key = [&](const char* k) { return prefix + "." + k; };
  if (s.initial_size > s.cut_size)
    fail("--set {}: must be in [1, {} = {}] (got {})", key("initial_cut"), key("cut_size"),
         s.cut_size, s.initial_size);
  if (s.guided && s.splits > 0)
    fail("--set {}: needs {}=table (the guided descent keeps its cut)", key("splits"),
         key("sampling"));
  if (s.pool_levels > 0 && (s.splits > 0 || s.guided))
    fail("--set {}: needs {}=0 and {}=table (a cut every cell shares)", key("pool"), key("splits"),
         key("sampling"));
  if (s.pool_levels == 0 && s.pool_up > 0)
    fail("--set {}: needs pooling ({} > 0)", key("pool_up"), key("pool"));
}

}  // namespace rll
