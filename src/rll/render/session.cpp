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
  m_scene = load_scene(settings.scene, lo);
  m_integrator = make_integrator_settings(settings.integrator, settings.max_depth, m_params);
  m_accel = std::make_unique<Accel>(m_scene.mesh);
}

std::unique_ptr<LightSampler> RenderSession::make_sampler(const std::string& name) const {
  return make_light_sampler(name, m_scene, m_params, m_accel.get());
}

RenderProgress RenderSession::render(LightSampler& sampler, Film& film,
                                     const RenderSettings& settings, const std::string& label,
                                     bool show_progress, const std::atomic<bool>* cancel,
                                     const AfterPass& after_pass) const {
  Integrator integrator(m_scene, *m_accel, sampler, m_integrator);
  ProgressBar bar(label, show_progress);
  RenderProgress p = rll::render(m_scene, integrator, sampler, film, settings, cancel,
                                 [&](const RenderProgress& pr, const Film& f) {
                                   bar.update(pr);
                                   if (after_pass) after_pass(pr, f);
                                 });
  bar.finish();
  return p;
}

}  // namespace rll
