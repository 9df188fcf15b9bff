// The Python module `rll`: loads scenes, renders them with any light sampler into numpy arrays,
// measures images against references and reads and writes EXR files, over the library (the
// session and evaluation layers), not the command line.
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "module.h"
#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/core/parallel.h"
#include "rll/eval/metrics.h"
#include "rll/lights/light_sampler.h"
#include "rll/render/aov.h"
#include "rll/render/film.h"
#include "rll/render/render.h"
#include "rll/render/share.h"
#include "rll/scene/builtin.h"
#include "rll/session/session.h"

using namespace rll;
using namespace rll::python;

namespace rll::python {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "images are handed to numpy as float triples");

std::string fspath(const py::handle& path) {
  return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}

py::array image_to_array(Image image) {
  auto* owned = new Image(std::move(image));
  py::capsule free_image(owned, [](void* p) { delete static_cast<Image*>(p); });
  const auto h = py::ssize_t(owned->height()), w = py::ssize_t(owned->width());
  const auto f = py::ssize_t(sizeof(float));
  return py::array_t<float>({h, w, py::ssize_t(3)}, {w * 3 * f, 3 * f, f},
                            reinterpret_cast<const float*>(owned->pixels().data()), free_image);
}

Image image_from_array(const py::handle& obj, const char* name) {
  auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a) fail("{}: expected an HxWx3 array of numbers", name);
  if (a.ndim() != 3 || a.shape(2) != 3 || a.shape(0) < 1 || a.shape(1) < 1)
    fail("{}: expected an HxWx3 array, got shape {}", name,
         py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()))))
             .cast<std::string>());
  if (a.shape(0) > kMaxImageSide || a.shape(1) > kMaxImageSide ||
      size_t(a.shape(0)) * size_t(a.shape(1)) > kMaxImagePixels)
    fail("{}: {}x{} is larger than rll's image limit", name, a.shape(1), a.shape(0));
  Image image(int(a.shape(1)), int(a.shape(0)));
  std::memcpy(static_cast<void*>(image.pixels().data()), a.data(),
              image.pixel_count() * sizeof(Rgb));
  return image;
}

}  // namespace rll::python

namespace {

// The limits of the command line's flags (apps/commands.h), so that Python takes what `rll render`
// takes.
constexpr long long kMaxSpp = (1 << 30) - 1;
constexpr int kMaxPassSpp = 1024;  // as `rll render --pass-spp`
constexpr int kMaxThreads = 4096;
constexpr double kMaxSeconds = 1e7;

// "WIDTHxHEIGHT" from None (empty: the scene's own), a string or a (width, height) pair.
std::string resolution_arg(const py::object& res) {
  if (res.is_none()) return "";
  if (py::isinstance<py::str>(res)) return res.cast<std::string>();
  if (py::isinstance<py::sequence>(res) && py::len(res) == 2) {
    auto wh = res.cast<std::vector<long long>>();
    return std::to_string(wh[0]) + "x" + std::to_string(wh[1]);
  }
  fail("res: expected None, 'WIDTHxHEIGHT' or (width, height), got {}",
       py::repr(res).cast<std::string>());
}

// A parameter value as `--set key=value` takes it (Python's True is "true").
std::string param_value(const py::handle& v) {
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  return py::str(v).cast<std::string>();
}

std::shared_ptr<RenderSession> make_session(const SessionSettings& s) {
  py::gil_scoped_release release;
  return std::make_shared<RenderSession>(s);
}

}  // namespace

namespace rll::python {

SessionSettings settings_with(const PyScene& scene, const py::dict& params) {
  SessionSettings settings = scene.settings;
  for (const auto& [k, v] : params)
    settings.set.push_back(py::str(k).cast<std::string>() + "=" + param_value(v));
  Params::parse(settings.set);  // a malformed key fails before the scene is loaded again
  return settings;
}

std::shared_ptr<RenderSession> session_for(PyScene& scene, const SessionSettings& settings) {
  const SessionSettings& own = scene.settings;
  const bool same = settings.integrator == own.integrator && settings.max_depth == own.max_depth &&
                    settings.resolution == own.resolution && settings.set == own.set &&
                    settings.wavefront == own.wavefront && settings.device == own.device;
  return same ? scene.session : make_session(settings);
}

std::shared_ptr<LightSampler> named_sampler(const RenderSession& session, const std::string& spec) {
  try {
    std::shared_ptr<LightSampler> sampler = session.make_sampler(spec);
    session.check_params_used();
    return sampler;
  } catch (const Error& e) {
    const std::string msg = e.what();
    if (msg.rfind("--set: ", 0) == 0) throw Error("params: " + msg.substr(7));
    throw Error("sampler: " + msg);
  }
}

}  // namespace rll::python

namespace {

std::shared_ptr<PyScene> py_load(const py::object& path, const py::object& res) {
  auto s = std::make_shared<PyScene>();
  s->settings.scene = fspath(path);
  s->settings.resolution = resolution_arg(res);
  s->session = make_session(s->settings);
  return s;
}

struct PyRender {
  py::array image;
  py::array counts;
  int spp = 0;
  double seconds = 0;
  bool interrupted = false;
  py::dict stats;
  py::object state = py::none();
  py::dict aov;
};

}  // namespace

namespace rll::python {

py::dict progress_dict(const RenderProgress& p) {
  py::dict d;
  d["passes"] = p.passes;
  d["spp"] = p.spp_done;
  d["spp_target"] = p.spp_target;
  d["seconds"] = p.seconds;
  d["samples"] = p.samples;
  return d;
}

py::object to_python(const nlohmann::json& j) {
  return py::module_::import("json").attr("loads")(j.dump());
}

void PassWatcher::operator()(const RenderProgress& p) {
  py::gil_scoped_acquire gil;
  try {
    if (!progress.is_none()) progress(progress_dict(p));
  } catch (py::error_already_set& e) {
    if (e.matches(PyExc_KeyboardInterrupt))
      interrupted = true;
    else
      callback_error = std::current_exception();
    cancel = true;
  }
}

void PassWatcher::check_signals() {
  if (PyErr_CheckSignals() == 0) return;
  py::error_already_set e;  // takes the exception the handler raised
  if (e.matches(PyExc_KeyboardInterrupt))
    interrupted = true;
  else if (!callback_error)
    callback_error = std::make_exception_ptr(std::move(e));
  cancel = true;
}

void run_watched(PassWatcher& watch, const std::function<void()>& work) {
  std::mutex m;
  std::condition_variable cv;
  bool done = false;
  std::exception_ptr error;
  py::gil_scoped_release release;
  std::thread worker([&] {
    try {
      work();
    } catch (...) {
      error = std::current_exception();
    }
    std::lock_guard lock(m);
    done = true;
    cv.notify_all();
  });
  std::unique_lock lock(m);
  while (!cv.wait_for(lock, std::chrono::milliseconds(kSignalPollMs), [&] { return done; })) {
    lock.unlock();
    {
      py::gil_scoped_acquire gil;
      watch.check_signals();
    }
    lock.lock();
  }
  lock.unlock();
  worker.join();
  if (error) std::rethrow_exception(error);
}

void PassWatcher::rethrow() const {
  if (callback_error) std::rethrow_exception(callback_error);
}

}  // namespace rll::python

namespace {

PyRender py_render(PyScene& scene, const std::string& sampler_spec, const std::string& integrator,
                   int max_depth, long long spp, std::optional<double> time, const py::object& res,
                   uint64_t seed, const py::dict& params, int threads, const py::object& progress,
                   const py::object& aov, bool wavefront, const std::string& device,
                   int pass_spp, long long max_pass_spp) {
  std::vector<Aov> aovs;
  if (!aov.is_none()) {
    std::string list;
    if (py::isinstance<py::str>(aov)) {
      list = aov.cast<std::string>();
    } else {
      for (const auto& name : aov.cast<std::vector<std::string>>())
        list += (list.empty() ? "" : ",") + name;
    }
    aovs = parse_aovs(list, "aov");
  }
  if (!aovs.empty() && (wavefront || device != "cpu"))
    fail("aov: the diagnostics are measured by the megakernel; leave out wavefront and device");
  if (spp < 1 || spp > kMaxSpp) fail("spp: {} is not in [1, {}]", spp, kMaxSpp);
  if (time && !(*time > 0 && *time <= kMaxSeconds))
    fail("time: {} seconds is not in (0, {}] (None: no limit)", *time, kMaxSeconds);
  if (max_depth < 1) fail("max_depth: {} is not at least 1", max_depth);
  if (pass_spp < 1 || pass_spp > kMaxPassSpp)
    fail("pass_spp: {} is not in [1, {}]", pass_spp, kMaxPassSpp);
  if (max_pass_spp < 1 || max_pass_spp > kMaxSpp)
    fail("max_pass_spp: {} is not in [1, {}]", max_pass_spp, kMaxSpp);
  if (threads < 0 || threads > kMaxThreads)
    fail("threads: {} is not in [0, {}] (0: all cores)", threads, kMaxThreads);
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    fail("progress: expected a callable or None");
  SessionSettings settings = settings_with(scene, params);
  settings.integrator = integrator;
  settings.max_depth = max_depth;
  settings.wavefront = wavefront;
  settings.device = device;
  const std::string resolution = resolution_arg(res);
  if (!resolution.empty()) settings.resolution = resolution;

  // The lock is taken without the GIL: a render holding it takes the GIL between passes.
  std::unique_lock<std::mutex> lock(scene.mutex, std::defer_lock);
  {
    py::gil_scoped_release release;
    lock.lock();
  }
  const std::shared_ptr<RenderSession> session = session_for(scene, settings);
  const std::shared_ptr<LightSampler> sampler = named_sampler(*session, sampler_spec);

  RenderSettings rs;
  rs.spp = int(spp);
  rs.time_limit = time.value_or(0);
  rs.seed = seed;
  rs.pass_spp = pass_spp;
  rs.max_pass_spp = int(max_pass_spp);
  Film film(session->scene().width, session->scene().height);
  if (!aovs.empty()) film.track_camera_vertex();
  PassWatcher watch(progress);
  RenderProgress p;
  {
    ThreadLimit limit(threads);
    run_watched(watch, [&] {
      p = session->render(*sampler, film, rs, "render", false, &watch.cancel,
                          [&](const RenderProgress& pr, const Film&) { watch(pr); });
    });
  }
  watch.rethrow();

  PyRender r;
  r.image = image_to_array(film.resolve());
  r.counts = numpy_of(film.counts(), {py::ssize_t(film.height()), py::ssize_t(film.width())});
  r.state = state_object({session, sampler});
  if (!aovs.empty())
    for (auto& [name, values] : resolve_aovs(film, *sampler, aovs))
      r.aov[py::str(name.substr(4))] =  // (without the channels' "aov.")
          numpy_of(std::move(values), {py::ssize_t(film.height()), py::ssize_t(film.width())});
  r.spp = p.spp_done;
  r.seconds = p.seconds;
  r.interrupted = watch.interrupted || p.cancelled;
  const Scene& sc = session->scene();
  r.stats["scene"] = settings.scene;
  r.stats["resolution"] = py::make_tuple(sc.width, sc.height);
  r.stats["integrator"] = integrator;
  r.stats["max_depth"] = session->integrator().max_depth;
  r.stats["renderer"] = session->renderer_name();
  r.stats["sampler"] = to_python(sampler->describe());
  r.stats["spp"] = p.spp_done;
  r.stats["passes"] = p.passes;
  r.stats["seconds"] = p.seconds;
  r.stats["samples"] = p.samples;
  r.stats["samples_per_second"] = p.seconds > 0 ? p.samples / p.seconds : 0.0;
  py::dict rays;
  rays["camera"] = p.rays.camera;
  rays["bounce"] = p.rays.bounce;
  rays["shadow"] = p.rays.shadow;
  rays["total"] = p.rays.total();
  r.stats["rays"] = rays;
  r.stats["lights"] = sc.lights.size();
  r.stats["triangles"] = sc.mesh.triangle_count();
  r.stats["threads"] = threads > 0 ? threads : hardware_threads();
  r.stats["seed"] = seed;
  r.stats["interrupted"] = r.interrupted;
  r.stats["out_of_time"] = p.out_of_time;
  r.stats["nonfinite_samples"] = p.nonfinite;
  return r;
}

py::dict py_error(const py::handle& image, const py::handle& reference,
                  const py::handle& reference_variance) {
  const Image img = image_from_array(image, "img"), ref = image_from_array(reference, "ref");
  check_measured_pixels(img, "img", MeasuredRole::image);
  check_measured_pixels(ref, "ref", MeasuredRole::reference);
  if (img.width() != ref.width() || img.height() != ref.height())
    fail("error: img is {}x{} and ref is {}x{}", img.width(), img.height(), ref.width(),
         ref.height());
  Image var;
  const bool has_var = !reference_variance.is_none();
  if (has_var) {
    var = image_from_array(reference_variance, "reference_variance");
    check_measured_pixels(var, "reference_variance", MeasuredRole::reference_variance);
    if (var.width() != ref.width() || var.height() != ref.height())
      fail("error: reference_variance is {}x{}, ref {}x{}", var.width(), var.height(), ref.width(),
           ref.height());
  }
  const ErrorMetrics m = error_metrics(img, ref, has_var ? &var : nullptr);
  py::dict d;
  for (const char* name : kMetricNames) d[name] = metric_by_name(m, name);
  d["reference_noise_subtracted"] = has_var;
  return d;
}

}  // namespace

PYBIND11_MODULE(rll, m) {
  m.doc() =
      "rll, a path tracer with learnt light sampling: load scenes, render them with any light "
      "sampler into numpy arrays, measure images against references, read and write EXR files.";
  py::register_exception<Error>(m, "Error", PyExc_RuntimeError);
  bind_state(m);

  m.def(
      "scenes",
      [] {
        py::dict d;
        for (const auto& s : builtin_scenes()) d[py::str(s.name)] = s.description;
        return d;
      },
      "The built-in scenes, name -> description (load them as 'builtin:NAME').");
  m.def("samplers", &light_sampler_names, "The light sampler names render() takes.");

  py::class_<PyScene, std::shared_ptr<PyScene>>(
      m, "Scene", "A loaded scene with its light tree and ray-tracing structure (rll.load).")
      .def_property_readonly(
          "source", [](const PyScene& s) { return s.settings.scene; },
          "The file or builtin:NAME it was loaded from.")
      .def_property_readonly(
          "lights", [](const PyScene& s) { return s.scene().lights.size(); },
          "Number of lights (each emissive triangle is one).")
      .def_property_readonly(
          "triangles", [](const PyScene& s) { return s.scene().mesh.triangle_count(); },
          "Number of triangles (the sky dome's included).")
      .def_property_readonly(
          "bounds",
          [](const PyScene& s) {
            const Bounds3& b = s.scene().bounds;
            return py::make_tuple(py::make_tuple(b.lo.x, b.lo.y, b.lo.z),
                                  py::make_tuple(b.hi.x, b.hi.y, b.hi.z));
          },
          "((xmin, ymin, zmin), (xmax, ymax, zmax)) of the geometry, the sky dome left out.")
      .def_property_readonly(
          "resolution",
          [](const PyScene& s) { return py::make_tuple(s.scene().width, s.scene().height); },
          "(width, height) of the film.")
      .def("__repr__", [](const PyScene& s) {
        return "<rll.Scene '" + s.settings.scene + "': " + std::to_string(s.scene().lights.size()) +
               " lights, " + std::to_string(s.scene().mesh.triangle_count()) + " triangles, " +
               std::to_string(s.scene().width) + "x" + std::to_string(s.scene().height) + ">";
      });

  py::class_<PyRender>(m, "Render", "The result of rll.render.")
      .def_readonly("image", &PyRender::image,
                    "The mean radiance per pixel, float32 array of shape (height, width, 3).")
      .def_readonly("spp", &PyRender::spp, "Samples per pixel every pixel has.")
      .def_readonly("seconds", &PyRender::seconds,
                    "Render time (the progress callback's time left out).")
      .def_readonly("interrupted", &PyRender::interrupted,
                    "True when Ctrl-C (KeyboardInterrupt) stopped the render early.")
      .def_readonly("stats", &PyRender::stats,
                    "Statistics as `rll render --stats` writes them: rays, samples, sampler...")
      .def_readonly("counts", &PyRender::counts,
                    "Samples behind each pixel, uint32 array of shape (height, width) (the "
                    "`count` channel of the CLI's EXR files).")
      .def_readonly("aov", &PyRender::aov,
                    "The diagnostics asked for with aov=, name -> float32 array (height, width): "
                    "cell (id, -1: none), probability, entropy, visible, rewards (NaN where a "
                    "pixel has nothing to measure).")
      .def_readonly("state", &PyRender::state,
                    "The learnt state (rll.State) of rll, fermat or the oracle after the render; "
                    "None for samplers that learn nothing.")
      .def("__repr__", [](const PyRender& r) {
        return "<rll.Render " + std::to_string(r.image.shape(1)) + "x" +
               std::to_string(r.image.shape(0)) + ", " + std::to_string(r.spp) + " spp>";
      });

  m.def("load", &py_load, py::arg("path"), py::arg("res") = py::none(),
        "Loads a scene file (.pbrt, .gltf/.glb, .obj, .ply, .json) or 'builtin:NAME', at\n"
        "`res` ('WIDTHxHEIGHT' or (width, height); None: the scene's own). Raises rll.Error\n"
        "with rll's message when the scene cannot be read.");
  m.def("render", &py_render, py::arg("scene"), py::arg("sampler") = "rll",
        py::arg("integrator") = "path", py::arg("max_depth") = 5, py::arg("spp") = 16,
        py::arg("time") = py::none(), py::arg("res") = py::none(), py::arg("seed") = 1,
        py::arg("params") = py::dict(), py::arg("threads") = 0, py::arg("progress") = py::none(),
        py::arg("aov") = py::none(), py::arg("wavefront") = false, py::arg("device") = "cpu",
        py::arg("pass_spp") = 1, py::arg("max_pass_spp") = 8,
        "Renders `scene` with a light sampler (see samplers()) as `rll render` does with the\n"
        "same settings, to the same image: `spp` samples per pixel, or fewer when `time`\n"
        "seconds run out; `max_depth` bounds the path length (`--max-depth`); `params` are `--set` "
        "parameters (key: value); `threads` 0 uses every\n"
        "core. `progress(dict)` is called after every pass (passes, spp, spp_target, seconds,\n"
        "samples). The GIL is released while rendering; Ctrl-C stops the render within\n"
        "milliseconds, inside a pass too, and returns what it has (Render.interrupted is then\n"
        "True; Render.counts has each pixel's samples, Render.spp the fewest). `aov`: per-pixel diagnostics at the\n"
        "camera vertex, names as `rll render --aov` takes them (a list or 'a,b'; aov_names()),\n"
        "returned in Render.aov; the image is the same with or without. `wavefront` and\n"
        "`device` ('cpu' or 'cuda') as `--wavefront` and `--device`; `pass_spp` and\n"
        "`max_pass_spp` as `--pass-spp` and `--max-pass-spp` (the first passes' size, the\n"
        "largest pass).");
  m.def("error", &py_error, py::arg("img"), py::arg("ref"),
        py::arg("reference_variance") = py::none(),
        "Errors of an HxWx3 image against a reference as `rll error` measures them: a dict of\n"
        "relmse, trimmed_relmse, mrse and mse; with `reference_variance` (per pixel and\n"
        "channel) the reference's own noise is subtracted.");
  m.def(
      "read_exr",
      [](const py::object& path, bool metadata) -> py::object {
        const std::string p = fspath(path);
        ExrFile f;
        {
          py::gil_scoped_release release;
          f = read_exr_file(p);
        }
        const int w = f.image.width(), h = f.image.height();
        py::array image = image_to_array(std::move(f.image));
        if (!metadata) return image;
        py::dict info, attributes;
        for (const auto& [k, v] : f.attributes) attributes[py::str(k)] = v;
        info["attributes"] = attributes;
        info["count"] = f.counts.empty() ? py::object(py::none())
                                         : py::object(numpy_of(std::move(f.counts), {h, w}));
        py::dict channels;
        for (auto& [name, values] : f.channels)
          channels[py::str(name)] = numpy_of(std::move(values), {h, w});
        info["channels"] = channels;
        const std::string* share = f.attribute(kShareAttribute);
        info["share"] = share ? py::module_::import("json").attr("loads")(*share) : py::none();
        return py::make_tuple(image, info);
      },
      py::arg("path"), py::arg("metadata") = false,
      "Reads the R, G, B channels of an OpenEXR file as a float32 HxWx3 array. With\n"
      "`metadata`, returns (image, info): info['count'] the samples behind each pixel (uint32\n"
      "HxW, the `count` channel `rll render` writes; None where the file has none),\n"
      "info['attributes'] the header's string attributes, info['channels'] its other float\n"
      "channels (name -> HxW; `rll render --aov` writes aov.NAME), info['share'] the `rll.share` "
      "header\n"
      "(the settings and share a render was made with, parsed from JSON; None if absent).");
  m.def(
      "write_exr",
      [](const py::object& path, const py::handle& image, const py::object& count,
         const py::dict& attributes, const py::object& share) {
        ExrFile f;
        f.image = image_from_array(image, "image");
        if (!count.is_none()) {
          auto c = py::array_t<uint32_t, py::array::c_style | py::array::forcecast>::ensure(count);
          if (!c || c.ndim() != 2 || c.shape(0) != f.image.height() ||
              c.shape(1) != f.image.width())
            fail("count: expected an HxW array of sample counts ({}x{}), as the image",
                 f.image.height(), f.image.width());
          f.counts.assign(c.data(), c.data() + c.size());
        }
        for (const auto& [k, v] : attributes) {
          const std::string key = py::str(k).cast<std::string>();
          if (!py::isinstance<py::str>(v)) fail("attributes: the value of '{}' is not a str", key);
          f.attributes.emplace_back(key, v.cast<std::string>());
        }
        if (!share.is_none()) {
          if (f.attribute(kShareAttribute)) fail("share: also given in attributes");
          f.attributes.emplace_back(
              kShareAttribute,
              py::module_::import("json").attr("dumps")(share).cast<std::string>());
        }
        const std::string p = fspath(path);
        py::gil_scoped_release release;
        write_exr(p, f);
      },
      py::arg("path"), py::arg("image"), py::arg("count") = py::none(),
      py::arg("attributes") = py::dict(), py::arg("share") = py::none(),
      "Writes an HxWx3 array as a 32-bit float RGB OpenEXR file (atomically); with `count`\n"
      "(HxW sample counts, e.g. Render.counts) the `count` channel, `attributes` (str -> str) as\n"
      "header attributes and `share` (a dict, stored as JSON) as the `rll.share` header that\n"
      "`rll merge` reads.");
  m.def(
      "aov_names",
      [] {
        py::dict d;
        for (const auto& a : aov_list()) d[py::str(a.name)] = a.meaning;
        return d;
      },
      "The per-pixel diagnostics render(aov=...) and `rll render --aov` know, name -> meaning.");
  m.def(
      "cell_colours",
      [](const py::handle& cells) {
        auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(cells);
        if (!a || a.ndim() != 2)
          fail("cells: expected an HxW array of cell ids (Render.aov['cell'])");
        Image image(int(a.shape(1)), int(a.shape(0)));
        for (size_t i = 0; i < image.pixel_count(); ++i) image[i] = cell_colour(a.data()[i]);
        return image_to_array(std::move(image));
      },
      py::arg("cells"),
      "A false colour per cell id of an HxW cell image (Render.aov['cell']): HxWx3 float32,\n"
      "neighbouring ids in unrelated colours, black where there is no cell (-1).");
  bind_measure(m);
}
