// The settings of RLL's per-cell cuts and their learning (CutSettings, read from rll.* or
// fermat.* by lights/rll_settings.cpp): the cut's size, the learning rule and its forgetting,
// the target, the prior, the defensive weight, pooling and the guided descent.
#pragma once

namespace rll {

// How Q and M2 follow the rewards. Shrinkage: the mean of the rewards and of the prior estimate
// counted as `prior_samples` rewards (a learning rate that starts at 1/n), forgetting as
// `Forgetting` says. Exponential: the paper's Q := (1-a) Q + a r per reward.
enum class LearningRule { Shrinkage, Exponential };

// How the shrinkage rule forgets (rll.forget). Changes: the mean of all of a cluster's rewards
// (the rate stays 1/n, so a static cell keeps sharpening), cut back to the last 1/alpha rewards
// where a pass's rewards fail the change test (change_test) and, for every cluster, when the
// lights change. Floor: the last 1/alpha rewards at most, for good (v2: the rate settles at the
// floor alpha).
enum class Forgetting { Changes, Floor };

// What a cell samples clusters in proportion to: sqrt(M2), the variance-optimal target of a
// one-sample estimator (DESIGN 2b), or the mean Q (the paper).
enum class LearnTarget { Moment, Mean };

// How a cluster's prior weight and a split's share of Q are estimated: from the light tree's
// importance of the node at the cell's anchor (spatial, visibility-blind), from the node's
// power alone, or equal for every cluster (Fermat's RLL: a uniform defensive term over the
// clusters, Q split half and half).
enum class ClusterWeight { Importance, Power, Uniform };

// The largest M (rll.cut_size) a CutStore accepts (the end of pass's scratch, CutScratch in
// learn/cut_end_pass.h, is sized by each cell's cut, not by this bound).
inline constexpr int kMaxCutSize = 4096;

struct CutSettings {
  int cut_size = 128;      // M, the most clusters of a cell (at most kMaxCutSize)
  int initial_size = 128;  // clusters of a new cell's cut (the shared initial cut), <= M
  // The shrinkage rule's memory after a change (forget=changes) or always (forget=floor): the
  // last 1/alpha rewards; the exponential rule's rate.
  float alpha = 0.02f;
  Forgetting forget = Forgetting::Changes;
  // The change test's threshold (forget=changes): a pass's mean of a cluster's rewards that
  // differs from the running mean by more than change_z standard errors is a change; 0: no test
  // (only a change of the lights forgets).
  float change_z = 5;
  float threshold = 2;   // T: split l_max and collapse p_min if score(l_max) > T value(p_min)
  int splits = 0;        // split-collapse steps per cell and pass (0: the cut stays as it started)
  float epsilon = 0.1f;  // weight of the defensive prior once a cell is trusted
  LearnTarget target = LearnTarget::Moment;
  ClusterWeight prior = ClusterWeight::Importance;
  // True: the CDF is (1-e) V/sum V + e prior (the defensive prior per cell, folded in). False:
  // the CDF holds the learnt distribution alone, the sampler mixing in its own defensive term.
  bool prior_in_cdf = true;
  LearningRule rule = LearningRule::Shrinkage;
  float prior_samples = 4;  // n0 of the shrinkage rule
  // Rewards a cell must have seen before its learnt distribution gets half the weight the
  // defensive term does not take: the cell's defensive weight is
  // e + (1 - e) * trust / (trust + rewards seen).
  float trust = 256;
  // Pooling (rll.pool=L, 0: off): every pass, the rewards of all cells whose anchors fall in
  // one cell L levels coarser are pooled, and that coarse cell learns Q and M2 of its own; a
  // cell's values are then shrunk toward the coarse cell's distribution (scaled to the cell's
  // own total) with the weight of `pool_weight` rewards per cluster, in place of the
  // visibility-blind prior for clusters the cell has not visited. Needs a cut shared by every
  // cell (splits = 0).
  int pool_levels = 0;  // (rll's default is 1: RllSettings)
  float pool_weight = 8;
  // What the coarse cell learns (rll.pool_guess): false (share), Q and M2 of the pooled
  // rewards, its distribution taken as the cell's; true (ratio), of the rewards divided by each
  // cell's own prior share of their cluster, so that the guess is the cell's prior times the
  // coarse cell's factor per cluster (visibility seen by the neighbours, the light's falloff
  // seen at the cell's own anchor).
  bool pool_ratio = false;
  // Pooling in two tiers (rll.pool_up=U, 0: off): a coarse cell's values are themselves shrunk,
  // by the same rule and weight, toward those of the cell U levels coarser still, which pools
  // every cell under it; where the first tier has few rewards of a cluster, the second speaks.
  int pool_up = 0;
  // Tiers of coarse cells: 0 without pooling, 2 with pool_up.
  int pool_tiers() const { return pool_levels > 0 ? 1 + (pool_up > 0) : 0; }
  ClusterWeight split = ClusterWeight::Importance;
  // The value of a cluster never visited: < 0, the visited clusters' estimate of the cell's total
  // shared by prior; >= 0, this constant (Fermat's RLL starts every Q at 0.01).
  float q_init = -1;
  // The guided descent (rll.sampling=guided): the values learnt are each cluster's ratio of its
  // reward to the light tree's importance of its node at the point, and the cell bakes, for
  // every inner node above its cut, the factors by which a descent from the root scales its
  // children's importances (guide_left/right) instead of a table over the clusters.
  bool guided = false;
  // Finer cells where the light changes (rll.refine=L, 0: off; docs/rll.md): every pass a cell
  // notes, per cluster, the rewards of the points in the upper half of its box along one axis
  // (x, y, z in turn); at the end of the pass, where giving each half its own distribution would
  // lower the cost of the one-sample estimator by more than `refine_gain` (a fraction), with at
  // least `refine_min` rewards, the cell is marked refined, and its points look up the cell one
  // level finer instead, down to L levels below their own.
  int refine = 0;
  float refine_gain = 0.5f;
  int refine_min = 256;
};

}  // namespace rll
