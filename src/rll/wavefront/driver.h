// The wavefront renderer's loop over a batch of paths, written once for every device: the stages
// of wavefront/kernels.h launched over their queues, bounce after bounce, then the accumulation.
// A backend says how memory is taken and how a stage is launched: the host backend
// (wavefront.cpp) with host_parallel_for, the CUDA backend (cuda/wavefront.cu) with CUDA launches.
//
// A backend provides:
//   template <class T> View<T> take(size_t n)         memory for n elements (zeroed), kept with it
//   template <class Body> void launch(size_t n, const Body& body)      body(i) for i in [0, n)
//   template <class Body> void launch_queue(const WavefrontQueue& q, uint32_t upper,
//                                           const Body& body)   body(q.slots[k]) for k < q.count()
//   void zero(void* p, size_t bytes), void write(uint32_t* p, uint32_t v),
//   void copy(uint32_t* to, const uint32_t* from)       one word, in order with the launches
//   template <class T> T read(const T* p)               one value (waits for the launches)
//   template <class Fn> void timed(WavefrontStage s, const Fn& fn)   times what fn launches
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>

#include "rll/wavefront/kernels.h"
#include "rll/wavefront/stages.h"

namespace rll {

template <typename Backend, typename Tracer, typename Sampler>
class WavefrontDriver {
 public:
  using Kernels = WavefrontKernels<Tracer, Sampler>;

  // `k` holds the scene, camera, tables, tracer, sampler and film; the driver adds the path slots,
  // queues and tally, n_slots of each, taken from the backend once.
  WavefrontDriver(Backend& backend, const Kernels& k, size_t n_slots)
      : m_backend(backend), m_k(k), m_slots(n_slots) {
    auto take = [&]<typename T>(size_t n) { return m_backend.template take<T>(n); };
    m_k.p = PathSlots::make(take, n_slots);
    for (View<uint32_t>& q : m_k.queue_slots) q = m_backend.template take<uint32_t>(n_slots);
    m_k.queue_sizes = m_backend.template take<uint32_t>(kWavefrontQueues).data;
    m_k.tally = m_backend.template take<WavefrontTally>(1).data;
  }

  size_t slots() const { return m_slots; }
  // A sampler's view after the end of a pass (its tables may have moved).
  void set_sampler(const Sampler& s) { m_k.sampler = s; }
  const Kernels& kernels() const { return m_k; }

  // Runs every path of the batch to its end and adds them to the film; returns the batch's counts.
  WavefrontTally run_batch(const WavefrontBatch& b) {
    m_backend.zero(m_k.tally, sizeof(WavefrontTally));
    m_backend.timed(WavefrontStage::Camera, [&] {
      const Kernels k = m_k;
      const WavefrontBatch batch = b;
      m_backend.launch(b.n, [k, batch] RLL_HD(size_t i) { k.camera_stage(batch, uint32_t(i)); });
    });
    m_backend.write(&m_k.queue_sizes[kRays], b.n);
    for (uint32_t rays = b.n; rays > 0; rays = m_backend.read(&m_k.queue_sizes[kRays])) {
      m_backend.zero(&m_k.queue_sizes[kNextRays],
                     sizeof(uint32_t) * (kWavefrontQueues - kNextRays));
      stage<WavefrontStage::ClosestHit>(kRays, b.n);
      stage<WavefrontStage::Emission>(kHits, b.n);
      stage<WavefrontStage::NeeSample>(kNee, b.n);
      stage<WavefrontStage::Shadow>(kShadows, b.n);
      stage<WavefrontStage::NeeFinish>(kNee, b.n);
      if (m_k.sampler.learns) stage<WavefrontStage::Rewards>(kNee, b.n);
      stage<WavefrontStage::BsdfSample>(kBounces, b.n);
      // The next bounce's rays become this one's.
      std::swap(m_k.queue_slots[kRays], m_k.queue_slots[kNextRays]);
      m_backend.copy(&m_k.queue_sizes[kRays], &m_k.queue_sizes[kNextRays]);
    }
    m_backend.timed(WavefrontStage::Accumulate, [&] {
      const Kernels k = m_k;
      const WavefrontBatch batch = b;
      m_backend.launch(b.pixels(),
                       [k, batch] RLL_HD(size_t j) { k.accumulate_stage(batch, uint64_t(j)); });
    });
    return m_backend.read(m_k.tally);
  }

  // Launches stage S over the slots of queue `q` (at most `upper` of them). (Public: CUDA's
  // extended lambdas may not live in private member functions.)
  template <WavefrontStage S>
  void stage(WavefrontQueueId q, uint32_t upper) {
    m_backend.timed(S, [&] {
      const Kernels k = m_k;
      m_backend.launch_queue(k.queue(q), upper, [k] RLL_HD(uint32_t i) { k.template run<S>(i); });
    });
  }

 private:
  Backend& m_backend;
  Kernels m_k;
  size_t m_slots;
};

}  // namespace rll
