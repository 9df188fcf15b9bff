// The learning's parameters as tables (core/param_table.h), each key with its range or choices
// written once: CutSettings' (the cut and its learning) and CellGridSettings' (the cells), read
// under a sampler's prefix (rll., fermat.) by lights/rll_settings.cpp, checked by CutStore, and
// listed by `rll samplers --params NAME`. Host code only.
#pragma once

#include <string>
#include <vector>

#include "rll/core/param_table.h"
#include "rll/learn/cell_grid.h"
#include "rll/learn/cut_settings.h"

namespace rll {

const std::vector<ParamSpec<CutSettings>>& cut_params();
const std::vector<ParamSpec<CellGridSettings>>& cell_grid_params();

// Every parameter of `s` in its range, and the rules between them (initial_cut <= cut_size;
// pooling needs a shared cut: splits=0 and sampling=table; the guided descent keeps its cut);
// errors name PREFIX.KEY.
void check_cut_settings(const CutSettings& s, const std::string& prefix);

}  // namespace rll
