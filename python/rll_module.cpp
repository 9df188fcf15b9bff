// The Python module `rll`: loads scenes, renders them with any light sampler into numpy arrays,
// measures images against references and reads and writes EXR files, over the library (the
// session and evaluation layers), not the command line.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/core/parallel.h"
#include "rll/eval/metrics.h"
#include "rll/lights/light_sampler.h"
#include "rll/render/film.h"
#include "rll/render/render.h"
#include "rll/scene/builtin.h"
#include "rll/session/session.h"

namespace py = pybind11;
using namespace rll;

namespace {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "images are handed to numpy as float triples");

// The limits of the command line's flags (apps/commands.h), so that Python takes what `rll render`
// takes.
constexpr long long kMaxSpp = (1 << 30) - 1;
constexpr int kMaxThreads = 4096;
constexpr double kMaxSeconds = 1e7;

// A path argument as str or os.PathLike.
std::string fspath(const py::handle& path) {
  return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}

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

// The image as a float32 HxWx3 array that owns it (no copy).
py::array to_array(Image image) {
  auto* owned = new Image(std::move(image));
  py::capsule free_image(owned, [](void* p) { delete static_cast<Image*>(p); });
  const auto h = py::ssize_t(owned->height()), w = py::ssize_t(owned->width());
  const auto f = py::ssize_t(sizeof(float));
  return py::array_t<float>({h, w, py::ssize_t(3)}, {w * 3 * f, 3 * f, f},
                            reinterpret_cast<const float*>(owned->pixels().data()), free_image);
}

// An HxWx3 array (any real dtype, converted to float32) as an Image; `name` is for messages.
Image from_array(const py::handle& obj, const char* name) {
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

// A parameter value as `--set key=value` takes it (Python's True is "true").
std::string param_value(const py::handle& v) {
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  return py::str(v).cast<std::string>();
}

// A scene loaded once, with the session that renders it with the default integrator; renders
// with other settings (integrator, params, res) load it again into a session of their own.
struct PyScene {
  SessionSettings settings;
  std::shared_ptr<RenderSession> session;
  std::mutex mutex;  // one render at a time: a session's parameter bookkeeping is not shared

  const Scene& scene() const { return session->scene(); }
};

std::shared_ptr<RenderSession> make_session(const SessionSettings& s) {
  py::gil_scoped_release release;
  return std::make_shared<RenderSession>(s);
}

std::shared_ptr<PyScene> py_load(const py::object& path, const py::object& res) {
  auto s = std::make_shared<PyScene>();
  s->settings.scene = fspath(path);
  s->settings.resolution = resolution_arg(res);
  s->session = make_session(s->settings);
  return s;
}

struct PyRender {
  py::array image;
  int spp = 0;
  double seconds = 0;
  bool interrupted = false;
  py::dict stats;
};

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

PyRender py_render(PyScene& scene, const std::string& sampler_spec, const std::string& integrator,
                   int max_depth, long long spp, std::optional<double> time, const py::object& res,
                   uint64_t seed, const py::dict& params, int threads, const py::object& progress) {
  if (spp < 1 || spp > kMaxSpp) fail("spp: {} is not in [1, {}]", spp, kMaxSpp);
  if (time && !(*time > 0 && *time <= kMaxSeconds))
    fail("time: {} seconds is not in (0, {}] (None: no limit)", *time, kMaxSeconds);
  if (max_depth < 1) fail("max_depth: {} is not at least 1", max_depth);
  if (threads < 0 || threads > kMaxThreads)
    fail("threads: {} is not in [0, {}] (0: all cores)", threads, kMaxThreads);
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    fail("progress: expected a callable or None");
  SessionSettings settings = scene.settings;
  settings.integrator = integrator;
  settings.max_depth = max_depth;
  const std::string resolution = resolution_arg(res);
  if (!resolution.empty()) settings.resolution = resolution;
  for (const auto& [k, v] : params)
    settings.set.push_back(py::str(k).cast<std::string>() + "=" + param_value(v));
  Params::parse(settings.set);  // a malformed key fails before the scene is loaded again

  // The lock is taken without the GIL: a render holding it takes the GIL between passes.
  std::unique_lock<std::mutex> lock(scene.mutex, std::defer_lock);
  {
    py::gil_scoped_release release;
    lock.lock();
  }
  const bool own = settings.integrator != scene.settings.integrator ||
                   settings.max_depth != scene.settings.max_depth ||
                   settings.resolution != scene.settings.resolution || !settings.set.empty();
  std::shared_ptr<RenderSession> session = own ? make_session(settings) : scene.session;
  std::unique_ptr<LightSampler> sampler;
  try {
    sampler = session->make_sampler(sampler_spec);
    session->check_params_used();
  } catch (const Error& e) {
    const std::string msg = e.what();
    if (msg.rfind("--set: ", 0) == 0) throw Error("params: " + msg.substr(7));
    throw Error("sampler: " + msg);
  }

  RenderSettings rs;
  rs.spp = int(spp);
  rs.time_limit = time.value_or(0);
  rs.seed = seed;
  Film film(session->scene().width, session->scene().height);
  std::atomic<bool> cancel{false};
  bool interrupted = false;
  std::exception_ptr callback_error;
  // Between passes, on this thread: Ctrl-C (Python's SIGINT handler raising KeyboardInterrupt)
  // cancels the render as SIGINT cancels `rll render`; the progress callback runs with the GIL.
  auto after_pass = [&](const RenderProgress& p, const Film&) {
    py::gil_scoped_acquire gil;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (!progress.is_none()) progress(progress_dict(p));
    } catch (py::error_already_set& e) {
      if (e.matches(PyExc_KeyboardInterrupt))
        interrupted = true;
      else
        callback_error = std::current_exception();
      cancel = true;
    }
  };
  RenderProgress p;
  {
    ThreadLimit limit(threads);
    py::gil_scoped_release release;
    p = session->render(*sampler, film, rs, "render", false, &cancel, after_pass);
  }
  if (callback_error) std::rethrow_exception(callback_error);

  PyRender r;
  r.image = to_array(film.resolve());
  r.spp = p.spp_done;
  r.seconds = p.seconds;
  r.interrupted = interrupted || p.cancelled;
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
  const Image img = from_array(image, "img"), ref = from_array(reference, "ref");
  check_measured_pixels(img, "img", MeasuredRole::image);
  check_measured_pixels(ref, "ref", MeasuredRole::reference);
  if (img.width() != ref.width() || img.height() != ref.height())
    fail("error: img is {}x{} and ref is {}x{}", img.width(), img.height(), ref.width(),
         ref.height());
  Image var;
  const bool has_var = !reference_variance.is_none();
  if (has_var) {
    var = from_array(reference_variance, "reference_variance");
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
        "Renders `scene` with a light sampler (see samplers()) as `rll render` does with the\n"
        "same settings, to the same image: `spp` samples per pixel, or fewer when `time`\n"
        "seconds run out; `max_depth` bounds the path length (`--max-depth`); `params` are `--set` "
        "parameters (key: value); `threads` 0 uses every\n"
        "core. `progress(dict)` is called after every pass (passes, spp, spp_target, seconds,\n"
        "samples). The GIL is released while rendering; Ctrl-C stops the render and returns\n"
        "what it has (Render.interrupted is then True).");
  m.def("error", &py_error, py::arg("img"), py::arg("ref"),
        py::arg("reference_variance") = py::none(),
        "Errors of an HxWx3 image against a reference as `rll error` measures them: a dict of\n"
        "relmse, trimmed_relmse, mrse and mse; with `reference_variance` (per pixel and\n"
        "channel) the reference's own noise is subtracted.");
  m.def(
      "read_exr",
      [](const py::object& path) {
        const std::string p = fspath(path);
        Image image;
        {
          py::gil_scoped_release release;
          image = read_exr_file(p).image;
        }
        return to_array(std::move(image));
      },
      py::arg("path"), "Reads the R, G, B channels of an OpenEXR file as a float32 HxWx3 array.");
  m.def(
      "write_exr",
      [](const py::object& path, const py::handle& image) {
        ExrFile f;
        f.image = from_array(image, "image");
        const std::string p = fspath(path);
        py::gil_scoped_release release;
        write_exr(p, f);
      },
      py::arg("path"), py::arg("image"),
      "Writes an HxWx3 array as a 32-bit float RGB OpenEXR file (atomically).");
}
