#include "rll/render/render.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>

#include "rll/core/error.h"
#include "rll/core/parallel.h"
#include "rll/core/rng.h"
#include "rll/render/path_vertex.h"

namespace rll {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
// How many samples a tile takes between two looks at the pass's stop (an atomic load, and a
// clock read under a time budget): well under a millisecond of work on any scene we render, so
// that a stop is seen at once while looking costs nothing measurable.
constexpr int kSamplesPerStopCheck = 64;
}  // namespace

bool PassStop::operator()() const {
  if (m_stop.load(std::memory_order_relaxed)) return true;
  if ((m_cancel && m_cancel->load(std::memory_order_relaxed)) ||
      (m_time_limit > 0 &&
       seconds_since(m_t0) >= m_time_limit - m_reserve.load(std::memory_order_relaxed))) {
    m_stop.store(true);
    return true;
  }
  return false;
}

int pass_size_for_budget(int size, double left, double seconds_per_spp) {
  if (!(seconds_per_spp > 0) || !(left < double(size) * seconds_per_spp)) return size;
  return std::max(1, int(std::floor(left / seconds_per_spp)));
}

Ray camera_ray(const Scene& scene, int x, int y, SampleStream& stream) {
  return camera_ray(scene.camera, x, y, stream);
}

RenderProgress run_passes(const Scene& scene, const std::function<void()>& end_pass, Film& film,
                          const RenderSettings& settings, const std::atomic<bool>* cancel,
                          const std::function<void(const RenderProgress&, const Film&)>& after_pass,
                          const PassWork& work, const std::function<uint32_t()>& min_count) {
  if (settings.spp < 1) fail("--spp must be at least 1 (got {})", settings.spp);
  if (settings.pass_spp < 1) fail("pass size must be at least 1 sample per pixel");
  if (settings.first_sample + uint64_t(settings.spp) > (uint64_t(1) << 32) &&
      settings.spp != kUnlimitedSpp)
    fail("samples {} to {} of a pixel are past the 2^32 the sample points hold",
         settings.first_sample, settings.first_sample + uint64_t(settings.spp));
  const int max_pass = std::max(settings.pass_spp, settings.max_pass_spp);
  if (film.width() != scene.width || film.height() != scene.height)
    fail("film size does not match the scene");
  const uint64_t frame_seed =
      mix64(settings.seed + 0x51ed270b27f3e5a1ull * uint64_t(settings.frame));

  RenderProgress progress;
  progress.spp_target = settings.spp;
  progress.time_limit = settings.time_limit;
  auto spp_done = [&] { return int(min_count ? min_count() : film.min_count()); };
  progress.spp_done = spp_done();
  auto t0 = Clock::now();
  const PassStop stop(cancel, settings.time_limit, t0);

  // The last pass's rate (seconds of work per sample per pixel) and its end of pass's seconds,
  // which size the next pass under a time budget.
  const double pixels = double(film.width()) * double(film.height());
  double seconds_per_spp = 0, end_pass_seconds = 0;
  while (progress.spp_done < settings.spp && !stop.stopped()) {
    const int first = progress.spp_done;
    const int size = std::min(max_pass, settings.pass_spp << std::min(20, progress.passes / 2));
    int count = std::min(size, settings.spp - first);
    if (settings.time_limit > 0) {
      stop.reserve(end_pass_seconds);
      count = pass_size_for_budget(
          count, settings.time_limit - seconds_since(t0) - end_pass_seconds, seconds_per_spp);
    }
    const auto w0 = Clock::now();
    const uint64_t camera0 = progress.rays.camera;
    work(first, count, frame_seed, stop, progress.rays, progress.nonfinite, progress.filter);
    if (progress.rays.camera > camera0)
      seconds_per_spp = seconds_since(w0) * pixels / double(progress.rays.camera - camera0);
    // A stopped pass leaves some pixels with fewer samples; the film's counts keep it unbiased.
    // The sampler's end of pass still runs on it: the rewards it gathered are as valid as a whole
    // pass's (the learning weighs rewards by their counts, never by the pass's size), and a state
    // saved or returned after a Ctrl-C then holds everything the render saw.
    progress.passes += 1;
    progress.spp_done = spp_done();
    progress.samples = progress.rays.camera;
    progress.seconds = seconds_since(t0);
    const auto e0 = Clock::now();
    end_pass();
    end_pass_seconds = seconds_since(e0);
    if (stop.stopped()) {
      progress.cancelled = cancel && cancel->load();
      progress.out_of_time = !progress.cancelled;
    }
    if (after_pass) {
      // The caller's time between passes (progress output, error metrics at checkpoints) is
      // not render time: it neither counts in `seconds` nor uses up the time budget.
      const auto c0 = Clock::now();
      after_pass(progress, film);
      t0 += Clock::now() - c0;
    }
  }
  progress.seconds = seconds_since(t0);
  // A cancel that came before the first pass ran no pass at all: still a cancelled render (its
  // caller would otherwise take an empty film for a finished one and write it).
  progress.cancelled =
      progress.cancelled || (cancel && cancel->load() && progress.spp_done < settings.spp);
  progress.out_of_time =
      progress.out_of_time ||
      (settings.time_limit > 0 && progress.spp_done < settings.spp && !progress.cancelled);
  return progress;
}

namespace {

// The pixels of the image, tile by tile in parallel, each tile's in its order:
// `sample(x, y, rays, nonfinite, stop_now)` takes samples of pixel (x, y), asking stop_now()
// before each (which asks `stop` every kSamplesPerStopCheck samples of the tile), and returns
// false where stop_now() said to stop; the tiles' counts are added up.
template <typename Sample>
void for_each_tile(int w, int h, int ts, const PassStop& stop, RayCounters& pass_rays,
                   uint64_t& pass_nonfinite, const Sample& sample) {
  const int tiles_x = (w + ts - 1) / ts, tiles_y = (h + ts - 1) / ts;
  std::mutex merge_mutex;
  parallel_for_each(size_t(tiles_x) * tiles_y, [&](size_t tile) {
    if (stop()) return;
    RayCounters rays;
    uint64_t nonfinite = 0;
    const int x0 = int(tile % tiles_x) * ts, y0 = int(tile / tiles_x) * ts;
    // `stop` is asked again every kSamplesPerStopCheck samples, so that a cancel (Ctrl-C) or
    // the end of the time budget ends even a long pass's tile soon; the pixel it ends in keeps
    // the samples it took (each pixel's first n, counted by the film).
    bool stopped = false;
    int unchecked = 0;
    for (int y = y0; y < std::min(h, y0 + ts) && !stopped; ++y)
      for (int x = x0; x < std::min(w, x0 + ts) && !stopped; ++x)
        stopped = !sample(x, y, rays, nonfinite, [&] {
          if (++unchecked < kSamplesPerStopCheck) return false;
          unchecked = 0;
          return stop();
        });
    std::lock_guard lock(merge_mutex);
    pass_rays += rays;
    pass_nonfinite += nonfinite;
  });
}

}  // namespace

RenderProgress render(const Scene& scene, Integrator& integrator, LightSampler& sampler, Film& film,
                      const RenderSettings& settings, const std::atomic<bool>* cancel,
                      const std::function<void(const RenderProgress&, const Film&)>& after_pass,
                      PsfHistory* history) {
  // ReSTIR's reuse is a frame-wide step after each sample of every pixel, which the megakernel's
  // paths, pixel by pixel, cannot take (the session renders it with the wavefront renderer).
  if (integrator.settings().restir.on)
    fail(
        "a restir sampler renders with the wavefront renderer (render_wavefront), not the "
        "megakernel");
  const int w = film.width(), h = film.height(), ts = std::max(1, settings.tile_size);
  const bool tracks_vertex = film.camera_vertex() != nullptr;
  auto trace = [&](int x, int y, int s, uint64_t frame_seed, RayCounters& rays, PsfCut* cut) {
    SampleStream stream(frame_seed, uint64_t(y) * w + x, settings.first_sample + uint64_t(s),
                        settings.points);
    CameraVertexSample vertex;
    const Rgb L = integrator.li(camera_ray(scene, x, y, stream), stream, rays,
                                tracks_vertex ? &vertex : nullptr, cut);
    if (tracks_vertex) film.add_camera_vertex(x, y, vertex);
    return L;
  };
  auto pass = [&](int first, int count, uint64_t frame_seed, const PassStop& stop,
                  RayCounters& pass_rays, uint64_t& pass_nonfinite, PsfCounts&) {
    for_each_tile(w, h, ts, stop, pass_rays, pass_nonfinite,
                  [&](int x, int y, RayCounters& rays, uint64_t& nonfinite, const auto& stop_now) {
                    for (int s = first; s < first + count; ++s) {
                      if (stop_now()) return false;
                      Rgb L = trace(x, y, s, frame_seed, rays, nullptr);
                      if (!is_finite(L)) {
                        ++nonfinite;
                        L = Rgb(0);
                      }
                      film.add(x, y, L);
                    }
                    return true;
                  });
  };
  // Path-space filtering: a batch per sample index (render/psf.h), its cells in `table`, or with
  // temporal reuse in the history's tables, which change places every sample.
  std::unique_ptr<PsfTable> table;
  const PsfConstants& psf = integrator.constants().psf;
  PsfFrameCells* frames = nullptr;
  if (psf.on && psf.temporal > 0 && history && history->cells().pixels == size_t(w) * h)
    frames = &history->cells();
  if (psf.on) table = std::make_unique<PsfTable>(size_t(w) * h, !frames);
  auto filtered_pass = [&](int first, int count, uint64_t frame_seed, const PassStop& stop,
                           RayCounters& pass_rays, uint64_t& pass_nonfinite, PsfCounts& filter) {
    const FilmView fv = film.view();
    for (int s = first; s < first + count && !stop.stopped(); ++s) {
      table->clear();
      const PsfTableView t = frames ? frames->next() : table->view();
      if (frames) clear_psf_cells(t);
      const View<PsfRecord> records = table->records();
      const View<PsfPathEnd> ends = table->ends();
      std::atomic<uint64_t> reused{0};
      uint64_t paths = 0;
      // The paths first, then their ends (psf_end_paths: the cells fetched ahead of the inserts).
      for_each_tile(w, h, ts, stop, pass_rays, pass_nonfinite,
                    [&](int x, int y, RayCounters& rays, uint64_t&, const auto& stop_now) {
                      if (stop_now()) return false;
                      PsfPathEnd& e = ends[size_t(y) * w + x];
                      e.cut = PsfCut{};
                      e.L = trace(x, y, s, frame_seed, rays, &e.cut);
                      e.traced = true;
                      return true;
                    });
      psf_end_paths(psf, t, fv, records, ends, paths, pass_nonfinite);
      if (frames && frames->blends(settings.follows_frame)) {
        const PsfTableView last = frames->previous();
        parallel_for(t.keys.size, 4096, [&](size_t begin, size_t end) {
          uint64_t n = 0;
          for (size_t c = begin; c < end; ++c) n += psf_blend_cell(psf, t, last, c);
          reused.fetch_add(n, std::memory_order_relaxed);
        });
      }
      parallel_for(size_t(w) * h, 4096, [&](size_t begin, size_t end) {
        for (size_t p = begin; p < end; ++p) psf_resolve_pixel(psf, t, fv, records, p);
      });
      filter.batches += 1;
      filter.cells += *t.used;
      filter.paths += paths;
      filter.reused += reused.load();
      if (frames) frames->filled();
    }
  };
  integrator.sampler_changed();
  return run_passes(
      scene,
      [&] {
        sampler.end_pass();
        integrator.sampler_changed();
      },
      film, settings, cancel, after_pass, psf.on ? PassWork(filtered_pass) : PassWork(pass));
}

}  // namespace rll
