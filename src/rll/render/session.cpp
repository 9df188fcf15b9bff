#include "rll/render/session.h"

#include <cstdio>

#include "rll/core/error.h"
#include "rll/render/progress.h"

namespace rll {

LoadOptions parse_resolution(const std::string& res) {
  LoadOptions lo;
  if (res.empty()) return lo;
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(res.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X'))
    fail("--res '{}': expected WIDTHxHEIGHT, e.g. 640x480", res);
  if (w <= 0 || h <= 0) fail("--res '{}': width and height must be positive", res);
  lo.width = w;
  lo.height = h;
  return lo;
}

RenderSession::RenderSession(const SessionSettings& settings)
    : m_settings(settings), m_params(Params::parse(settings.set)) {
  const LoadOptions lo = parse_resolution(settings.resolution);
  m_points = parse_point_set(settings.points, "--points");
  m_scene = load_scene(settings.scene, lo);
  m_integrator = make_integrator_settings(settings.integrator, settings.max_depth, m_params);
  m_accel = std::make_unique<Accel>(m_scene.mesh);
}

std::unique_ptr<LightSampler> RenderSession::make_sampler(const std::string& spec) const {
  size_t colon = spec.find(':');
  if (colon == std::string::npos) return make_light_sampler(spec, m_scene, m_params, m_accel.get());
  const std::string name = spec.substr(0, colon);
  Params params = m_params;
  for (size_t start = colon + 1; start <= spec.size();) {
    size_t end = std::min(spec.find(':', start), spec.size());
    std::string kv = spec.substr(start, end - start);
    size_t eq = kv.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == kv.size())
      fail("sampler '{}': '{}' is not key=value", spec, kv);
    std::string key = kv.substr(0, eq);
    if (key.find('.') == std::string::npos) key = name + "." + key;
    params.set(key, kv.substr(eq + 1));
    start = end + 1;
  }
  auto sampler = make_light_sampler(name, m_scene, params, m_accel.get());
  params.check_all_used();  // a variant's own keys must all be known
  m_params.merge_used(params);
  return sampler;
}

void RenderSession::set_frame(int frame, LightSampler* sampler) {
  if (!m_scene.animate) return;
  m_scene.animate(m_scene, frame);
  m_scene.refresh_lights_from_mesh();
  m_accel->update_vertices(m_scene.mesh);
  if (sampler) sampler->lights_changed(m_scene);
}

RenderProgress RenderSession::render(LightSampler& sampler, Film& film,
                                     const RenderSettings& settings, const std::string& label,
                                     bool show_progress, const std::atomic<bool>* cancel,
                                     const AfterPass& after_pass) const {
  Integrator integrator(m_scene, *m_accel, sampler, m_integrator);
  ProgressBar bar(label, show_progress);
  RenderSettings rs = settings;
  rs.points = m_points;
  RenderProgress p = rll::render(m_scene, integrator, sampler, film, rs, cancel,
                                 [&](const RenderProgress& pr, const Film& f) {
                                   bar.update(pr);
                                   if (after_pass) after_pass(pr, f);
                                 });
  bar.finish();
  return p;
}

}  // namespace rll
