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

SessionSettings measured_settings(const PyScene& scene, const std::string& integrator,
                                  int max_depth, const py::dict& params) {
  SessionSettings s = settings_with(scene, params);
  s.integrator = integrator;
  s.max_depth = max_depth;
  return s;
}

ReferenceCache cache_at(const py::object& cache_dir) {
  return ReferenceCache(cache_dir.is_none() ? default_cache_dir()
                                            : std::filesystem::path(fspath(cache_dir)));
}

// The reference as compare's summary.json describes it, its image and variance (0x0: unknown).
struct Reference {
  Image image, variance;
  nlohmann::json json;
};

Reference obtain(const RenderSession& session, const ReferenceCache& cache,
                 const ReferenceRequest& request) {
  ObtainedReference got;
  {
    py::gil_scoped_release release;
    got = obtain_reference(session, cache, request, false);
  }
  Reference r;
  r.image = std::move(got.image);
  r.variance = std::move(got.variance);
  r.json = reference_json(got.from_cache, got.info, r.image, r.variance);
  return r;
}

py::dict py_reference(PyScene& scene, long long spp, const std::string& sampler, uint64_t seed,
                      const std::string& integrator, int max_depth, const py::dict& params,
                      const py::object& cache_dir, bool force, int threads) {
  if (spp < 2 || spp > kMaxSpp) fail("spp: {} is not in [2, {}]", spp, kMaxSpp);
  const SessionSettings settings = measured_settings(scene, integrator, max_depth, params);
  std::lock_guard<std::mutex> lock(scene.mutex);
  const auto session = session_for(scene, settings);
  named_sampler(*session, sampler);  // its name and parameters checked before rendering
  ReferenceRequest request;
  request.sampler = sampler;
  request.spp = int(spp);
  request.seed = seed;
  request.force = force;
  ThreadLimit limit(threads);
  const Reference ref = obtain(*session, cache_at(cache_dir), request);
  py::dict d = to_python(ref.json);
  d["image"] = image_to_array(ref.image);
  d["variance"] =
      ref.variance.pixel_count() ? py::object(image_to_array(ref.variance)) : py::none();
  return d;
}

py::dict py_compare(PyScene& scene, const std::vector<std::string>& samplers,
                    std::optional<long long> spp, std::optional<double> time, int repeats,
                    uint64_t seed, const py::object& reference, long long reference_spp,
                    const std::string& reference_sampler, const std::string& integrator,
                    int max_depth, const py::dict& params, const py::object& cache_dir, int threads,
                    const py::object& progress) {
  if (samplers.empty()) fail("samplers: give at least one sampler");
  for (size_t i = 0; i < samplers.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (samplers[i] == samplers[j]) fail("samplers: '{}' is given twice", samplers[i]);
  if (spp.has_value() == time.has_value())
    fail("give one budget: spp (samples per pixel) or time (seconds per run)");
  if (spp && (*spp < 1 || *spp > kMaxSpp)) fail("spp: {} is not in [1, {}]", *spp, kMaxSpp);
  if (time && !(*time > 0 && *time <= 1e7)) fail("time: {} seconds is not in (0, 1e7]", *time);
  if (repeats < 1 || repeats > 1000) fail("repeats: {} is not in [1, 1000]", repeats);
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    fail("progress: expected a callable or None");
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
  if (reference.is_none()) {
    ReferenceRequest request;
    request.sampler = reference_sampler;
    request.spp = int(reference_spp);
    // A reference never shares its seeds (and noise) with a run.
    request.seed_allowed = [&](uint64_t s) { return !reference_shares_a_seed(s, seed, repeats); };
    ref = obtain(*session, cache_at(cache_dir), request);
  } else {
    if (py::isinstance<py::array>(reference)) {
      ref.image = image_from_array(reference, "reference");
      ref.json = {{"source", "array"}};
    } else {
      const std::string path = fspath(reference);
      ref.image = read_measured_image(path, MeasuredRole::reference);
      ref.json = {{"source", "file"}, {"path", path}};
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
  if (watch.interrupted) {
    PyErr_SetNone(PyExc_KeyboardInterrupt);
    throw py::error_already_set();
  }
  const std::vector<SamplerSummary> summaries = summarize(samplers, runs);

  py::dict d;
  d["scene"] = scene.settings.scene;
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
