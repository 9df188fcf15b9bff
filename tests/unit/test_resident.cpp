// A learning sampler's state lent to a device's copy (lights/resident.h), with a copy on the host
// standing in for the GPU's (cuda/device_rll.cuh, which no GPU here runs): while lent, the
// sampler's end of pass and lights_changed run on the copy and nothing is pulled back; the first
// host read (sampler_view) pulls it, once; a copy that goes first hands the state back, a sampler
// that goes first is forgotten; and the learnt result is the same to the bit as the host's own.
#include <gtest/gtest.h>

#include <bit>

#include "rll/lights/light_dispatch.h"
#include "rll/lights/resident.h"
#include "support/rll_twins.h"

using namespace rll;
using namespace rll::test;

namespace {

// Works on the learner's own host arrays (the views resident_state gives) with a pool of its own,
// counting what the learner asks of it.
class HostCopy final : public DeviceCopy {
 public:
  explicit HostCopy(ResidentLearner& learner) {
    const ResidentState s = learner.resident_state();
    m_learn = s.learn;
    m_pool = *s.pool;
    learner.lend_to(*this);
    m_learner = &learner;
  }
  ~HostCopy() {
    if (m_learner) m_learner->sync();
  }
  void pull(RllPoolState<HostBackend>& pool) override {
    ++pulls;
    m_learner = nullptr;
    pool = m_pool;
  }
  RllPassCounts end_pass(const RllLearnView& host, uint32_t used_before, bool reset) override {
    ++end_passes;
    m_learn.keyer = host.keyer;
    return rll_end_pass(HostBackend{}, m_learn, m_pool, m_scratch, used_before, reset);
  }
  void view_changed(const RllView&) override { ++views; }
  void lights_changed(const LightTreeView&, View<const double>) override {
    ++lights;
    rll_lights_changed(HostBackend{}, m_learn, m_pool, m_scratch);
  }
  void forget() override { m_learner = nullptr; }
  bool holds(const ResidentLearner& l) const { return m_learner == &l; }
  bool holds_any() const { return m_learner != nullptr; }

  int pulls = 0, end_passes = 0, views = 0, lights = 0;

 private:
  ResidentLearner* m_learner = nullptr;
  RllLearnView m_learn;
  RllPoolState<HostBackend> m_pool;
  RllScratch<HostBackend> m_scratch;
};

// One pass of next-event samples through the views taken before (a lent sampler's are not taken
// again: that would pull its state back), the same for both.
void feed(RllTwins& t, const SamplerView& va, const SamplerView& vb, Pcg32& rng) {
  for (const LightContext& c : t.contexts) {
    LightContext ca = c, cb = c;
    const float up = rng.next_float();
    const double u = rng.next_double();
    NeeRecord r;
    r.estimate = r.unoccluded = r.max_rgb = rng.next_float() < 0.4f ? 0.0f : rng.next_float();
    prepare_point(va, ca, up);
    prepare_point(vb, cb, up);
    const SampledLight sa = sample_light(va, ca, u), sb = sample_light(vb, cb, u);
    ASSERT_EQ(sa.light, sb.light);
    if (sa.pmf > 0) record_nee(va, ca, sa, r);
    if (sb.pmf > 0) record_nee(vb, cb, sb, r);
  }
}

TEST(Resident, LentStateLearnsAsTheHostsAndIsPulledOnce) {
  for (const char* sampler : {"rll", "fermat"}) {
    SCOPED_TRACE(sampler);
    RllTwins t("cornell-boxes-room", sampler,
               std::string(sampler) == "rll" ? std::vector<std::string>{"rll.pool=1"}
                                             : std::vector<std::string>{});
    ASSERT_EQ(t.b->resident_learner(), static_cast<ResidentLearner*>(t.b.get()));
    const SamplerView va = t.a->sampler_view(), vb = t.b->sampler_view();
    Pcg32 rng(9);
    {
      HostCopy copy(*t.b);
      ASSERT_EQ(t.b->lent_to(), &copy);
      for (int pass = 0; pass < 3; ++pass) {
        feed(t, va, vb, rng);
        t.a->end_pass();
        t.b->end_pass();  // on the copy
      }
      t.a->lights_changed(t.scene);
      t.b->lights_changed(t.scene);
      EXPECT_EQ(copy.end_passes, 3);
      EXPECT_EQ(copy.lights, 1);
      EXPECT_EQ(copy.views, 4) << "each end of pass and lights_changed tell the copy";
      EXPECT_EQ(copy.pulls, 0) << "pulled back while lent";
      t.b->sampler_view();  // a host read
      EXPECT_EQ(copy.pulls, 1);
      EXPECT_EQ(t.b->lent_to(), nullptr);
      EXPECT_FALSE(copy.holds(*t.b));
      t.b->sampler_view();
      EXPECT_EQ(copy.pulls, 1) << "pulled twice";
    }
    EXPECT_EQ(t.a->passes(), t.b->passes());
    const SamplerView fa = t.a->sampler_view(), fb = t.b->sampler_view();
    for (size_t i = 0; i < t.contexts.size(); i += 3) {
      LightContext ca = t.contexts[i], cb = t.contexts[i];
      prepare_point(fa, ca, 0.5f);
      prepare_point(fb, cb, 0.5f);
      for (uint32_t l = uint32_t(i % 5); l < t.scene.lights.size(); l += 5)
        ASSERT_EQ(std::bit_cast<uint32_t>(light_pmf(fa, ca, l)),
                  std::bit_cast<uint32_t>(light_pmf(fb, cb, l)))
            << "context " << i << " light " << l;
    }
  }
}

TEST(Resident, ACopyThatGoesFirstHandsTheStateBackAndASamplerThatGoesFirstIsForgotten) {
  RllTwins t("cornell-boxes-room", "rll", {});
  {
    HostCopy copy(*t.b);
    t.b->end_pass();
    EXPECT_EQ(copy.pulls, 0);
    // (its destructor hands the state back)
  }
  EXPECT_EQ(t.b->lent_to(), nullptr);
  auto copy = std::make_unique<HostCopy>(*t.b);
  ASSERT_TRUE(copy->holds(*t.b));
  t.b.reset();
  EXPECT_FALSE(copy->holds_any()) << "the copy still holds a sampler that is gone";
  copy.reset();  // (must not touch the sampler)
  // A frozen learner is not one: its tables are uploaded whole.
  t.a->freeze();
  EXPECT_EQ(t.a->resident_learner(), nullptr);
}

}  // namespace
