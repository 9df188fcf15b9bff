// High-sample reference images, cached on disk and keyed by a hash of the finalized scene's
// content and of the integrator settings, so that `rll compare` reuses what `rll reference`
// (or an earlier compare) rendered, and a changed scene never meets a stale reference.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "rll/core/image.h"
#include "rll/render/integrator.h"
#include "rll/scene/scene.h"

namespace rll {

// Bump when a change of the renderer changes the expected value of an image (a fixed BSDF, a new
// integrator setting with a non-neutral default): every cached reference becomes stale.
inline constexpr int kReferenceCacheVersion = 1;

// Hash of the integrator settings (and kReferenceCacheVersion).
uint64_t integrator_settings_hash(const IntegratorSettings& settings);

struct ReferenceKey {
  uint64_t scene = 0;       // Scene::fingerprint
  uint64_t settings = 0;    // integrator_settings_hash
  std::string hex() const;  // 32 hex digits, the prefix of the cache entry's file names
  bool operator==(const ReferenceKey&) const = default;
};
ReferenceKey reference_key(const Scene& scene, const IntegratorSettings& settings);

// $RLL_CACHE_DIR when set and not empty, otherwise out/cache.
std::filesystem::path default_cache_dir();

// One cached reference: the image and what it was rendered with. A reference is rendered as two
// independent halves of equal spp (seeds `seed` and `seed + 1`), so that its own per-pixel noise
// can be estimated and subtracted from the errors measured against it (metrics.h); the cache
// keeps their mean and the first half.
struct ReferenceInfo {
  std::filesystem::path image;  // the .exr in the cache (the mean of the halves)
  std::filesystem::path half;   // the first half's .exr; empty for an entry made without halves
  std::string scene;            // the scene spec it was loaded from (absolute path for files)
  int width = 0, height = 0;
  std::string sampler;
  int spp = 0;
  uint64_t seed = 0;
  double seconds = 0;
  // The frame of an animated scene it shows (ReferenceRequest::frame), -1 for a static scene:
  // the cache keeps one entry per frame.
  int frame = -1;
};

// A folder of references: for key K, K-<spp>spp-seed<seed>.exr and a .json beside it.
class ReferenceCache {
 public:
  explicit ReferenceCache(std::filesystem::path dir) : m_dir(std::move(dir)) {}
  const std::filesystem::path& dir() const { return m_dir; }

  // The entry for `key` with the most samples among those with at least `min_spp` (and, when
  // `seed_allowed` is given, a seed it accepts); nullopt if there is none. Unreadable entries
  // are ignored.
  std::optional<ReferenceInfo> find(const ReferenceKey& key, int min_spp,
                                    const std::function<bool(uint64_t)>& seed_allowed = {}) const;
  // Stores `image` (and the first half, when given) under `key`, creating the folder, and returns
  // the stored entry. Entries of the same scene spec, resolution and settings whose scene content
  // differs are deleted: the scene changed since they were rendered.
  ReferenceInfo store(const ReferenceKey& key, const Image& image, ReferenceInfo info,
                      const Image* first_half = nullptr) const;
  // Deletes an entry's files (a damaged one).
  void remove(const ReferenceInfo& info) const;
  // Deletes temporaries (`*.tmp-PID-N`) left by writes that were killed: those of processes that
  // no longer run. Returns how many were deleted.
  int remove_stale_temporaries() const;
  // Creates the folder and checks that files can be written in it (before a render, rather than
  // after); throws rll::Error naming it.
  void check_writable() const;

 private:
  std::filesystem::path m_dir;
};

// The scene spec as stored in the cache: files by absolute path, builtin:NAME as is.
std::string canonical_scene_spec(const std::string& spec);

class RenderSession;

// Far from the small seeds that comparisons use, so that a reference never shares its random
// numbers (and hence its noise) with a render it is compared with.
inline constexpr uint64_t kDefaultReferenceSeed = 1000003;

// True if a reference of seed `s` (halves s and s + 1) shares a seed with runs of seeds
// [run_seed, run_seed + repeats), and so their noise: compare never measures against one.
inline bool reference_shares_a_seed(uint64_t s, uint64_t run_seed, int repeats) {
  auto is_run = [&](uint64_t x) { return x >= run_seed && x - run_seed < uint64_t(repeats); };
  return is_run(s) || is_run(s + 1);
}

struct ReferenceRequest {
  // Tree sampling: visibility-blind, without learning state, and far better behaved than power
  // on occluded scenes (whose lamps power sampling gives pmfs near 1e-7).
  std::string sampler = "tree";
  int spp = 1024;                         // at least this many samples per pixel
  uint64_t seed = kDefaultReferenceSeed;  // of the first half; the second half uses seed + 1
  int pass_spp = 1, max_pass_spp = 8;     // as in RenderSettings
  bool force = false;                     // render and store even when the cache holds one
  // The frame of an animated scene the session has moved to (RenderSession::set_frame), -1 for
  // a static scene: storing it leaves the other frames' entries in the cache (they differ in
  // content from it, as an edited scene's would).
  int frame = -1;
  // When given, cached references with a seed it rejects are not used.
  std::function<bool(uint64_t)> seed_allowed;
};

struct ObtainedReference {
  Image image;
  // Per pixel and channel, the variance of `image` estimated from its two halves; empty (0x0)
  // when the cached entry was made without halves.
  Image variance;
  ReferenceInfo info;
  bool from_cache = false;
  bool complete = true;  // false: the render was cancelled; it was not stored
  // When not complete: the samples behind each pixel of `image` (both halves' so far).
  std::vector<uint32_t> counts;
};

// The cached reference for the session's scene and integrator with at least request.spp, or a
// new one rendered as two halves of ceil(spp / 2) samples (progress bars labelled "reference
// 1/2" and "2/2") and stored in the cache. A cache entry that cannot be read back (truncated,
// wrong size, non-finite pixels) is reported, deleted and rendered again.
// What summary.json says of an obtained reference: source (cache or rendered), cache_entry,
// sampler, spp, seed, seconds and, where its variance is known, noise_relmse
// (reference_noise_relmse).
nlohmann::json reference_json(bool from_cache, const ReferenceInfo& info, const Image& image,
                              const Image& variance);

ObtainedReference obtain_reference(const RenderSession& session, const ReferenceCache& cache,
                                   const ReferenceRequest& request, bool show_progress,
                                   const std::atomic<bool>* cancel = nullptr);

}  // namespace rll
