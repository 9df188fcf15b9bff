// Path-space filtering (`--filter psf`; Binder, Fricke & Keller 2018, as Fermat's psfpt renders
// the paper's teaser; docs/psf.md): each camera path is cut at one vertex, the radiance the rest of
// the path brings back to that vertex is averaged over the paths whose vertices share a cell of a
// jittered spatial hash (learn/cell_grid.h's keys: position by the ray footprint, normal), and
// each cut path gets its cell's mean times its own throughput. The cell table and everything a
// path does with it are RLL_HD functions over flat views (DESIGN 6): the megakernel, the CPU
// wavefront and the GPU run the same ones. Cells sum in integer words (ExactSum), so the image of
// a seed does not depend on the threads, their order or the device.
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "rll/core/device.h"
#include "rll/core/math.h"
#include "rll/core/param_table.h"
#include "rll/core/sampling.h"
#include "rll/learn/cell_grid.h"
#include "rll/learn/moments.h"
#include "rll/render/film.h"
#include "rll/scene/bsdf.h"

namespace rll {

// The filter's settings (`--set psf.KEY=VALUE`, psf_params()); the defaults are Fermat's psfpt's.
struct PsfSettings {
  bool on = false;  // --filter psf
  // The first vertex that may be cut, counted from the camera vertex (0). -1: Fermat's default,
  // its first bounce (1) for `path`, the camera vertex for `direct` (its only vertex).
  int depth = -1;
  float width = 3;      // cell radius in ray footprints (Fermat's psf_width)
  float max_prob = 32;  // a cut needs the bounce before it sampled with a pdf below this (rough)
  // ... and the segment to the vertex at least this long (scene units; Fermat declares 0.1 but
  // its test is commented out, so its renders use none: 0)
  float min_dist = 0;
  float clamp = 100;  // firefly clamp of every contribution to the film, per channel; 0: none
  // Temporal reuse (Fermat's psf_temporal_reuse, as an exponential blend): the weight, in [0, 1),
  // of the cells of the sample before in a render that follows a frame (RenderSettings::
  // follows_frame); 0: off.
  float temporal = 0;
  // Fermat's demodulation (docs/psf.md): at a cut vertex with a separable diffuse lobe, the cell
  // averages only that lobe's radiance divided by its albedo (irradiance-like), each path
  // multiplies its own albedo back in, and the glossy lobe's share goes to the film unfiltered.
  bool demodulate = true;
};

// The psf.* keys as one table (core/param_table.h): read, checked, listed by `rll filters`.
const std::vector<ParamSpec<PsfSettings>>& psf_params();
// `--filter NAME` ("none" or "psf") and the psf.* keys in `params` (refused without
// --filter psf); `max_depth` the integrator's vertices (1 for direct): a depth past the last
// vertex is refused, -1 resolved. Throws rll::Error naming the key.
PsfSettings make_psf_settings(const std::string& filter, int max_depth, bool path,
                              const Params& params);
// The filters `--filter` takes, "none" first.
const std::vector<std::string>& filter_names();

// What every path vertex reads of the filter (in PathConstants): the settings and the keyer of
// its cells, whose cell radius is `width` footprints.
struct PsfConstants {
  bool on = false;
  int depth = 1;
  float max_prob = 32, min_dist = 0, clamp = 0;
  float temporal = 0;       // PsfSettings::temporal
  bool demodulate = false;  // PsfSettings::demodulate
  CellKeyer keyer;
};
PsfConstants make_psf_constants(const PsfSettings& s, const Bounds3& scene_bounds);

// The jitter of a path's cell is drawn at dimensions of its own, far past every decision of the
// path and its resampled light candidates (render/path_vertex.h), so that filtering changes none
// of the numbers the path draws.
inline constexpr uint32_t kPsfJitterDimension = 1u << 25;

// A path's cut: the key of its cell (0: not cut), its throughput at the cut vertex and what it
// had gathered before it (the emission up to and at the cut vertex, the light sampled before it),
// which goes to the film unfiltered.
// Fermat's cap on a bounce's spread in the cone that sizes the filter's cells (`min_p`: a pdf of
// 32, about 10 degrees; render/path_vertex.h, psf_cut_footprint).
inline constexpr float kPsfMinConePdf = 32.0f;

// With psf.demodulate, the weight is the throughput times the cut vertex's diffuse albedo, and
// the cut splits what the path gathers at and after it (psf_split_nee, psf_split_bounce): `before`
// also takes the glossy share of the cut vertex's light samples and, at the end, of what came
// back through its bounce (1 - `share`); `kept` holds the diffuse share of its light samples.
struct PsfCut {
  uint64_t key = 0;
  Rgb weight{0}, before{0};
  Rgb kept{0}, share{1};
};
// A cut whose key is still to be computed (keys are odd: CellKeyer::key).
inline constexpr uint64_t kPsfKeyPending = 2;

// The cell of the cut vertex at point p with shading normal ns (either side: turned toward wo),
// footprint `footprint`, `depth` its depth; u: 5 uniform numbers. As Fermat's jittered hash: the
// cell radius is `width` footprints, rounded to a power of two at random in proportion to the
// fraction (u[4]); the position is jittered by a disk in the tangent plane of one cell edge at the
// camera vertex and half of one deeper (Fermat's filter_scale 2 and 1, in cell radii), the normal
// by up to one bin.
RLL_HD inline uint64_t psf_key(const PsfConstants& f, const Vec3& p, Vec3 ns, const Vec3& wo,
                               float footprint, int depth, const float u[5]) {
  if (dot(ns, wo) < 0) ns = -ns;
  const Vec2 d = sample_uniform_disk_concentric({u[0], u[1]});
  const float disk = depth == 0 ? 1.0f : 0.5f;
  return f.keyer.key(
      f.keyer.locate_jittered(p, ns, footprint, u[4], {d.x * disk, d.y * disk}, {u[2], u[3]}));
}

// Whether psf.demodulate splits the cut vertex of BSDF `bsdf` into its diffuse lobe (filtered,
// demodulated by its albedo) and its glossy one (to the film): a Separable diffuse part
// (Bsdf::diffuse_part). A Layered one (CoatedDiffuse, whose walk mixes the lobes) is filtered
// whole, as without the key; a vertex without a diffuse lobe is not cut (psf_cuts_here).
RLL_HD inline bool psf_splits(const PsfConstants& f, const Bsdf& bsdf) {
  return f.demodulate && bsdf.diffuse_part() == Bsdf::DiffusePart::Separable;
}

// At a cut vertex that psf_splits: the diffuse share of one light sample's `value` (its estimate of
// f Le cos / pdf toward wi), which the path keeps for its cell; the glossy share, times the
// throughput `beta`, goes to the film with what the path gathered before the cut.
RLL_HD inline Rgb psf_split_nee(const Bsdf& bsdf, const Vec3& wo, const Vec3& wi, const Rgb& beta,
                                const Rgb& value, PsfCut& cut) {
  const Rgb share = bsdf.diffuse_share(wo, wi);
  cut.before += beta * (value * (Rgb(1) - share));
  return value * share;
}

// After the bounce from a cut vertex that psf_splits, toward wi: what comes back through it
// splits by the diffuse lobe's share of f(wo, wi) (psf_end_path); the path's radiance so far
// (the diffuse share of the vertex's light samples) is kept apart from it.
RLL_HD inline void psf_split_bounce(const Bsdf& bsdf, const Vec3& wo, const Vec3& wi, Rgb& L,
                                    PsfCut& cut) {
  cut.share = bsdf.diffuse_share(wo, wi);
  cut.kept = L;
  L = Rgb(0);
}

// A component-wise clamp of a contribution to the film or to a cell (0: none).
RLL_HD inline Rgb psf_clamp(const Rgb& v, float clamp) {
  return clamp > 0 ? min(v, Rgb(clamp)) : v;
}

// The cells of one batch of paths: an open-addressed table of keys (linear probing), and per cell
// the sums of what its paths brought back after their cuts and of their throughputs at the cuts,
// per channel. The table holds more cells than a batch has paths (each cuts once), so that an
// insert always finds its key or a free slot: which cells a batch has never depends on the order
// of its threads (a table that could fill would drop different cells each run).
struct PsfTableView {
  View<uint64_t> keys;       // 0: free
  View<ExactSum> sums;       // 6 per cell: radiance after the cut (r, g, b), throughput (r, g, b)
  uint32_t* used = nullptr;  // cells taken in this batch
};

// The cells for a batch of `paths` paths: twice as many, plus one.
RLL_HD inline size_t psf_capacity(size_t paths) {
  return 2 * paths + 1;
}

// The slot where the probe for `key` starts.
RLL_HD inline uint32_t psf_home_slot(const PsfTableView& t, uint64_t key) {
  return uint32_t((key >> 1) % uint32_t(t.keys.size));
}

// The cell of `key` (!= 0), taken if free; thread-safe.
RLL_HD inline uint32_t psf_cell(const PsfTableView& t, uint64_t key) {
  const uint32_t n = uint32_t(t.keys.size);
  uint32_t slot = psf_home_slot(t, key);
  for (;;) {
    const uint64_t seen = atomic_cas(&t.keys[slot], 0, key);
    if (seen == 0) {
      atomic_add(t.used, 1u);
      return slot;
    }
    if (seen == key) return slot;
    if (++slot == n) slot = 0;
  }
}

// What a pixel's path of the batch left for the resolve: 1 + its cell (0: not filtered) and its
// throughput at the cut.
struct PsfRecord {
  uint32_t cell = 0;
  Rgb weight{0};
};

// How a path ended, for the caller's counts.
enum class PsfEnd { Unfiltered, Filtered, NonFinite };

// What a cut path adds to its cell: the exact words of its radiance after the cut (r, g, b) and of
// its throughput at the cut (r, g, b), the six sums of PsfTableView, in that order.
struct PsfCellAdd {
  ExactSum::Words w[6];
  RLL_HD PsfCellAdd& operator+=(const PsfCellAdd& o) {
    for (int i = 0; i < 6; ++i) w[i] += o.w[i];
    return *this;
  }
};

// Adds `a` to the sums of `cell`; thread-safe.
RLL_HD inline void psf_add_to_cell(const PsfTableView& t, uint32_t cell, const PsfCellAdd& a) {
  ExactSum* s = &t.sums[6 * size_t(cell)];
  for (int i = 0; i < 6; ++i) s[i].add(a.w[i]);
}

// The end of a pixel's path of the batch but for its cell: what goes to the film now (clamped; a
// non-finite path adds 0, as every renderer drops them) and, for a cut path (Filtered), what it
// adds to its cell (`add`: its radiance after the cut, `L` then the path's radiance gathered after
// the cut, and its throughput). `L` is the whole path's radiance where it was not cut.
RLL_HD inline PsfEnd psf_end_path_values(const PsfConstants& f, const FilmView& film, size_t pixel,
                                         const PsfCut& cut, Rgb L, PsfCellAdd& add) {
  if (cut.key == 0) {
    PsfEnd end = PsfEnd::Unfiltered;
    if (!is_finite(L)) {
      end = PsfEnd::NonFinite;
      L = Rgb(0);
    }
    film.add(pixel, psf_clamp(L, f.clamp));
    return end;
  }
  if (!is_finite(L) || !is_finite(cut.before) || !is_finite(cut.weight) || !is_finite(cut.kept)) {
    film.add(pixel, Rgb(0));
    return PsfEnd::NonFinite;
  }
  Rgb before = cut.before;
  if (f.demodulate) {  // (the glossy share of what came back through the cut's bounce)
    before += L * (Rgb(1) - cut.share);
    L = cut.kept + L * cut.share;
  }
  film.add(pixel, psf_clamp(before, f.clamp));
  const Rgb after = psf_clamp(L, f.clamp);
  for (int ch = 0; ch < 3; ++ch) {
    add.w[ch] = ExactSum::words(double(after[ch]));
    add.w[3 + ch] = ExactSum::words(double(cut.weight[ch]));
  }
  return PsfEnd::Filtered;
}

// The end of a pixel's path of the batch (psf_end_path_values), a cut path's values added to its
// cell and recorded for the resolve.
RLL_HD inline PsfEnd psf_end_path(const PsfConstants& f, const PsfTableView& t,
                                  const FilmView& film, View<PsfRecord> records, size_t pixel,
                                  const PsfCut& cut, Rgb L) {
  PsfRecord r;
  PsfCellAdd add;
  const PsfEnd end = psf_end_path_values(f, film, pixel, cut, L, add);
  if (end == PsfEnd::Filtered) {
    const uint32_t cell = psf_cell(t, cut.key);
    psf_add_to_cell(t, cell, add);
    r.cell = cell + 1;
    r.weight = cut.weight;
  }
  records[pixel] = r;
  return end;
}

// After every path of the batch ended: the pixel's cut path gets its cell's mean, the ratio of
// the cell's radiance to its throughput (which weighs each path by its throughput and gives a
// path alone in its cell exactly its own radiance), times its own throughput, clamped; added to
// the film's sums (the sample was counted by psf_end_path).
RLL_HD inline void psf_resolve_pixel(const PsfConstants& f, const PsfTableView& t,
                                     const FilmView& film, View<const PsfRecord> records,
                                     size_t pixel) {
  const PsfRecord r = records[pixel];
  if (r.cell == 0) return;
  const ExactSum* s = &t.sums[6 * size_t(r.cell - 1)];
  Rgb v(0);
  for (int ch = 0; ch < 3; ++ch) {
    const double after = s[ch].value(), weight = s[3 + ch].value();
    if (weight > 0) v[ch] = float(double(r.weight[ch]) * (after / weight));
  }
  film.add_sum(pixel, psf_clamp(v, f.clamp));
}

// Temporal reuse (psf.temporal, docs/psf.md; Fermat's psf_temporal_reuse, which sums a cell over
// up to 64 frames and then starts it afresh): in a render that follows a frame, each sample's cell
// adds `temporal` times the sums its key had in the sample before (the last sample of the frame
// before, for a frame's first), which had blended its own sample before: the sums, and so the
// cell's mean, are an exponentially weighted blend over the samples, a path weighing temporal^k
// after k samples. A cell that no path of a sample reaches is not kept (the table stays as
// large as one sample's). The last sample's table is only read while the next is blended.

// Where a table has no cell of a key.
inline constexpr uint32_t kPsfNoCell = 0xffffffffu;

// The cell of `key` (!= 0) in a table that no thread writes to, or kPsfNoCell.
RLL_HD inline uint32_t psf_find(const PsfTableView& t, uint64_t key) {
  const uint32_t n = uint32_t(t.keys.size);
  uint32_t slot = psf_home_slot(t, key);
  for (uint32_t probes = 0; probes < n; ++probes) {
    const uint64_t seen = t.keys[slot];
    if (seen == key) return slot;
    if (seen == 0) break;
    if (++slot == n) slot = 0;
  }
  return kPsfNoCell;
}

// After every path of the sample, before the resolve: cell `cell` of its table `t`, where a path
// took it, adds `temporal` times the sums of its key in the last sample's table `last`; true
// where it found them. One thread per cell, each sum one add: the blend is exact and independent
// of the threads as the paths' adds are.
RLL_HD inline bool psf_blend_cell(const PsfConstants& f, const PsfTableView& t,
                                  const PsfTableView& last, size_t cell) {
  const uint64_t key = t.keys[cell];
  if (key == 0) return false;
  const uint32_t from = psf_find(last, key);
  if (from == kPsfNoCell) return false;
  ExactSum* s = &t.sums[6 * cell];
  const ExactSum* l = &last.sums[6 * size_t(from)];
  for (int i = 0; i < 6; ++i) s[i].add(double(f.temporal) * l[i].value());
  return true;
}

// Temporal reuse's two tables of cells, in the memory of the device that renders (views, copied
// into kernels by value): the last sample's, which the next sample blends, and the next sample's,
// which its paths fill; they change places every sample. Kept from render to render by whoever
// renders frames (the session on the host, the GPU renderer on its device).
struct PsfFrameCells {
  PsfTableView tables[2];
  int last = 0;        // tables[last]: the last sample's cells, where `holds`
  bool holds = false;  // a sample was rendered into tables[last]
  size_t pixels = 0;   // the film's pixels they are sized for (psf_capacity each)

  // The table the next sample fills (clear it first), and the one it blends.
  const PsfTableView& next() const { return tables[1 - last]; }
  const PsfTableView& previous() const { return tables[last]; }
  // Whether the next sample blends the last one's cells: in a render that follows a frame.
  bool blends(bool follows_frame) const { return follows_frame && holds; }
  // The next sample's cells are in: they are the last sample's now.
  void filled() {
    last = 1 - last;
    holds = true;
  }
};

// The megakernel's path of a batch, ended in a loop of their own (psf_end_paths) rather than
// each as it is traced: their cells' cache lines, random in a table of 16 MB at 320 x 240, are
// then fetched ahead of their inserts instead of one miss after another within the tracing.
struct PsfPathEnd {
  PsfCut cut;
  Rgb L{0};
  bool traced = false;  // (a stopped batch leaves pixels untraced: they add nothing)
};

// The bytes the filter takes per pixel of the film: a record, psf_capacity cells of a key and six
// sums for its batch of one path per pixel, and a path's end (the megakernel's per pixel, with
// its radiance; the wavefront's cut per path slot, smaller).
inline constexpr double kPsfBytesPerPixel =
    sizeof(PsfRecord) + 2.0 * (sizeof(uint64_t) + 6 * sizeof(ExactSum)) + sizeof(PsfPathEnd);
inline constexpr const char* kPsfPixelText = "the path-space filter's cells and path records";

// The bytes a pixel temporal reuse adds: the second table of cells.
inline constexpr double kPsfTemporalBytesPerPixel = 2.0 * (sizeof(uint64_t) + 6 * sizeof(ExactSum));
inline constexpr const char* kPsfTemporalPixelText =
    "the path-space filter's cells of the sample before (psf.temporal)";

// Throws rll::Error where the filter's table and records for `pixels` pixels (and with `temporal`
// the second table of temporal reuse) do not fit the memory budget (core/memory_budget.h), before
// they are allocated.
void check_psf_memory(size_t pixels, bool temporal = false);

// A batch's counts, summed over the batches of a render: --stats' `filter`.
struct PsfCounts {
  uint64_t batches = 0;  // batches resolved (one per sample of each pixel)
  uint64_t cells = 0;    // cells used, summed over the batches
  uint64_t paths = 0;    // paths filtered (cut), over all batches
  uint64_t reused = 0;   // cells that blended the last sample's (psf.temporal), over all batches
  PsfCounts& operator+=(const PsfCounts& o) {
    batches += o.batches;
    cells += o.cells;
    paths += o.paths;
    reused += o.reused;
    return *this;
  }
};

// What --stats and summaries say of the filter: {"name": "none"}, or "psf" with its settings and,
// where `counts` is given, the cells used per batch, the paths filtered and their share of the
// `samples` camera paths, and with temporal reuse the cells that blended the sample before's and
// `temporal_bytes`, the memory its second table took.
nlohmann::json filter_json(const PsfSettings& s, const PsfCounts* counts = nullptr,
                           uint64_t samples = 0, size_t temporal_bytes = 0);

// Every cell of a table in the host's memory free (in parallel).
void clear_psf_cells(const PsfTableView& t);

// The host's table and records, for the megakernel: one batch of one path per pixel at a time.
class PsfTable {
 public:
  // Checks the memory (check_psf_memory) before allocating; without `cells` (temporal reuse,
  // whose cells a PsfHistory holds) only the records.
  explicit PsfTable(size_t pixels, bool cells = true);
  // Starts a batch: every cell free, every record empty.
  void clear();
  PsfTableView view() { return {view_of(m_keys), {m_sums.data(), m_sums.size()}, &m_used}; }
  View<PsfRecord> records() { return view_of(m_records); }
  uint32_t used() const { return m_used; }

  // The megakernel's paths of the batch (PsfPathEnd).
  View<PsfPathEnd> ends() { return view_of(m_ends); }

 private:
  std::vector<uint64_t> m_keys;
  std::vector<ExactSum> m_sums;
  std::vector<PsfRecord> m_records;
  std::vector<PsfPathEnd> m_ends;
  uint32_t m_used = 0;
};

// The ends of the megakernel's paths of a batch (PsfPathEnd) as psf_end_path's, each pixel's
// in turn (in parallel), the keys of the paths a few pixels ahead prefetched and each thread's
// adds to a cell gathered before they reach it; their counts added to `paths` (filtered) and
// `nonfinite`. The cells' sums are exact, so the image is the one of ending each path as it is
// traced, to the bit.
void psf_end_paths(const PsfConstants& f, const PsfTableView& t, const FilmView& film,
                   View<PsfRecord> records, View<const PsfPathEnd> ends, uint64_t& paths,
                   uint64_t& nonfinite);

// Temporal reuse's cells in the host's memory (the megakernel's and the CPU wavefront's), kept by
// the session from frame to frame.
class PsfHistory {
 public:
  // Checks the memory of the filter with both tables (check_psf_memory) before allocating.
  explicit PsfHistory(size_t pixels);
  PsfHistory(const PsfHistory&) = delete;
  PsfHistory& operator=(const PsfHistory&) = delete;
  PsfFrameCells& cells() { return m_cells; }
  // The memory of the second table, what temporal reuse adds (--stats).
  size_t bytes() const { return size_t(double(m_cells.pixels) * kPsfTemporalBytesPerPixel); }

 private:
  std::vector<uint64_t> m_keys[2];
  std::vector<ExactSum> m_sums[2];
  uint32_t m_used[2] = {0, 0};
  PsfFrameCells m_cells;
};

}  // namespace rll
