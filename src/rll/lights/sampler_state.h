// A light sampler's learnt state in a file (`rll render --rll-state`), so that a render starts
// from what an earlier one learnt: shares of a render on other machines skip the warm-up.
//
// The file is versioned and tied to what the state means: the scene (its fingerprint, which
// covers the resolution), the sampler's name and its parameters. A state of another scene,
// sampler, parameters or format version is refused with a message naming what differs; a
// truncated or damaged file is an error, never a crash. Written atomically.
#pragma once

#include <cstdint>
#include <filesystem>

namespace rll {

class LightSampler;

inline constexpr uint32_t kSamplerStateVersion = 2;

// Throws rll::Error if the sampler learns nothing that can be saved.
void check_sampler_has_state(const LightSampler& sampler, const char* flag);
// `scene_fingerprint` is Scene::fingerprint() of the scene as loaded, before any animation
// frame moved its lights: the state of an animation's last frame loads at the start of the
// next render of it.
void save_sampler_state(const std::filesystem::path& path, const LightSampler& sampler,
                        uint64_t scene_fingerprint);
void load_sampler_state(const std::filesystem::path& path, LightSampler& sampler,
                        uint64_t scene_fingerprint);

}  // namespace rll
