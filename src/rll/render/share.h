// Renders split by samples over independent jobs, and their exact merge.
//
// Share I of N (`rll render --task I/N --spp S`) renders sample indices [I*S, (I+1)*S) of every
// pixel: the N shares together hold exactly the samples of one render of N*S spp with the same
// seed, so merging them (the mean of each pixel weighted by its sample count) gives that
// render's image to float rounding. Every EXR `rll render` writes carries what a merge needs:
// per pixel the number of samples behind it (channel "count"), and in the header (string
// attribute "rll.share", JSON) the settings all shares of one render must have in common, the
// split and which shares the image holds. A merged image carries the same, so merges merge.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rll/core/image.h"

namespace rll {

class Film;

inline constexpr const char* kShareAttribute = "rll.share";
inline constexpr int kShareVersion = 1;

struct RenderTask {
  int index = 0;  // I, 0 <= I < count
  int count = 1;  // N
};
// Parses "I/N" (0 <= I < N <= 1000000); throws rll::Error naming `flag`.
RenderTask parse_task(const std::string& text, const char* flag);

struct ShareInfo {
  // Everything the shares of one render share (scene fingerprint, resolution, integrator,
  // sampler, --set, points, seed, frame, passes): a merge compares every field.
  nlohmann::json settings = nlohmann::json::object();
  int tasks = 1;         // N
  int task_spp = 0;      // S: samples per pixel of each share
  std::vector<int> held;  // the shares whose samples the image holds, ascending
  std::string scene;     // as given on the command line, for messages (paths differ between machines)
  std::string commit;    // the rll build that rendered it: another build warns, it does not refuse
};

// The image of a film with its counts and share metadata.
ExrFile share_file(const Film& film, const ShareInfo& info);
// The share metadata of an EXR; throws rll::Error naming `file` if it has none or it is damaged.
ShareInfo read_share_info(const ExrFile& exr, const std::string& file);

struct MergeResult {
  ExrFile file;               // the merged image, with counts and metadata
  ShareInfo info;
  uint32_t min_count = 0;     // the fewest samples behind a pixel: the merged spp
  uint32_t max_count = 0;
  std::vector<int> missing;   // shares of the render that no input held
  std::vector<std::string> warnings;
};
// Merges share images: refuses (rll::Error naming the files and the field) inputs of different
// renders and shares given twice. Shares may be missing (a failed job): the result is still an
// unbiased image, with `missing` listing them.
MergeResult merge_shares(const std::vector<std::filesystem::path>& inputs);

// The largest |a - b| / max(|a|, |b|) over pixels and channels (0 where both are 0); infinite
// if the sizes differ.
double max_relative_difference(const Image& a, const Image& b);

// "1 of the 4 shares is missing: share 3 (--task 3/4)": which shares, by number and by the flag
// that renders each.
std::string missing_shares_text(const std::vector<int>& missing, int tasks);

}  // namespace rll
