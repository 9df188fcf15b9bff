// Traced rays per second of the whole renderer on a scene, against a bare loop that traces
// the very same rays (recorded from the renderer) through the ray tracer with nothing else.
// The renderer's goal: keep at least 50% of the bare rate.
#include <fmt/format.h>

#include <chrono>

#include "rll/accel/accel.h"
#include "rll/core/error.h"
#include "rll/core/params.h"
#include "rll/core/parallel.h"
#include "rll/lighttree/light_tree.h"
#include "rll/render/render.h"
#include "rll/io/load.h"

using namespace rll;
using Clock = std::chrono::steady_clock;

namespace {
double seconds(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
}  // namespace

int main(int argc, char** argv) try {
  std::string scene_name = argc > 1 ? argv[1] : "builtin:cornell-boxes-room";
  std::string sampler_name = argc > 2 ? argv[2] : "power";
  int spp = argc > 3 ? std::atoi(argv[3]) : 4;
  int threads = argc > 4 ? std::atoi(argv[4]) : 0;
  ThreadLimit limit(threads);
  Scene scene = load_scene(scene_name);
  const LightTree tree = build_light_tree(scene);
  Accel accel(scene.mesh);
  Params params;
  auto sampler = make_light_sampler(sampler_name, scene, tree, params);
  IntegratorSettings is;  // path, MIS, depth 5
  Integrator integrator(scene, accel, *sampler, is);
  RenderSettings rs;
  rs.spp = spp;

  // 1. Record the rays of one render (single thread: the log is not thread-safe).
  RayLog log;
  {
    ThreadLimit one(1);
    accel.set_log(&log);
    Film film(scene.width, scene.height);
    render(scene, integrator, *sampler, film, rs);
    accel.set_log(nullptr);
  }
  const size_t total = log.closest.size() + log.shadow.size();

  // 2. The renderer, same settings and seed, timed (median of 3).
  std::vector<double> render_rates, bare_rates;
  for (int rep = 0; rep < 3; ++rep) {
    Film film(scene.width, scene.height);
    auto t0 = Clock::now();
    RenderProgress p = render(scene, integrator, *sampler, film, rs);
    render_rates.push_back(double(p.rays.total()) / seconds(t0));

    // 3. The bare loop: the same rays, in parallel chunks, nothing but the ray queries.
    std::atomic<uint64_t> hits{0};
    auto t1 = Clock::now();
    parallel_for(log.closest.size(), 4096, [&](size_t b, size_t e) {
      uint64_t h = 0;
      Hit hit;
      for (size_t i = b; i < e; ++i) h += accel.intersect(log.closest[i], hit);
      hits += h;
    });
    parallel_for(log.shadow.size(), 4096, [&](size_t b, size_t e) {
      uint64_t h = 0;
      for (size_t i = b; i < e; ++i) h += accel.occluded(log.shadow[i]);
      hits += h;
    });
    bare_rates.push_back(double(total) / seconds(t1));
  }
  std::sort(render_rates.begin(), render_rates.end());
  std::sort(bare_rates.begin(), bare_rates.end());
  double r = render_rates[1], b = bare_rates[1];
  fmt::print("scene {} sampler {} spp {} threads {}: {} rays ({} closest-hit, {} shadow)\n", scene_name,
             sampler_name, spp, threads > 0 ? threads : hardware_threads(), total, log.closest.size(), log.shadow.size());
  fmt::print("renderer   {:8.2f} M rays/s (median of 3)\n", r * 1e-6);
  fmt::print("bare loop  {:8.2f} M rays/s (median of 3)\n", b * 1e-6);
  fmt::print("ratio      {:8.1f} %  (goal >= 50%)\n", 100 * r / b);
  return 0;
} catch (const Error& e) {
  fmt::print(stderr, "rll_bench_rays: error: {}\n", e.what());
  return 1;
}
