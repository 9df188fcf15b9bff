#include "rll/render/psf.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <nlohmann/json.hpp>

#include "rll/core/error.h"
#include "rll/core/memory_budget.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"

namespace rll {

const std::vector<ParamSpec<PsfSettings>>& psf_params() {
  using S = PsfSettings;
  static const std::vector<ParamSpec<S>> table = {
      int_param("depth", ParamRange::closed(0, 10000).or_value(-1), field<S, &S::depth>(),
                "-1 is Fermat's default: the first bounce for path, the camera vertex for direct"),
      float_param("width", ParamRange::open_closed(0, 1e6), field<S, &S::width>(),
                  "the cell radius in ray footprints"),
      float_param("max_prob", ParamRange::positive(), field<S, &S::max_prob>(),
                  "the largest pdf of the bounce before a cut"),
      float_param("min_dist", ParamRange::at_least(0), field<S, &S::min_dist>()),
      float_param("clamp", ParamRange::at_least(0), field<S, &S::clamp>(), "0 clamps nothing"),
      float_param("temporal", ParamRange{0, 1, false, true}, field<S, &S::temporal>(),
                  "the weight of the sample before in frames that follow frames; 0 is off"),
      int_param("demodulate", ParamRange::closed(0, 1), field<S, &S::demodulate>(),
                "1 filters the diffuse lobe divided by its albedo and sends the glossy lobe to the "
                "film; 0 filters the whole radiance"),
  };
  return table;
}

const std::vector<std::string>& filter_names() {
  static const std::vector<std::string> names = {"none", "psf"};
  return names;
}

PsfSettings make_psf_settings(const std::string& filter, int max_depth, bool path,
                              const Params& params) {
  PsfSettings s;
  if (filter != "none" && filter != "psf")
    fail("--filter '{}': expected none or psf", shown_text(filter));
  if (filter == "none") {
    // A psf.* key without the filter would silently do nothing.
    for (const auto& [key, value] : params.values())
      if (key.rfind("psf.", 0) == 0)
        fail("--set {}: a parameter of the path-space filter, which renders only with --filter psf",
             shown_text(key));
    return s;
  }
  s.on = true;
  read_params(psf_params(), params, "psf", s);
  if (s.depth < 0) s.depth = path ? std::min(1, max_depth - 1) : 0;  // (path at depth 1: 0)
  // Vertices 0 .. max_depth - 1 sample light and bounce; a cut further along filters nothing.
  if (s.depth >= max_depth)
    fail(
        "--set psf.depth={}: past the last vertex the {} integrator shades ({} with --max-depth "
        "{}): the filter would filter nothing",
        s.depth, path ? "path" : "direct", max_depth - 1, max_depth);
  return s;
}

PsfConstants make_psf_constants(const PsfSettings& s, const Bounds3& scene_bounds) {
  PsfConstants c;
  if (!s.on) return c;
  c.on = true;
  c.depth = s.depth;
  c.max_prob = s.max_prob;
  c.min_dist = s.min_dist;
  c.clamp = s.clamp;
  c.temporal = s.temporal;
  c.demodulate = s.demodulate;
  // Fermat's hash: a cell of `width` footprints in radius, at most the scene's extent across,
  // the level of detail rounded at random, 4 bins per axis of the normal's square map; the
  // jitter is each path's own (psf_key), never the pass's.
  CellGridSettings g;
  g.footprint_scale = s.width;
  g.max_cell = 0.5f;
  g.normal_bins = 4;
  g.jitter = 0;
  g.level_rounding = CellGridSettings::LevelRounding::Stochastic;
  c.keyer = CellKeyer(g, scene_bounds);
  return c;
}

nlohmann::json filter_json(const PsfSettings& s, const PsfCounts* counts, uint64_t samples,
                           size_t temporal_bytes) {
  if (!s.on) return {{"name", "none"}};
  nlohmann::json j = {{"name", "psf"}};
  params_json(psf_params(), s, j);
  if (counts) {
    j["batches"] = counts->batches;
    j["cells_used"] = counts->cells;
    j["cells_per_batch"] =
        counts->batches > 0 ? double(counts->cells) / double(counts->batches) : 0.0;
    j["paths_filtered"] = counts->paths;
    j["filtered_share"] = samples > 0 ? double(counts->paths) / double(samples) : 0.0;
    if (s.temporal > 0) {
      j["cells_reused"] = counts->reused;
      j["temporal_bytes"] = temporal_bytes;
    }
  }
  return j;
}

void check_psf_memory(size_t pixels, bool temporal) {
  const double bytes = kPsfBytesPerPixel + (temporal ? kPsfTemporalBytesPerPixel : 0.0);
  check_memory_budget(
      double(pixels) * bytes,
      fmt::format("the path-space filter's cells and path records{} for {} pixels "
                  "({} bytes a pixel)",
                  temporal ? ", with the cells of the sample before (psf.temporal)" : "", pixels,
                  bytes));
}

PsfTable::PsfTable(size_t pixels, bool cells) {
  check_psf_memory(pixels);
  if (cells) {
    m_keys.resize(psf_capacity(pixels));
    m_sums.resize(6 * m_keys.size());
  }
  m_records.resize(pixels);
  m_ends.resize(pixels);
}

PsfHistory::PsfHistory(size_t pixels) {
  check_psf_memory(pixels, true);
  const size_t cells = psf_capacity(pixels);
  for (int i = 0; i < 2; ++i) {
    m_keys[i].resize(cells);
    m_sums[i].resize(6 * cells);
    m_cells.tables[i] = {view_of(m_keys[i]), view_of(m_sums[i]), &m_used[i]};
  }
  m_cells.pixels = pixels;
}

namespace {
// Large tables are cleared in parallel: a 1080p frame's are 450 MB, cleared every sample.
void zero_in_parallel(void* data, size_t bytes) {
  constexpr size_t kChunk = size_t(1) << 20;
  unsigned char* p = static_cast<unsigned char*>(data);
  parallel_for((bytes + kChunk - 1) / kChunk, 1, [&](size_t begin, size_t end) {
    const size_t from = begin * kChunk, to = std::min(bytes, end * kChunk);
    std::memset(p + from, 0, to - from);
  });
}
}  // namespace

void clear_psf_cells(const PsfTableView& t) {
  zero_in_parallel(t.keys.data, t.keys.size * sizeof(uint64_t));
  zero_in_parallel(t.sums.data, t.sums.size * sizeof(ExactSum));
  *t.used = 0;
}

void PsfTable::clear() {
  clear_psf_cells(view());
  zero_in_parallel(m_records.data(), m_records.size() * sizeof(PsfRecord));
  parallel_for(m_ends.size(), 1 << 16, [&](size_t begin, size_t end) {
    for (size_t p = begin; p < end; ++p) m_ends[p].traced = false;
  });
}

void psf_end_paths(const PsfConstants& f, const PsfTableView& t, const FilmView& film,
                   View<PsfRecord> records, View<const PsfPathEnd> ends, uint64_t& paths,
                   uint64_t& nonfinite) {
  // Far enough ahead for a miss to come back (a few hundred cycles), near enough to stay cached.
  constexpr size_t kAhead = 8;
  // A cell holds about 16 paths of a batch at the default width, most of them near each other in
  // pixel order: each thread sums its paths' words per cell in a small cache of its own (direct
  // mapped by key) and adds them to the cell once, when another key takes its entry or its range
  // ends, instead of twelve atomic adds and a compare-and-swap per path. The words are integers,
  // so the sums are those of adding each path's, to the bit.
  constexpr size_t kPending = 512;
  struct Pending {
    uint64_t key = 0;
    uint32_t cell = 0;
    PsfCellAdd add;
  };
  std::atomic<uint64_t> filtered{0}, dropped{0};
  parallel_for(ends.size, 4096, [&](size_t begin, size_t end) {
    Pending pending[kPending];
    uint64_t n = 0, bad = 0;
    for (size_t p = begin; p < end; ++p) {
      if (p + kAhead < end) {
        const uint64_t key = ends[p + kAhead].cut.key;
        if (key != 0 && pending[(key >> 1) % kPending].key != key)
          __builtin_prefetch(&t.keys[psf_home_slot(t, key)], 1);
      }
      const PsfPathEnd& e = ends[p];
      if (!e.traced) continue;
      PsfRecord r;
      PsfCellAdd add;
      const PsfEnd kind = psf_end_path_values(f, film, p, e.cut, e.L, add);
      if (kind == PsfEnd::Filtered) {
        Pending& c = pending[(e.cut.key >> 1) % kPending];
        if (c.key != e.cut.key) {
          if (c.key != 0) psf_add_to_cell(t, c.cell, c.add);
          c.key = e.cut.key;
          c.cell = psf_cell(t, c.key);
          c.add = PsfCellAdd{};
          __builtin_prefetch(&t.sums[6 * size_t(c.cell)], 1);
          __builtin_prefetch(&t.sums[6 * size_t(c.cell) + 5], 1);
        }
        c.add += add;
        r.cell = c.cell + 1;
        r.weight = e.cut.weight;
      }
      records[p] = r;
      n += kind == PsfEnd::Filtered;
      bad += kind == PsfEnd::NonFinite;
    }
    for (const Pending& c : pending)
      if (c.key != 0) psf_add_to_cell(t, c.cell, c.add);
    filtered.fetch_add(n, std::memory_order_relaxed);
    dropped.fetch_add(bad, std::memory_order_relaxed);
  });
  paths += filtered.load();
  nonfinite += dropped.load();
}

}  // namespace rll
