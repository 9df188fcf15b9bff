// A learning sampler's state kept by a device between passes and renders (`rll render --device
// cuda`, `rll interactive`), as two small interfaces rather than callbacks inside the sampler or
// a cast in the renderer. The device's copy (cuda/device_rll.cuh: owned by the GPU renderer, which
// the render session owns) is made from a ResidentLearner's state (rll and fermat while they
// learn: LightSampler::resident_learner()) and lent the state; the learner then runs its end of
// pass and lights_changed on the copy (DeviceCopy), and takes the state back (sync) before the
// host reads or changes it otherwise. Plain C++: the host's code needs no nvcc.
#pragma once

#include <cstdint>

#include "rll/core/backend.h"
#include "rll/lights/rll_learn_view.h"
#include "rll/lights/rll_pool.h"
#include "rll/lights/rll_view.h"

namespace rll {

// The device's copy as the learner sees it while the copy holds its state.
class DeviceCopy {
 public:
  // Copies the device's arrays back into the learner's host arrays and its coarse cells into
  // `pool`; the copy is no longer the learner's.
  virtual void pull(RllPoolState<HostBackend>& pool) = 0;
  // rll_end_pass on the copy with this pass's keyer (host.keyer); its counters.
  virtual RllPassCounts end_pass(const RllLearnView& host, uint32_t used_before, bool reset) = 0;
  // After the learner's end of pass or lights_changed: its next pass, keyer and free cells.
  virtual void view_changed(const RllView& host) = 0;
  // The lights moved or switched (the tree refit on the host, same shape): the tree and the
  // powers copied in, rll_lights_changed run on the copy.
  virtual void lights_changed(const LightTreeView& tree, View<const double> power_prefix) = 0;
  // The learner is going away: the copy is no longer its (nothing to copy back).
  virtual void forget() = 0;

 protected:
  ~DeviceCopy() = default;
};

// What a device's copy is made from: the learner's host arrays, current.
struct ResidentState {
  RllLearnView learn;                               // what the end of pass reads and writes
  const RllView* view = nullptr;                    // the sampling view, over the same arrays
  const RllPoolState<HostBackend>* pool = nullptr;  // the coarse cells of pooling
};

// The learner's side.
class ResidentLearner {
 public:
  // Its state, taken back first from any device that holds it.
  virtual ResidentState resident_state() = 0;
  // `copy` holds the state from now on (made from resident_state()).
  virtual void lend_to(DeviceCopy& copy) = 0;
  // Takes the state back from the copy that holds it (DeviceCopy::pull); nothing if none does.
  virtual void sync() const = 0;

 protected:
  ~ResidentLearner() = default;
};

}  // namespace rll
