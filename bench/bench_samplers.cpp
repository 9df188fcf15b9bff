// Per-call cost of each light sampler (ns per sample and per pmf, through the dispatch every
// renderer runs: lights/light_dispatch.h) and light-tree build time, on open fields of 10k, 100k
// and 1M emissive triangles.
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "rll/accel/accel.h"
#include "rll/core/params.h"
#include "rll/core/rng.h"
#include "rll/lights/light_dispatch.h"
#include "rll/lights/light_sampler.h"
#include "rll/lighttree/light_tree.h"
#include "rll/render/render.h"
#include "rll/scene/builder.h"

using namespace rll;

namespace {

// A floor under `n` small emitters scattered over a square, facing down.
Scene emitter_field_scene(int n) {
  Scene s;
  s.source = "bench-field";
  s.width = 64;
  s.height = 48;
  SceneBuilder b(s);
  uint32_t floor = b.diffuse(Rgb(0.5f));
  uint32_t lamp = b.emitter(Rgb(5.0f));
  float extent = std::sqrt(float(n)) * 0.5f;
  b.quad(Vec3(-extent, 0, -extent), Vec3(0, 0, 2 * extent), Vec3(2 * extent, 0, 0), floor);
  Pcg32 rng(5);
  for (int i = 0; i < n; ++i) {
    Vec3 c(extent * (2 * rng.next_float() - 1), 1 + 3 * rng.next_float(), extent * (2 * rng.next_float() - 1));
    b.triangle(c, c + Vec3(0.05f, 0, 0), c + Vec3(0, 0, 0.05f), lamp);  // x cross z = -y: faces down
  }
  s.camera.position = Vec3(0, extent, extent * 2);
  s.camera.target = Vec3(0, 0, 0);
  s.has_camera = true;
  s.finalize();
  return s;
}

struct Setup {
  Scene scene;
  LightTree tree;
  std::unique_ptr<Accel> accel;
  std::map<std::string, std::unique_ptr<LightSampler>> samplers;
  std::vector<LightContext> contexts;
};

Setup& setup(int n) {
  static std::map<int, std::unique_ptr<Setup>> cache;
  auto& s = cache[n];
  if (!s) {
    s = std::make_unique<Setup>();
    s->scene = emitter_field_scene(n);
    s->tree = build_light_tree(s->scene);
    s->accel = std::make_unique<Accel>(s->scene.mesh);
    Pcg32 rng(9);
    float extent = std::sqrt(float(n)) * 0.5f;
    for (int i = 0; i < 4096; ++i) {
      LightContext c;
      c.p = Vec3(extent * (2 * rng.next_float() - 1), 0, extent * (2 * rng.next_float() - 1));
      c.n = c.ns = Vec3(0, 1, 0);
      c.footprint = 0.05f;
      s->contexts.push_back(c);
    }
  }
  return *s;
}

LightSampler& sampler(Setup& s, const std::string& name) {
  auto& p = s.samplers[name];
  if (!p) {
    Params params;
    p = make_light_sampler(name, s.scene, s.tree, params, s.accel.get());
    if (p->sampler_view().learns) {  // train on a few passes so that cells hold learnt cuts
      IntegratorSettings is;
      is.type = IntegratorType::Direct;
      Integrator integrator(s.scene, *s.accel, *p, is);
      Film film(s.scene.width, s.scene.height);
      RenderSettings rs;
      rs.spp = 8;
      render(s.scene, integrator, *p, film, rs);
    }
    const SamplerView v = p->sampler_view();
    for (auto& c : s.contexts) prepare_point(v, c, 0.5f);
  }
  return *p;
}

void BM_Sample(benchmark::State& state, const std::string& name) {
  Setup& s = setup(int(state.range(0)));
  const SamplerView v = sampler(s, name).sampler_view();
  Pcg32 rng(1);
  size_t i = 0;
  for (auto _ : state) {
    SampledLight l = sample_light(v, s.contexts[i++ & 4095], rng.next_double());
    benchmark::DoNotOptimize(l);
  }
}

void BM_Pmf(benchmark::State& state, const std::string& name) {
  Setup& s = setup(int(state.range(0)));
  const SamplerView v = sampler(s, name).sampler_view();
  Pcg32 rng(2);
  const uint32_t n = uint32_t(s.scene.lights.size());
  size_t i = 0;
  for (auto _ : state) {
    float p = light_pmf(v, s.contexts[i++ & 4095], rng.next_bounded(n));
    benchmark::DoNotOptimize(p);
  }
}

void BM_TreeBuild(benchmark::State& state) {
  Setup& s = setup(int(state.range(0)));
  // On a copy: build() reorders the lights, which the samplers made over s.tree read in its order.
  Scene scene = s.scene;
  for (auto _ : state) {
    LightTree t = LightTree::build(scene);
    benchmark::DoNotOptimize(t.node_count());
  }
}

void BM_TreeRefit(benchmark::State& state) {
  Setup& s = setup(int(state.range(0)));
  for (auto _ : state) s.tree.refit(s.scene.lights);
}

}  // namespace

int main(int argc, char** argv) {
  for (const auto& name : light_sampler_names()) {
    if (name == "oracle") continue;  // samples exactly like rll; its cost is a preprocess
    benchmark::RegisterBenchmark(("sample/" + name).c_str(), BM_Sample, name)->Arg(10000)->Arg(100000)->Arg(1000000);
    benchmark::RegisterBenchmark(("pmf/" + name).c_str(), BM_Pmf, name)->Arg(10000)->Arg(100000)->Arg(1000000);
  }
  benchmark::RegisterBenchmark("tree_build", BM_TreeBuild)
      ->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();
  benchmark::RegisterBenchmark("tree_refit", BM_TreeRefit)
      ->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
}
