// Per-pixel diagnostics of the light sampler (`rll render --aov`, rll.render(aov=...)), measured
// at each sample's camera vertex (the first surface its path hit): the cell of the point, the pmf
// of the light its next-event sample chose, the entropy and rewards of the cell's learnt cluster
// distribution, the share of its shadow rays that reached their light. Reading them changes
// nothing the render computes: the image is the same to the bit with and without.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "rll/lights/light_sampler.h"
#include "rll/render/film.h"

namespace rll {

class CutStore;
class RllLightSampler;

enum class Aov { Cell, Probability, Entropy, Visible, Rewards };

struct AovInfo {
  Aov kind;
  const char* name;     // as --aov takes it; the EXR channel is "aov.<name>"
  const char* meaning;  // for --help and messages
};
// Every diagnostic, in the order they are listed and written.
const std::vector<AovInfo>& aov_list();
// "NAME[,NAME]" as a list (in the order given); an unknown or repeated name is an rll::Error
// naming `flag` and listing the valid names.
std::vector<Aov> parse_aovs(const std::string& list, const char* flag);
const char* aov_name(Aov aov);

// The RLL sampler holding the cells of `sampler` (rll and fermat themselves, the oracle's frozen
// one), or null for a sampler without cells.
const RllLightSampler* sampler_cells(const LightSampler& sampler);
// Entropy in bits of the cell's baked cluster distribution; NaN for a cell without a cut of its
// own (it samples by the light tree) or without a table (rll.sampling=guided).
double cell_entropy(const CutStore& cuts, uint32_t cell);

// The diagnostics of a film that tracked its camera vertices (Film::track_camera_vertex), after
// rendering with `sampler`: per diagnostic its channel name ("aov.<name>") and one value per
// pixel, row by row from the top. `cell`: the cell of the pixel's last sample (-1: none);
// `probability`: the mean pmf of the lights chosen; `visible`: shadow rays that reached their
// light over all light samples; `entropy`, `rewards`: of the pixel's cell in the sampler's state
// at the end; NaN where a pixel has nothing to measure.
std::vector<std::pair<std::string, std::vector<float>>> resolve_aovs(const Film& film,
                                                                     const LightSampler& sampler,
                                                                     const std::vector<Aov>& aovs);

// A false colour per cell id (-1, no cell: black), for looking at the `cell` diagnostic:
// neighbouring ids get unrelated colours.
Rgb cell_colour(float id);

}  // namespace rll
