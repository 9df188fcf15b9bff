#include "rll/session/session.h"

#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <map>
#include <set>

#include "rll/core/error.h"
#include "rll/cuda/cuda.h"
#include "rll/lights/light_sampler.h"
#include "rll/render/progress.h"

namespace rll {

const std::vector<std::string>& sampler_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n = light_sampler_names();
    n.push_back("restir");
    return n;
  }();
  return names;
}

LoadOptions parse_resolution(const std::string& res) {
  LoadOptions lo;
  if (res.empty()) return lo;
  // Each side is parsed whole, digits only: sscanf's %d would wrap 4294967328 to 32.
  auto side = [&](size_t begin, size_t end) -> long long {
    unsigned long long n = 0;
    const char* last = res.data() + end;
    auto [ptr, ec] = std::from_chars(res.data() + begin, last, n);
    if (begin >= end || ptr != last) return -1;
    return ec == std::errc::result_out_of_range || n > kMaxFilmSide ? kMaxFilmSide + 1ll
                                                                    : (long long)n;
  };
  const size_t x = res.find_first_of("xX");
  const long long w = x == std::string::npos ? -1 : side(0, x);
  const long long h = x == std::string::npos ? -1 : side(x + 1, res.size());
  if (w < 0 || h < 0) fail("--res '{}': expected WIDTHxHEIGHT, e.g. 640x480", shown_text(res));
  if (w == 0 || h == 0) fail("--res '{}': width and height must be positive", shown_text(res));
  if (w > kMaxFilmSide || h > kMaxFilmSide)
    fail("--res '{}': width and height must be at most {}", shown_text(res), kMaxFilmSide);
  if (w * h > kMaxFilmPixels)
    fail("--res '{}': {} pixels is more than the limit of {}", res, w * h, kMaxFilmPixels);
  // Before the scene (perhaps slow to load) is read.
  check_film_memory(w, h, kRenderBytesPerPixel, fmt::format("--res {}", res));
  lo.width = int(w);
  lo.height = int(h);
  return lo;
}

RenderSession::RenderSession(const SessionSettings& settings)
    : m_settings(settings), m_params(Params::parse(settings.set)) {
  const LoadOptions lo = parse_resolution(settings.resolution);
  m_points = parse_point_set(settings.points, "--points");
  if (settings.device != "cpu" && settings.device != "cuda")
    fail("--device '{}': expected cpu or cuda", settings.device);
  if (settings.tracer != "embree" && settings.tracer != "bvh")
    fail("--tracer '{}': expected embree or bvh", settings.tracer);
  if (settings.tracer == "bvh" && (!settings.wavefront || settings.device == "cuda"))
    fail(
        "--tracer bvh is the CPU wavefront renderer's: add --wavefront (--device cuda always "
        "traces with rll's BVH)");
  // Before the scene (perhaps slow to load): a GPU render needs a GPU.
  if (settings.device == "cuda") cuda::require_gpu();
  m_scene = load_scene(settings.scene, lo);
  // The scene's own film size is a claim of its file like any other: checked before the film
  // is allocated (a render's commands check again with what else they keep a pixel).
  check_film_memory(kRenderBytesPerPixel);
  // Reorders the lights: everything keyed by their order (fingerprint, learnt states) follows.
  m_tree = build_light_tree(m_scene);
  m_integrator =
      make_integrator_settings(settings.integrator, settings.max_depth, m_params, settings.filter);
  // The filter's cells and records are kept beside the film: checked with it (temporal reuse's
  // second table where a render that has frames around it makes it: render()).
  if (m_integrator.psf.on)
    check_film_memory(kRenderBytesPerPixel + kPsfBytesPerPixel,
                      fmt::format("{}, and {}", kRenderPixelText, kPsfPixelText));
  m_accel = std::make_unique<Accel>(m_scene.mesh);
  if (settings.device == "cuda") m_gpu = std::make_unique<cuda::GpuRenderer>(m_scene);
}

std::string RenderSession::film_source() const {
  if (!m_settings.resolution.empty()) return fmt::format("--res {}", m_settings.resolution);
  return fmt::format("the film of scene '{}'", m_settings.scene);
}

void RenderSession::check_film_memory(double bytes_per_pixel, const std::string& kept) const {
  rll::check_film_memory(m_scene.width, m_scene.height, bytes_per_pixel, film_source(), kept);
}

const char* RenderSession::renderer_name() const {
  if (m_gpu) return "cuda-wavefront";
  if (!m_settings.wavefront) {
    // A restir sampler renders with the wavefront renderer whatever --wavefront says.
    const size_t restirs = size_t(std::count(m_made.begin(), m_made.end(), "restir"));
    if (restirs == 0) return "megakernel";
    return restirs == m_made.size() ? "wavefront" : "megakernel, wavefront for restir";
  }
  return m_settings.tracer == "bvh" ? "wavefront-bvh" : "wavefront";
}

std::unique_ptr<LightSampler> RenderSession::make_sampler(const std::string& spec) const {
  std::unique_ptr<LightSampler> s = make_sampler_on_host(spec);
  if (m_gpu) {
    std::lock_guard lock(m_restir_mutex);
    const auto it = m_restir.find(s.get());
    if (it == m_restir.end()) {
      cuda::require_device_version(*s, spec);
    } else {
      try {
        cuda::require_device_version(*s, restir_source_name(it->second.settings.restir));
      } catch (const Error& e) {
        fail("sampler '{}': --set restir.source={}: {}", shown_text(spec),
             restir_source_name(it->second.settings.restir), e.what());
      }
    }
  }
  return s;
}

Params RenderSession::variant_params(const std::string& spec, std::string& name,
                                     std::vector<std::string>& own) const {
  Params params = m_params;
  const size_t colon = spec.find(':');
  name = spec.substr(0, colon);
  if (colon == std::string::npos) return params;
  // A key given twice (twice in the spec, or in the spec and by --set) is refused rather than
  // one value silently winning: the image's header and the summary record both.
  std::map<std::string, std::string> given;  // key -> as the spec wrote it
  for (size_t start = colon + 1; start <= spec.size();) {
    size_t end = std::min(spec.find(':', start), spec.size());
    std::string kv = spec.substr(start, end - start);
    size_t eq = kv.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == kv.size())
      fail("sampler '{}': '{}' is not key=value", shown_text(spec), shown_text(kv));
    std::string key = kv.substr(0, eq);
    if (key.find('.') == std::string::npos) key = name + "." + key;
    if (const auto it = given.find(key); it != given.end())
      fail("sampler '{}': {} is given twice in it ({} and {}): give it once", shown_text(spec),
           shown_text(key), shown_text(it->second), shown_text(kv));
    if (m_params.has(key))
      fail("sampler '{}': {} is given both in it ({}) and by --set {}={}: give it in one place",
           shown_text(spec), shown_text(key), shown_text(kv), shown_text(key),
           shown_text(m_params.values().at(key), 40));
    given.emplace(key, kv);
    params.set(key, kv.substr(eq + 1));
    own.push_back(kv.substr(0, eq));
    start = end + 1;
  }
  return params;
}

std::unique_ptr<LightSampler> RenderSession::make_sampler_on_host(const std::string& spec) const {
  const bool restir = spec.substr(0, spec.find(':')) == "restir";
  if (spec.find(':') == std::string::npos && !restir) {
    auto sampler = make_light_sampler(spec, m_scene, m_tree, m_params, m_accel.get());
    m_made.push_back(spec);
    return sampler;
  }
  std::string name;
  std::vector<std::string> own;  // the keys as the spec gives them
  Params params = variant_params(spec, name, own);
  // The integrator's keys (nee.candidates, ...) are a variant's too: integrator_for reads them.
  // A restir sampler's are ReSTIR's too (restir.*), and its sampler is restir.source's.
  const IntegratorSettings is = make_integrator_settings(
      m_settings.integrator, m_settings.max_depth, params, m_settings.filter, restir);
  if (restir)
    check_film_memory(kRenderBytesPerPixel + kRestirBytesPerPixel,
                      fmt::format("{}, and {}", kRenderPixelText, kRestirPixelText));
  auto sampler = make_light_sampler(restir ? restir_source_name(is.restir) : name, m_scene, m_tree,
                                    params, m_accel.get());
  // A variant's own keys must all be known, and are reported as the spec wrote them (not as
  // --set keys, which the user may never have given).
  std::vector<std::string> unknown;
  for (const auto& k : own)
    if (!params.used(k.find('.') == std::string::npos ? name + "." + k : k))
      unknown.push_back(shown_text(k));
  if (!unknown.empty()) {
    std::vector<std::string> keys;
    for (const auto& k : params.known_keys())
      if (k.rfind(name + ".", 0) == 0) keys.push_back(k.substr(name.size() + 1));
    fail("sampler '{}': {} has no parameter {} ({}; see `rll samplers --params {}`)",
         shown_text(spec), name, fmt::format("'{}'", fmt::join(unknown, "', '")),
         keys.empty() ? fmt::format("{} has no parameters of its own", name)
                      : fmt::format("its parameters: {}", fmt::join(keys, ", ")),
         name);
  }
  params.check_all_used();
  m_params.merge_used(params);
  m_made.push_back(name);
  if (restir) {
    std::lock_guard lock(m_restir_mutex);
    m_restir[sampler.get()] = {spec, is};
  }
  return sampler;
}

void RenderSession::check_params_used() const {
  // A key of a sampler that this command does not render with: say so, rather than list the
  // keys of the samplers it does (the oracle reads rll.* too: those are known then).
  const std::set<std::string> known = m_params.known_keys();
  const std::vector<std::string>& samplers = light_sampler_names();
  for (const auto& [key, value] : m_params.values())
    if (key.rfind("restir.", 0) == 0 && !m_params.used(key))
      fail(
          "--set {}: a parameter of ReSTIR, which renders only with a restir sampler (--sampler "
          "restir, or a spec such as restir:source=rll): leave it out, or render with restir",
          shown_text(key));
  for (const auto& [key, value] : m_params.values()) {
    const size_t dot = key.find('.');
    if (m_params.used(key) || dot == std::string::npos) continue;
    const std::string prefix = key.substr(0, dot);
    if (std::find(samplers.begin(), samplers.end(), prefix) == samplers.end()) continue;
    if (std::any_of(known.begin(), known.end(),
                    [&](const std::string& k) { return k.rfind(prefix + ".", 0) == 0; }))
      continue;
    fail(
        "--set {}: a parameter of sampler {}, which this command does not render with (it renders "
        "with {}): leave it out, or render with {}",
        shown_text(key), prefix,
        m_made.empty() ? "no sampler" : fmt::format("{}", fmt::join(m_made, ", ")), prefix);
  }
  m_params.check_all_used();
}

IntegratorSettings RenderSession::integrator_for(const std::string& spec) const {
  const bool restir = spec.substr(0, spec.find(':')) == "restir";
  if (spec.find(':') == std::string::npos && !restir) return m_integrator;
  std::string name;
  std::vector<std::string> own;
  return make_integrator_settings(m_settings.integrator, m_settings.max_depth,
                                  variant_params(spec, name, own), m_settings.filter, restir);
}

void RenderSession::set_frame(int frame, LightSampler* sampler) {
  if (!m_scene.animate) return;
  m_scene.animate(m_scene, frame);
  m_scene.refresh_lights_from_mesh();
  m_tree.refit(m_scene.lights);
  m_accel->update_vertices(m_scene.mesh);
  if (m_gpu) m_gpu->update(m_scene);
  if (sampler) sampler->lights_changed(m_scene);
}

RenderProgress RenderSession::render(LightSampler& sampler, Film& film,
                                     const RenderSettings& settings, const std::string& label,
                                     bool show_progress, const std::atomic<bool>* cancel,
                                     const AfterPass& after_pass, WavefrontTimes* times,
                                     const IntegratorSettings* integrator_settings) const {
  // A restir sampler renders with its spec's settings (make_sampler) unless told otherwise.
  const IntegratorSettings* made_as = nullptr;
  std::string restir_spec;
  {
    std::lock_guard lock(m_restir_mutex);
    const auto it = m_restir.find(&sampler);
    if (it != m_restir.end()) {
      made_as = &it->second.settings;  // (a map's elements stay where they are)
      restir_spec = it->second.spec;
    }
  }
  const IntegratorSettings& is = integrator_settings ? *integrator_settings
                                 : made_as           ? *made_as
                                                     : m_integrator;
  Integrator integrator(m_scene, *m_accel, sampler, is);
  ProgressBar bar(label, show_progress);
  RenderSettings rs = settings;
  rs.points = m_points;
  WavefrontSettings wavefront;
  wavefront.times = times;
  std::unique_lock lock(m_wavefront_mutex, std::try_to_lock);
  if (lock.owns_lock()) {
    wavefront.work = &m_wavefront_work;
    wavefront.memory = &m_wavefront_memory;
  }
  wavefront.after_pass_reads_film = bool(after_pass);  // (the progress bar reads no film)
  wavefront.film_stays_on_device = m_film_on_device;
  wavefront.tracer = m_settings.tracer == "bvh" ? WavefrontTracer::Bvh : WavefrontTracer::Embree;
  // The filter's temporal reuse on the CPU: the cells the last frame left (the GPU keeps its own).
  std::unique_lock psf_lock(m_psf_mutex, std::defer_lock);
  PsfHistory* history = nullptr;
  const size_t pixels = size_t(film.width()) * film.height();
  if (psf_temporal_frames(is.psf, settings) && !m_gpu && psf_lock.try_lock()) {
    if (!m_psf_history || m_psf_history->cells().pixels != pixels) {
      m_psf_history.reset();
      check_film_memory(
          kRenderBytesPerPixel + kPsfBytesPerPixel + kPsfTemporalBytesPerPixel,
          fmt::format("{}, {} and {}", kRenderPixelText, kPsfPixelText, kPsfTemporalPixelText));
      m_psf_history = std::make_unique<PsfHistory>(pixels);
    }
    history = m_psf_history.get();
  }
  wavefront.psf_history = history;
  // ReSTIR's on the CPU: the vertex records and reservoirs the sampler's last frame left.
  std::unique_lock restir_lock(m_restir_mutex, std::defer_lock);
  if (is.restir.on && !m_gpu && restir_lock.try_lock()) {
    std::unique_ptr<RestirHistory>& h = m_restir_history[restir_spec];
    if (!h || h->frames().pixels != pixels) {
      h.reset();
      h = std::make_unique<RestirHistory>(pixels);
    }
    wavefront.restir_history = h.get();
  }
  wavefront.restir_spec = restir_spec;
  auto run = [&](const RenderSettings& r, const AfterPass& after) {
    if (m_gpu) return m_gpu->render(m_scene, sampler, is, film, r, cancel, after, wavefront);
    // The megakernel has no frame-wide step: ReSTIR renders with the wavefront renderer.
    return m_settings.wavefront || is.restir.on
               ? render_wavefront(m_scene, *m_accel, sampler, is, film, r, cancel, after, wavefront)
               : rll::render(m_scene, integrator, sampler, film, r, cancel, after, history);
  };
  RenderProgress p = run(rs, [&](const RenderProgress& pr, const Film& f) {
    bar.update(pr);
    if (after_pass) after_pass(pr, f);
  });
  if (p.spp_done == 0 && !p.cancelled) {
    // The budget ran out before a whole pass: finish one sample per pixel without a time limit,
    // reporting the two parts as one render.
    const RenderProgress first = p;
    auto combined = [first](RenderProgress q) {
      q.passes += first.passes;
      q.seconds += first.seconds;
      q.samples += first.samples;
      q.nonfinite += first.nonfinite;
      q.rays += first.rays;
      q.spp_target = first.spp_target;
      q.time_limit = first.time_limit;
      q.out_of_time = true;
      return q;
    };
    rs.spp = 1;
    rs.time_limit = 0;
    p = combined(run(rs, [&](const RenderProgress& pr, const Film& f) {
      const RenderProgress q = combined(pr);
      bar.update(q);
      if (after_pass) after_pass(q, f);
    }));
  }
  bar.finish();
  return p;
}

size_t RenderSession::psf_history_bytes() const {
  if (m_gpu) return m_gpu->psf_temporal_bytes();
  std::lock_guard lock(m_psf_mutex);
  return m_psf_history ? m_psf_history->bytes() : 0;
}

std::map<std::string, RestirSettings> RenderSession::restir_made() const {
  std::lock_guard lock(m_restir_mutex);
  std::map<std::string, RestirSettings> made;
  for (const auto& [sampler, m] : m_restir) made[m.spec] = m.settings.restir;
  return made;
}

size_t RenderSession::restir_bytes() const {
  std::lock_guard lock(m_restir_mutex);
  size_t bytes = 0;
  for (const auto& [spec, history] : m_restir_history)
    if (history) bytes += size_t(double(history->frames().pixels) * kRestirBytesPerPixel);
  return bytes;
}

void RenderSession::read_film(Film& film) const {
  if (m_gpu) m_gpu->download_film(film);
}

}  // namespace rll
