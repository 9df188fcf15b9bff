// The 102,400-spot-light hall (builtin:spot-hall): time to build the scene (its geometry and
// lights), to finalize it, to build its light tree, and the memory of the tree and of each
// sampler's state (describe()["bytes"] where the sampler reports it), the peak RSS after.
// Goal (issue 32): load and build in under 2 s on 2 cores, sampler memory within 512 MiB.
// Usage: rll_bench_spot_hall [REPEATS]
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "rll/core/params.h"
#include "rll/core/parallel.h"
#include "rll/core/sysinfo.h"
#include "rll/lights/light_sampler.h"
#include "rll/lighttree/light_tree.h"
#include "rll/scene/builtin.h"

using namespace rll;
using Clock = std::chrono::steady_clock;

namespace {
double seconds(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  std::vector<double> make_s, finalize_s, tree_s;
  Scene scene;
  LightTree tree;
  for (int r = 0; r < repeats; ++r) {
    auto t0 = Clock::now();
    scene = make_builtin_scene("spot-hall");
    make_s.push_back(seconds(t0));
    t0 = Clock::now();
    scene.finalize();
    finalize_s.push_back(seconds(t0));
    t0 = Clock::now();
    tree = build_light_tree(scene);
    tree_s.push_back(seconds(t0));
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  fmt::print("spot-hall: {} lights, {} triangles, {} threads\n", scene.lights.size(),
             scene.mesh.triangle_count(), hardware_threads());
  fmt::print("median of {}: make {:.3f} s, finalize {:.3f} s, light tree {:.3f} s, total {:.3f} s\n",
             repeats, median(make_s), median(finalize_s), median(tree_s),
             median(make_s) + median(finalize_s) + median(tree_s));
  fmt::print("light tree: {:.1f} MiB\n", tree.bytes() / 1048576.0);
  for (const char* name : {"power", "tree", "ltc", "rll"}) {
    Params p;
    const auto t0 = Clock::now();
    auto sampler = make_light_sampler(name, scene, tree, p);
    const double s = seconds(t0);
    const nlohmann::json d = sampler->describe();
    fmt::print("{:<6} made in {:.3f} s, state {}\n", name, s,
               d.contains("bytes") ? fmt::format("{:.1f} MiB", d["bytes"].get<double>() / 1048576.0)
                                   : std::string("(not reported)"));
  }
  fmt::print("peak RSS {:.1f} MiB\n", peak_rss_bytes() / 1048576.0);
  return 0;
}
