// rll.reference and rll.compare: the cached high-sample reference of `rll reference`, and the
// interleaved, repeated measurement of several samplers of `rll compare`, returned as the data
// of its summary.json with the images as numpy arrays.
#include <pybind11/stl.h>

#include <map>

#include "module.h"
#include "rll/core/error.h"
#include "rll/core/parallel.h"
#include "rll/eval/compare.h"
#include "rll/eval/metrics.h"
#include "rll/eval/reference.h"

namespace rll::python {

namespace {

constexpr long long kMaxSpp = (1 << 30) - 1;  // as `rll compare --spp`
constexpr int kMaxThreads = 4096;             // as render()'s

SessionSettings measured_settings(const PyScene& scene, const std::string& integrator,
                                  int max_depth, const std::vector<std::string>& params) {
  SessionSettings s = settings_with(scene, params);
  s.integrator = integrator;
  s.max_depth = max_depth;
  return s;
}

ReferenceCache cache_at(const Call& c, const Arg<std::optional<PathLike>>& cache_dir) {
  return ReferenceCache(cache_dir.obj.is_none()
                            ? default_cache_dir()
                            : std::filesystem::path(c.path(cache_dir.obj, "cache_dir")));
}

// The reference as compare's summary.json describes it, its image and variance (0x0: unknown).
struct Reference {
  Image image, variance;
  nlohmann::json json;
};

// Renders (or finds in the cache) the reference with the GIL released, Ctrl-C cancelling it as
// a render (run_watched): then KeyboardInterrupt, and nothing is stored.
Reference obtain(const RenderSession& session, const ReferenceCache& cache,
                 const ReferenceRequest& request) {
  ObtainedReference got;
  PassWatcher watch;
  run_watched(watch,
              [&] { got = obtain_reference(session, cache, request, false, &watch.cancel); });
  watch.rethrow_or_interrupt();
  if (!got.complete) fail("the reference render was cancelled");  // (only Ctrl-C cancels it)
  Reference r;
  r.image = std::move(got.image);
  r.variance = std::move(got.variance);
  r.json = reference_json(got.from_cache, got.info, r.image, r.variance);
  return r;
}

py::dict py_reference(const Arg<PyScene>& scene_arg, const Arg<long long>& spp_arg,
                      const Arg<std::string>& sampler_arg, const Arg<uint64_t>& seed_arg,
                      const Arg<std::string>& integrator_arg, const Arg<int>& max_depth_arg,
                      const Arg<py::dict>& params_arg,
                      const Arg<std::optional<PathLike>>& cache_dir_arg, const Arg<bool>& force_arg,
                      const Arg<int>& threads_arg) {
  const Call c{"reference"};
  const std::shared_ptr<PyScene> scene_ptr = c.scene(scene_arg, "scene");
  PyScene& scene = *scene_ptr;
  const long long spp = c.get(spp_arg, "spp");
  const std::string sampler = c.get(sampler_arg, "sampler");
  const uint64_t seed = c.get(seed_arg, "seed");
  const std::string integrator = c.get(integrator_arg, "integrator");
  const int max_depth = c.get(max_depth_arg, "max_depth");
  const std::vector<std::string> params = c.params(params_arg, "params");
  const ReferenceCache cache = cache_at(c, cache_dir_arg);
  const bool force = c.get(force_arg, "force");
  const int threads = c.get(threads_arg, "threads");
  if (spp < 2 || spp > kMaxSpp) fail("spp: {} is not in [2, {}]", spp, kMaxSpp);
  const SessionSettings settings = measured_settings(scene, integrator, max_depth, params);
  // The lock is taken without the GIL: a render holding it takes the GIL to look for Ctrl-C.
  std::unique_lock<std::mutex> lock(scene.mutex, std::defer_lock);
  {
    py::gil_scoped_release release;
    lock.lock();
  }
  const auto session = session_for(scene, settings);
  named_sampler(*session, sampler);  // its name and parameters checked before rendering
  ReferenceRequest request;
  request.sampler = sampler;
  request.spp = int(spp);
  request.seed = seed;
  request.force = force;
  if (threads < 0 || threads > kMaxThreads)
    fail("threads: {} is not in [0, {}] (0: all cores)", threads, kMaxThreads);
  ThreadLimit limit(threads);
  const Reference ref = obtain(*session, cache, request);
  py::dict d = to_python(ref.json);
  d["image"] = image_to_array(ref.image);
  d["variance"] =
      ref.variance.pixel_count() ? py::object(image_to_array(ref.variance)) : py::none();
  return d;
}

py::dict py_compare(
    const Arg<PyScene>& scene_arg, const Arg<std::vector<std::string>>& samplers_arg,
    const Arg<std::optional<long long>>& spp_arg, const Arg<std::optional<double>>& time_arg,
    const Arg<int>& repeats_arg, const Arg<uint64_t>& seed_arg, const Arg<ReferenceLike>& reference,
    const Arg<long long>& reference_spp_arg, const Arg<std::string>& reference_sampler_arg,
    const Arg<std::string>& integrator_arg, const Arg<int>& max_depth_arg,
    const Arg<py::dict>& params_arg, const Arg<std::optional<PathLike>>& cache_dir_arg,
    const Arg<int>& threads_arg, const Arg<Callback>& progress_arg) {
  const Call c{"compare"};
  const std::shared_ptr<PyScene> scene_ptr = c.scene(scene_arg, "scene");
  PyScene& scene = *scene_ptr;
  const std::vector<std::string> samplers = c.get(samplers_arg, "samplers");
  const std::optional<long long> spp = c.get(spp_arg, "spp");
  const std::optional<double> time = c.get(time_arg, "time");
  const int repeats = c.get(repeats_arg, "repeats");
  const uint64_t seed = c.get(seed_arg, "seed");
  const long long reference_spp = c.get(reference_spp_arg, "reference_spp");
  const std::string reference_sampler = c.get(reference_sampler_arg, "reference_sampler");
  const std::string integrator = c.get(integrator_arg, "integrator");
  const int max_depth = c.get(max_depth_arg, "max_depth");
  const std::vector<std::string> params = c.params(params_arg, "params");
  const ReferenceCache cache = cache_at(c, cache_dir_arg);
  const int threads = c.get(threads_arg, "threads");
  const py::object progress = c.callback(progress_arg, "progress");
  if (samplers.empty()) fail("samplers: give at least one sampler");
  for (size_t i = 0; i < samplers.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (samplers[i] == samplers[j]) fail("samplers: '{}' is given twice", samplers[i]);
  if (spp.has_value() == time.has_value())
    fail("give one budget: spp (samples per pixel) or time (seconds per run)");
  if (spp && (*spp < 1 || *spp > kMaxSpp)) fail("spp: {} is not in [1, {}]", *spp, kMaxSpp);
  if (time && !(*time > 0 && *time <= 1e7)) fail("time: {} seconds is not in (0, 1e7]", *time);
  if (repeats < 1 || repeats > 1000) fail("repeats: {} is not in [1, 1000]", repeats);
  if (reference_spp < 1 || reference_spp > kMaxSpp)  // as `rll compare --reference-spp`
    fail("reference_spp: {} is not in [1, {}]", reference_spp, kMaxSpp);
  if (threads < 0 || threads > kMaxThreads)
    fail("threads: {} is not in [0, {}] (0: all cores)", threads, kMaxThreads);
  const SessionSettings settings = measured_settings(scene, integrator, max_depth, params);
  std::unique_lock<std::mutex> lock(scene.mutex, std::defer_lock);
  {
    py::gil_scoped_release release;
    lock.lock();
  }
  const auto session = session_for(scene, settings);
  for (const auto& name : samplers) named_sampler(*session, name);
  const Scene& sc = session->scene();
  ThreadLimit limit(threads);

  Reference ref;
  if (reference.obj.is_none()) {
    ReferenceRequest request;
    request.sampler = reference_sampler;
    request.spp = int(reference_spp);
    // A reference never shares its seeds (and noise) with a run.
    request.seed_allowed = [&](uint64_t s) { return !reference_shares_a_seed(s, seed, repeats); };
    ref = obtain(*session, cache, request);
  } else {
    const py::object& r = reference.obj;
    if (PyUnicode_Check(r.ptr()) || PyBytes_Check(r.ptr()) || py::hasattr(r, "__fspath__")) {
      const std::string path = c.path(r, "reference");
      ref.image = read_measured_image(path, MeasuredRole::reference);
      ref.json = {{"source", "file"}, {"path", path}};
    } else {
      ref.image = c.image(r, "reference");
      ref.json = {{"source", "array"}};
    }
    check_measured_pixels(ref.image, "reference", MeasuredRole::reference);
    if (ref.image.width() != sc.width || ref.image.height() != sc.height)
      fail("reference: the image is {}x{} but the scene renders at {}x{}", ref.image.width(),
           ref.image.height(), sc.width, sc.height);
  }

  PassWatcher watch(progress);
  std::vector<RunResult> runs;
  std::map<std::string, Image> first_images;
  py::list order;
  const int n = int(samplers.size());
  for (int r = 0; r < repeats && !watch.cancel; ++r) {
    py::list this_repeat;
    for (int k = 0; k < n && !watch.cancel; ++k) {
      const std::string& name = samplers[size_t((k + r) % n)];
      this_repeat.append(name);
      RenderSettings rs;
      rs.spp = time ? kUnlimitedSpp : int(*spp);
      rs.time_limit = time.value_or(0);
      rs.seed = seed + uint64_t(r);
      MeasuredRun m;
      run_watched(watch, [&] {
        m = measure_run(*session, name, r, rs, 1, ref.image,
                        ref.variance.pixel_count() ? &ref.variance : nullptr, name, false,
                        &watch.cancel, [&](const RenderProgress& p, const Film&) { watch(p); });
      });
      watch.rethrow();
      if (m.cancelled) break;
      runs.push_back(std::move(m.result));
      if (r == 0) first_images.emplace(name, std::move(m.image));
    }
    order.append(this_repeat);
  }
  watch.rethrow_or_interrupt();
  const std::vector<SamplerSummary> summaries = summarize(samplers, runs);

  py::dict d;
  d["scene"] = path_to_python(scene.settings.scene);
  d["resolution"] = py::make_tuple(sc.width, sc.height);
  d["lights"] = sc.lights.size();
  d["integrator"] = integrator;
  d["max_depth"] = session->integrator().max_depth;
  d["budget"] = time ? to_python({{"time", *time}}) : to_python({{"spp", *spp}});
  d["repeats"] = repeats;
  d["seed"] = seed;
  d["threads"] = threads > 0 ? threads : hardware_threads();
  d["set"] = settings.set;
  d["reference"] = to_python(ref.json);
  d["order"] = order;
  py::list entries;
  py::dict images;
  for (const auto& s : summaries) {
    entries.append(to_python(sampler_summary_json(s)));
    images[py::str(s.name)] = image_to_array(first_images.at(s.name));
  }
  d["samplers"] = entries;
  d["images"] = images;
  d["reference_image"] = image_to_array(ref.image);
  return d;
}

}  // namespace

void bind_measure(py::module_& m) {
  m.def("reference", &py_reference, py::arg("scene"), py::arg("spp") = 1024,
        py::arg("sampler") = "tree", py::arg("seed") = kDefaultReferenceSeed,
        py::arg("integrator") = "path", py::arg("max_depth") = 5, py::arg("params") = py::dict(),
        py::arg("cache_dir") = py::none(), py::arg("force") = false, py::arg("threads") = 0,
        "The reference of `rll reference`: the cached one for the scene and integrator settings\n"
        "with at least `spp` samples per pixel, or one rendered as two halves (seeds `seed` and\n"
        "`seed` + 1) and cached (`cache_dir`, default $RLL_CACHE_DIR or out/cache; `force`\n"
        "renders anew). A dict: image (HxWx3 float32), variance (its per-pixel variance from the\n"
        "halves, or None), source ('cache' or 'rendered'), cache_entry, sampler, spp, seed,\n"
        "seconds, noise_relmse.");
  m.def("compare", &py_compare, py::arg("scene"), py::arg("samplers"), py::arg("spp") = py::none(),
        py::arg("time") = py::none(), py::arg("repeats") = 1, py::arg("seed") = 1,
        py::arg("reference") = py::none(), py::arg("reference_spp") = 1024,
        py::arg("reference_sampler") = "tree", py::arg("integrator") = "path",
        py::arg("max_depth") = 5, py::arg("params") = py::dict(), py::arg("cache_dir") = py::none(),
        py::arg("threads") = 0, py::arg("progress") = py::none(),
        "Measures `samplers` as `rll compare` does: every sampler under one budget (`spp`, or\n"
        "`time` seconds per run), fresh each run, runs interleaved over `repeats` (seeds seed,\n"
        "seed + 1, ...), against `reference` (an HxWx3 array, an image file, or None: the cached\n"
        "reference of rll.reference with `reference_spp` and `reference_sampler`). Returns the\n"
        "data of compare's summary.json as a dict: scene, budget, repeats, seed, reference,\n"
        "order, and per sampler (in the order given) spp, seconds, relmse, trimmed_relmse, mrse,\n"
        "mse, efficiency, ratios, visible_ratio, memory and convergence checkpoints (median,\n"
        "min, max and values over repeats); with `images` (sampler -> its first repeat's image)\n"
        "and `reference_image`. `progress(dict)` is called after every pass; Ctrl-C raises\n"
        "KeyboardInterrupt.");
}

}  // namespace rll::python
