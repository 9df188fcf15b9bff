// The Python module `rll`: loads scenes, renders them with any light sampler into numpy arrays,
// measures images against references and reads and writes EXR files, over the library (the
// session and evaluation layers), not the command line.
#include <pybind11/stl.h>

#include <dlfcn.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "interpreter.h"
#include "module.h"
#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/core/memory_budget.h"
#include "rll/core/parallel.h"
#include "rll/eval/metrics.h"
#include "rll/lights/light_sampler.h"
#include "rll/render/aov.h"
#include "rll/render/film.h"
#include "rll/render/psf.h"
#include "rll/render/render.h"
#include "rll/render/share.h"
#include "rll/scene/builtin.h"
#include "rll/session/session.h"

using namespace rll;
using namespace rll::python;

namespace rll::python {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "images are handed to numpy as float triples");

std::string type_name_of(const py::handle& obj) {
  if (obj.is_none()) return "None";
  const py::handle type = py::type::handle_of(obj);
  const std::string module = py::str(type.attr("__module__")),
                    name = py::str(type.attr("__qualname__"));
  return module == "builtins" ? name : module + "." + name;
}

std::string short_repr(const py::handle& obj, size_t max_chars) {
  std::string r;
  try {
    r = py::repr(obj).cast<std::string>();
  } catch (const py::error_already_set&) {
    return "<" + type_name_of(obj) + ">";
  }
  if (r.size() > max_chars) r = r.substr(0, max_chars) + "...";
  return r;
}

py::str path_to_python(const std::string& path) {
  return py::module_::import("os").attr("fsdecode")(py::bytes(path));
}

void Call::type_error(const char* arg, const std::string& expected, const py::handle& got) const {
  throw ArgumentTypeError(
      fmt::format("{}(): argument '{}' must be {}, not {}", fn, arg, expected, type_name_of(got)));
}

void Call::item_type_error(const char* arg, const std::string& expected,
                           const py::handle& item) const {
  throw ArgumentTypeError(fmt::format("{}(): argument '{}' must be {}, not one holding {}", fn, arg,
                                      expected, type_name_of(item)));
}

void Call::value_error(const char* arg, const std::string& what) const {
  throw ArgumentValueError(fmt::format("{}(): argument '{}': {}", fn, arg, what));
}

std::shared_ptr<PyScene> Call::scene(const Arg<PyScene>& a, const char* arg) const {
  if (!py::isinstance<PyScene>(a.obj)) type_error(arg, "an rll.Scene (rll.load(...))", a.obj);
  return a.obj.cast<std::shared_ptr<PyScene>>();
}

std::string Call::path(const py::handle& obj, const char* arg) const {
  const bool path_like =
      PyUnicode_Check(obj.ptr()) || PyBytes_Check(obj.ptr()) || py::hasattr(obj, "__fspath__");
  if (!path_like) type_error(arg, "a path (str, bytes or os.PathLike)", obj);
  py::object encoded;
  try {
    encoded = py::module_::import("os").attr("fsencode")(obj);
  } catch (const py::error_already_set& e) {  // a __fspath__ that returns neither str nor bytes
    if (!e.matches(PyExc_TypeError)) throw;
    type_error(arg, "a path (str, bytes or os.PathLike)", obj);
  }
  std::string p = encoded.cast<std::string>();
  if (const size_t nul = p.find('\0'); nul != std::string::npos)
    value_error(arg, fmt::format("{} holds a NUL byte (at byte {}), which no file name can hold "
                                 "(the system would read the name only up to it)",
                                 short_repr(obj), nul));
  return p;
}

std::vector<std::string> Call::params(const Arg<py::dict>& a, const char* arg) const {
  std::vector<std::string> set;
  for (const auto& [k, v] : get(a, arg)) {
    if (!py::isinstance<py::str>(k)) item_type_error(arg, "a dict with str keys", k);
    const std::string key = text(k, arg);
    if (v.is_none())
      value_error(
          arg, fmt::format("the value of '{}' is None: give a value, or leave the key out", key));
    const std::string value =
        py::isinstance<py::bool_>(v) ? (v.cast<bool>() ? "true" : "false") : text(py::str(v), arg);
    set.push_back(key + "=" + value);
  }
  return set;
}

std::string Call::text(const py::handle& str, const char* arg) const {
  py::ssize_t size = 0;
  const char* utf8 = PyUnicode_AsUTF8AndSize(str.ptr(), &size);
  if (!utf8) {
    PyErr_Clear();
    value_error(arg, fmt::format("{} holds a character that UTF-8 cannot encode (a lone "
                                 "surrogate)",
                                 short_repr(str)));
  }
  std::string s(utf8, size_t(size));
  if (const size_t nul = s.find('\0'); nul != std::string::npos)
    value_error(arg, fmt::format("{} holds a NUL character (at {})", short_repr(str), nul));
  return s;
}

py::object Call::callback(const Arg<Callback>& a, const char* arg) const {
  if (!a.obj.is_none() && !PyCallable_Check(a.obj.ptr()))
    type_error(arg, "a callable or None", a.obj);
  return a.obj;
}

std::string Call::resolution(const Arg<Resolution>& a, const char* arg) const {
  const py::object& res = a.obj;
  const char* expected = "None, 'WIDTHxHEIGHT' or (width, height)";
  if (res.is_none()) return "";
  if (py::isinstance<py::str>(res)) return text(res, arg);
  if (!py::isinstance<py::sequence>(res) || py::isinstance<py::bytes>(res))
    type_error(arg, expected, res);
  if (py::len(res) != 2)
    value_error(arg, fmt::format("expected {}, got {}", expected, short_repr(res)));
  std::string wh;
  for (const auto& side : res) {
    if (!PyIndex_Check(side.ptr())) item_type_error(arg, "(width, height), two ints", side);
    wh += (wh.empty() ? "" : "x") +
          py::str(py::int_(py::reinterpret_borrow<py::object>(side))).cast<std::string>();
  }
  return wh;  // parsed, and its range checked, as --res is
}

std::string Call::name_list(const Arg<NameList>& a, const char* arg) const {
  const py::object& names = a.obj;
  if (names.is_none()) return "";
  if (py::isinstance<py::str>(names)) return text(names, arg);
  if (!py::isinstance<py::sequence>(names) || py::isinstance<py::bytes>(names))
    type_error(arg, "None, 'a,b' or a sequence of str", names);
  std::string list;
  for (const auto& name : names) {
    if (!py::isinstance<py::str>(name)) item_type_error(arg, "a sequence of str", name);
    list += (list.empty() ? "" : ",") + text(name, arg);
  }
  return list;
}

std::optional<std::array<float, 3>> Call::point(const Arg<Point3>& a, const char* arg) const {
  const py::object& p = a.obj;
  if (p.is_none()) return std::nullopt;
  // The length first: a sequence of a billion numbers is not converted to find it too long.
  if (!py::isinstance<py::sequence>(p) || py::isinstance<py::str>(p) ||
      py::isinstance<py::bytes>(p))
    type_error(arg, "three numbers or None", p);
  if (py::len(p) != 3) value_error(arg, fmt::format("expected 3 coordinates, got {}", py::len(p)));
  std::array<float, 3> v{};
  for (size_t i = 0; i < 3; ++i) {
    const py::object x = p[py::int_(i)];
    if (!PyIndex_Check(x.ptr()) && !py::hasattr(x, "__float__"))
      item_type_error(arg, "three numbers", x);
    v[i] = float(x.cast<double>());
  }
  return v;
}

void Call::check_image_size(const char* arg, py::ssize_t height, py::ssize_t width,
                            size_t bytes_per_pixel) const {
  if (height > kMaxImageSide || width > kMaxImageSide ||
      size_t(height) * size_t(width) > kMaxImagePixels)
    value_error(arg, fmt::format("{}x{} is larger than rll's image limit ({} pixels a side, {} "
                                 "pixels in all)",
                                 width, height, kMaxImageSide, kMaxImagePixels));
  check_memory_budget(double(height) * double(width) * double(bytes_per_pixel),
                      fmt::format("{}(): argument '{}' ({}x{})", fn, arg, width, height));
}

py::array Call::real_array(const py::handle& obj, const char* arg, int ndim,
                           const char* shape_text) const {
  if (obj.is_none()) type_error(arg, fmt::format("an {} array", shape_text), obj);
  // No copy of an ndarray (a broadcast or strided view stays one); other objects are made into
  // an array, no larger than what they hold already.
  const py::array a = py::array::ensure(obj);  // null (the error cleared) where numpy cannot
  if (!a) type_error(arg, fmt::format("an {} array of numbers", shape_text), obj);
  const char kind = a.dtype().kind();
  if (kind != 'b' && kind != 'i' && kind != 'u' && kind != 'f')
    fail("{}: expected an {} array of numbers, got dtype {}", arg, shape_text,
         py::str(a.dtype()).cast<std::string>());
  if (a.ndim() != ndim)
    fail("{}: expected an {} array, got shape {}", arg, shape_text,
         py::str(a.attr("shape")).cast<std::string>());
  return a;
}

Image Call::image(const py::handle& obj, const char* arg) const {
  const py::array a = real_array(obj, arg, 3, "HxWx3");
  if (a.shape(2) != 3 || a.shape(0) < 1 || a.shape(1) < 1)
    fail("{}: expected an HxWx3 array, got shape {}", arg,
         py::str(a.attr("shape")).cast<std::string>());
  check_image_size(arg, a.shape(0), a.shape(1), sizeof(Rgb));
  Image image(int(a.shape(1)), int(a.shape(0)));
  // numpy copies (and casts, as forcecast did) straight into the image: one copy, not two.
  const auto h = py::ssize_t(image.height()), w = py::ssize_t(image.width());
  const auto f = py::ssize_t(sizeof(float));
  const py::capsule no_owner(image.pixels().data(), [](void*) {});
  py::array_t<float> into({h, w, py::ssize_t(3)}, {w * 3 * f, 3 * f, f},
                          reinterpret_cast<float*>(image.pixels().data()), no_owner);
  py::module_::import("numpy").attr("copyto")(into, a, py::arg("casting") = "unsafe");
  return image;
}

py::array image_to_array(Image image) {
  auto* owned = new Image(std::move(image));
  py::capsule free_image(owned, [](void* p) { delete static_cast<Image*>(p); });
  const auto h = py::ssize_t(owned->height()), w = py::ssize_t(owned->width());
  const auto f = py::ssize_t(sizeof(float));
  return py::array_t<float>({h, w, py::ssize_t(3)}, {w * 3 * f, 3 * f, f},
                            reinterpret_cast<const float*>(owned->pixels().data()), free_image);
}

}  // namespace rll::python

namespace {

// The limits of the command line's flags (apps/commands.h), so that Python takes what `rll render`
// takes.
constexpr long long kMaxSpp = (1 << 30) - 1;
constexpr int kMaxPassSpp = 1024;  // as `rll render --pass-spp`
constexpr int kMaxThreads = 4096;
constexpr double kMaxSeconds = 1e7;

std::shared_ptr<RenderSession> make_session(const SessionSettings& s) {
  py::gil_scoped_release release;
  return std::make_shared<RenderSession>(s);
}

}  // namespace

namespace rll::python {

SessionSettings settings_with(const PyScene& scene, const std::vector<std::string>& params) {
  SessionSettings settings = scene.settings;
  settings.set.insert(settings.set.end(), params.begin(), params.end());
  Params::parse(settings.set);  // a malformed key fails before the scene is loaded again
  return settings;
}

std::shared_ptr<RenderSession> session_for(PyScene& scene, const SessionSettings& settings) {
  const SessionSettings& own = scene.settings;
  const bool same = settings.integrator == own.integrator && settings.max_depth == own.max_depth &&
                    settings.resolution == own.resolution && settings.set == own.set &&
                    settings.wavefront == own.wavefront && settings.device == own.device &&
                    settings.filter == own.filter;
  return same ? scene.session : make_session(settings);
}

std::shared_ptr<LightSampler> named_sampler(const RenderSession& session, const std::string& spec) {
  try {
    py::gil_scoped_release release;  // a sampler may precompute (the oracle, ltc's tables)
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

std::shared_ptr<PyScene> py_load(const Arg<PathLike>& path, const Arg<Resolution>& res) {
  const Call c{"load"};
  auto s = std::make_shared<PyScene>();
  s->settings.scene = c.path(path, "path");
  s->settings.resolution = c.resolution(res, "res");
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
  // Bytes that are not UTF-8 (a path's) as U+FFFD rather than nlohmann's exception.
  return py::module_::import("json").attr("loads")(
      j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

py::object parse_json(const std::string& text, const std::string& where,
                      const std::string& what_to_do) {
  const py::module_ json = py::module_::import("json");
  try {
    return json.attr("loads")(py::bytes(text));
  } catch (py::error_already_set& e) {
    // json.JSONDecodeError (a ValueError) with the line and column; UnicodeDecodeError for
    // bytes that are not text.
    if (!e.matches(PyExc_ValueError)) throw;
    const py::object err = e.value();
    if (py::hasattr(err, "lineno"))
      fail("{} is not valid JSON (line {}, column {}: {}); {}", where,
           err.attr("lineno").cast<long long>(), err.attr("colno").cast<long long>(),
           py::str(err.attr("msg")).cast<std::string>(), what_to_do);
    fail("{} is not valid JSON ({}); {}", where, py::str(err).cast<std::string>(), what_to_do);
  }
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

void PassWatcher::rethrow_or_interrupt() const {
  rethrow();
  if (interrupted) {
    PyErr_SetNone(PyExc_KeyboardInterrupt);
    throw py::error_already_set();
  }
}

}  // namespace rll::python

namespace {

PyRender py_render(const Arg<PyScene>& scene_arg, const Arg<std::string>& sampler_arg,
                   const Arg<std::string>& integrator_arg, const Arg<int>& max_depth_arg,
                   const Arg<long long>& spp_arg, const Arg<std::optional<double>>& time_arg,
                   const Arg<Resolution>& res_arg, const Arg<uint64_t>& seed_arg,
                   const Arg<py::dict>& params_arg, const Arg<int>& threads_arg,
                   const Arg<Callback>& progress_arg, const Arg<NameList>& aov_arg,
                   const Arg<bool>& wavefront_arg, const Arg<std::string>& device_arg,
                   const Arg<long long>& pass_spp_arg, const Arg<long long>& max_pass_spp_arg,
                   const Arg<std::string>& filter_arg) {
  const Call c{"render"};
  const std::shared_ptr<PyScene> scene_ptr = c.scene(scene_arg, "scene");
  PyScene& scene = *scene_ptr;
  const std::string sampler_spec = c.get(sampler_arg, "sampler");
  const std::string integrator = c.get(integrator_arg, "integrator");
  const int max_depth = c.get(max_depth_arg, "max_depth");
  const long long spp = c.get(spp_arg, "spp");
  const std::optional<double> time = c.get(time_arg, "time");
  const std::string resolution = c.resolution(res_arg, "res");
  const uint64_t seed = c.get(seed_arg, "seed");
  const std::vector<std::string> params = c.params(params_arg, "params");
  const int threads = c.get(threads_arg, "threads");
  const py::object progress = c.callback(progress_arg, "progress");
  const std::string aov_list = c.name_list(aov_arg, "aov");
  const bool wavefront = c.get(wavefront_arg, "wavefront");
  const std::string device = c.get(device_arg, "device");
  const long long pass_spp = c.get(pass_spp_arg, "pass_spp");
  const long long max_pass_spp = c.get(max_pass_spp_arg, "max_pass_spp");
  const std::string filter = c.get(filter_arg, "filter");

  std::vector<Aov> aovs;
  if (!aov_arg.obj.is_none()) aovs = parse_aovs(aov_list, "aov");
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
  const std::vector<std::string>& filters = filter_names();
  if (std::find(filters.begin(), filters.end(), filter) == filters.end())
    fail("filter: '{}' is not one of none, psf", shown_text(filter));
  SessionSettings settings = settings_with(scene, params);
  settings.filter = filter;
  settings.integrator = integrator;
  settings.max_depth = max_depth;
  settings.wavefront = wavefront;
  settings.device = device;
  if (!resolution.empty()) settings.resolution = resolution;

  // The lock is taken without the GIL: a render holding it takes the GIL between passes.
  std::unique_lock<std::mutex> lock(scene.mutex, std::defer_lock);
  {
    py::gil_scoped_release release;
    lock.lock();
  }
  const std::shared_ptr<RenderSession> session = session_for(scene, settings);
  // The diagnostics of `aov` are kept beside the film: checked with it, as `rll render --aov`.
  if (!aovs.empty())
    session->check_film_memory(
        kRenderBytesPerPixel + kCameraVertexBytesPerPixel + 4.0 * double(aovs.size()),
        fmt::format("{}, and the aov diagnostics", kRenderPixelText));
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
  r.stats["scene"] = path_to_python(settings.scene);
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
  r.stats["filter"] = to_python(
      filter_json(session->integrator().psf, &p.filter, p.samples, session->psf_history_bytes()));
  return r;
}

py::dict py_error(const Arg<ArrayLike>& image, const Arg<ArrayLike>& reference,
                  const Arg<std::optional<ArrayLike>>& reference_variance) {
  const Call c{"error"};
  const Image img = c.image(image.obj, "img"), ref = c.image(reference.obj, "ref");
  check_measured_pixels(img, "img", MeasuredRole::image);
  check_measured_pixels(ref, "ref", MeasuredRole::reference);
  if (img.width() != ref.width() || img.height() != ref.height())
    fail("error: img is {}x{} and ref is {}x{}", img.width(), img.height(), ref.width(),
         ref.height());
  Image var;
  const bool has_var = !reference_variance.obj.is_none();
  if (has_var) {
    var = c.image(reference_variance.obj, "reference_variance");
    check_measured_pixels(var, "reference_variance", MeasuredRole::reference_variance);
    if (var.width() != ref.width() || var.height() != ref.height())
      fail("error: reference_variance is {}x{}, ref {}x{}", var.width(), var.height(), ref.width(),
           ref.height());
  }
  ErrorMetrics m;
  {
    py::gil_scoped_release release;
    m = error_metrics(img, ref, has_var ? &var : nullptr);
  }
  py::dict d;
  for (const char* name : kMetricNames) d[name] = metric_by_name(m, name);
  d["reference_noise_subtracted"] = has_var;
  return d;
}

// Text of a file (an EXR header's attribute, a channel's name) as str: bytes that are not UTF-8
// as U+FFFD rather than a UnicodeDecodeError.
py::str text_to_python(const std::string& text) {
  PyObject* s = PyUnicode_DecodeUTF8(text.data(), py::ssize_t(text.size()), "replace");
  if (!s) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(s);
}

py::object py_read_exr(const Arg<PathLike>& path_arg, const Arg<bool>& metadata_arg) {
  const Call c{"read_exr"};
  const std::string p = c.path(path_arg, "path");
  const bool metadata = c.get(metadata_arg, "metadata");
  ExrFile f;
  {
    py::gil_scoped_release release;
    f = read_exr_file(p);
  }
  const int w = f.image.width(), h = f.image.height();
  py::array image = image_to_array(std::move(f.image));
  if (!metadata) return image;
  py::dict info, attributes;
  for (const auto& [k, v] : f.attributes) attributes[text_to_python(k)] = text_to_python(v);
  info["attributes"] = attributes;
  info["count"] =
      f.counts.empty() ? py::object(py::none()) : py::object(numpy_of(std::move(f.counts), {h, w}));
  py::dict channels;
  for (auto& [name, values] : f.channels)
    channels[text_to_python(name)] = numpy_of(std::move(values), {h, w});
  info["channels"] = channels;
  const std::string* share = f.attribute(kShareAttribute);
  info["share"] = share ? parse_json(*share, fmt::format("{}: the {} header", p, kShareAttribute),
                                     "the file was damaged or written by another program; "
                                     "read_exr(path) without metadata reads its image")
                        : py::none();
  return py::make_tuple(image, info);
}

void py_write_exr(const Arg<PathLike>& path_arg, const Arg<ArrayLike>& image_arg,
                  const Arg<std::optional<ArrayLike>>& count_arg,
                  const Arg<py::dict>& attributes_arg, const Arg<JsonObject>& share_arg) {
  const Call c{"write_exr"};
  // The path first: a bad one is refused before an image is converted.
  const std::string p = c.path(path_arg, "path");
  const py::dict attributes = c.get(attributes_arg, "attributes");
  ExrFile f;
  f.image = c.image(image_arg.obj, "image");
  if (!count_arg.obj.is_none()) {
    const py::array a = c.real_array(count_arg.obj, "count", 2, "HxW");
    if (a.shape(0) != f.image.height() || a.shape(1) != f.image.width())
      fail("count: expected an HxW array of sample counts ({}x{}), as the image, got shape {}",
           f.image.height(), f.image.width(), py::str(a.attr("shape")).cast<std::string>());
    // Counts are whole numbers of samples in the channel's uint32: a negative, fractional or
    // larger value would be written as another number (forcecast wraps -1 to 4294967295).
    const py::module_ np = py::module_::import("numpy");
    const bool whole = a.dtype().kind() != 'f' ||
                       np.attr("all")(np.attr("equal")(a, np.attr("floor")(a))).cast<bool>();
    const double lo = np.attr("min")(a).cast<double>(), hi = np.attr("max")(a).cast<double>();
    if (!whole || !(lo >= 0) || !(hi <= 4294967295.0))
      fail(
          "count: the sample counts must be whole numbers in [0, 4294967295] (the count "
          "channel's uint32), found values in [{}, {}]{}",
          lo, hi, whole ? "" : " and fractions");
    auto counts = py::array_t<uint32_t, py::array::c_style | py::array::forcecast>::ensure(a);
    if (!counts) throw py::error_already_set();
    f.counts.assign(counts.data(), counts.data() + counts.size());
  }
  for (const auto& [k, v] : attributes) {
    if (!py::isinstance<py::str>(k)) c.item_type_error("attributes", "a dict of str -> str", k);
    const std::string key = c.text(k, "attributes");
    if (!py::isinstance<py::str>(v)) fail("attributes: the value of '{}' is not a str", key);
    f.attributes.emplace_back(key, c.text(v, "attributes"));
  }
  if (!share_arg.obj.is_none()) {
    const py::object& share = share_arg.obj;
    if (!py::isinstance<py::dict>(share)) c.type_error("share", "a dict or None", share);
    if (f.attribute(kShareAttribute)) fail("share: also given in attributes");
    std::string text;
    try {
      // JSON proper (no NaN or Infinity, which rll merge's parser refuses).
      text = py::module_::import("json")
                 .attr("dumps")(share, py::arg("allow_nan") = false)
                 .cast<std::string>();
    } catch (py::error_already_set& e) {
      if (!e.matches(PyExc_TypeError) && !e.matches(PyExc_ValueError)) throw;
      fail("share: cannot be stored as JSON ({}); give a dict of str, numbers, lists and dicts",
           py::str(e.value()).cast<std::string>());
    }
    f.attributes.emplace_back(kShareAttribute, text);
  }
  py::gil_scoped_release release;
  write_exr(p, f);
}

py::array py_cell_colours(const Arg<ArrayLike>& cells_arg) {
  const Call c{"cell_colours"};
  const py::array a = c.real_array(cells_arg.obj, "cells", 2, "HxW (Render.aov['cell'])");
  c.check_image_size("cells", a.shape(0), a.shape(1), sizeof(Rgb) + sizeof(float));
  const auto ids = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!ids) throw py::error_already_set();
  Image image(int(a.shape(1)), int(a.shape(0)));
  for (size_t i = 0; i < image.pixel_count(); ++i) image[i] = cell_colour(ids.data()[i]);
  return image_to_array(std::move(image));
}

// The folder this module was loaded from (for PYTHONPATH in messages; __file__ is set only
// after the module's init).
std::string module_folder() {
  Dl_info info{};
  if (!dladdr(reinterpret_cast<const void*>(&module_folder), &info) || !info.dli_fname)
    return "<the folder of rll's module>";
  return std::filesystem::path(info.dli_fname).parent_path().string();
}

// Refuses (ImportError) an interpreter of another Python installation than the one the module
// was built for (interpreter.h): pyenv's python3 first on PATH, say, of the same version loads
// the module but lacks Debian's numpy ("No module named numpy" at the first array) or has
// another one; and an interpreter of that installation that cannot import numpy (a venv
// without the system's packages). Either error says which interpreter to use.
void check_interpreter() {
  const py::module_ sys = py::module_::import("sys"), os = py::module_::import("os");
  const auto real = [&](const py::object& p) {
    return os.attr("path").attr("realpath")(p).cast<std::string>();
  };
  const std::string running = py::str(sys.attr("executable")).cast<std::string>();
  const std::string version = py::str(sys.attr("version")).cast<std::string>();
  const std::string this_one =
      fmt::format("{} (Python {})", running.empty() ? "this Python" : running,
                  version.substr(0, version.find(' ')));
  // (An empty prefix: the build could not ask the interpreter; nothing to compare with.)
  if (*kBuiltForBasePrefix && real(sys.attr("base_prefix")) != real(py::str(kBuiltForBasePrefix)))
    throw std::runtime_error(fmt::format(
        "rll was built for {} (Python {}, installed in {}), but this is {}, installed in {}, "
        "whose numpy and ABI are not the ones rll was built with: run PYTHONPATH={} {}, or "
        "build rll for this interpreter (cmake -DPython3_EXECUTABLE={})",
        kBuiltForExecutable, kBuiltForVersion, kBuiltForBasePrefix, this_one,
        py::str(sys.attr("base_prefix")).cast<std::string>(), module_folder(), kBuiltForExecutable,
        running));
  try {
    py::module_::import("numpy");
  } catch (py::error_already_set& e) {
    if (!e.matches(PyExc_ImportError)) throw;
    throw std::runtime_error(fmt::format(
        "rll needs numpy, which {} cannot import ({}): install numpy for it (a venv made with "
        "--system-site-packages sees Debian's python3-numpy), or run PYTHONPATH={} {}, which "
        "rll was built for",
        this_one, py::str(e.value()).cast<std::string>(), module_folder(), kBuiltForExecutable));
  }
}

}  // namespace

PYBIND11_MODULE(rll, m) {
  check_interpreter();
  m.doc() =
      "rll, a path tracer with learnt light sampling: load scenes, render them with any light "
      "sampler into numpy arrays, measure images against references, read and write EXR files.";
  const py::object error = py::register_exception<Error>(m, "Error", PyExc_RuntimeError);
  // Registered after rll.Error: pybind11 tries the last registered translator first.
  const py::tuple type_bases = py::make_tuple(error, py::handle(PyExc_TypeError));
  const py::tuple value_bases = py::make_tuple(error, py::handle(PyExc_ValueError));
  py::register_exception<ArgumentTypeError>(m, "ArgumentTypeError", type_bases).doc() =
      "An argument of the wrong type (None where an object is needed): a TypeError and "
      "an rll.Error.";
  py::register_exception<ArgumentValueError>(m, "ArgumentValueError", value_bases).doc() =
      "An argument that Python's own functions would refuse with a ValueError (a path "
      "holding a NUL byte, an int out of range): a ValueError and an rll.Error.";
  bind_state(m);

  m.def(
      "scenes",
      [] {
        py::dict d;
        for (const auto& s : builtin_scenes()) d[py::str(s.name)] = s.description;
        return d;
      },
      "The built-in scenes, name -> description (load them as 'builtin:NAME').");
  m.def("samplers", &sampler_names, "The sampler names render() takes (the light samplers and restir).");

  py::class_<PyScene, std::shared_ptr<PyScene>>(
      m, "Scene", "A loaded scene with its light tree and ray-tracing structure (rll.load).")
      .def_property_readonly(
          "source", [](const PyScene& s) { return path_to_python(s.settings.scene); },
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
        return py::str("<rll.Scene '{}': {} lights, {} triangles, {}x{}>")
            .format(path_to_python(s.settings.scene), s.scene().lights.size(),
                    s.scene().mesh.triangle_count(), s.scene().width, s.scene().height);
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
        py::arg("pass_spp") = 1, py::arg("max_pass_spp") = 8, py::arg("filter") = "none",
        "Renders `scene` with a light sampler (see samplers()) as `rll render` does with the\n"
        "same settings, to the same image: `spp` samples per pixel, or fewer when `time`\n"
        "seconds run out; `max_depth` bounds the path length (`--max-depth`); `params` are `--set` "
        "parameters (key: value); `threads` 0 uses every\n"
        "core. `progress(dict)` is called after every pass (passes, spp, spp_target, seconds,\n"
        "samples). The GIL is released while rendering; Ctrl-C stops the render within\n"
        "milliseconds, inside a pass too, and returns what it has (Render.interrupted is then\n"
        "True; Render.counts has each pixel's samples, Render.spp the fewest). `aov`: per-pixel "
        "diagnostics at the\n"
        "camera vertex, names as `rll render --aov` takes them (a list or 'a,b'; aov_names()),\n"
        "returned in Render.aov; the image is the same with or without. `wavefront` and\n"
        "`device` ('cpu' or 'cuda') as `--wavefront` and `--device`; `pass_spp` and\n"
        "`max_pass_spp` as `--pass-spp` and `--max-pass-spp` (the first passes' size, the\n"
        "largest pass). `filter`: 'none', or 'psf' as `--filter psf` (path-space filtering;\n"
        "its keys in `params` as psf.KEY; Render.stats['filter'] counts its cells and paths).");
  m.def("error", &py_error, py::arg("img"), py::arg("ref"),
        py::arg("reference_variance") = py::none(),
        "Errors of an HxWx3 image against a reference as `rll error` measures them: a dict of\n"
        "relmse, trimmed_relmse, mrse and mse; with `reference_variance` (per pixel and\n"
        "channel) the reference's own noise is subtracted.");
  m.def("read_exr", &py_read_exr, py::arg("path"), py::arg("metadata") = false,
        "Reads the R, G, B channels of an OpenEXR file as a float32 HxWx3 array. With\n"
        "`metadata`, returns (image, info): info['count'] the samples behind each pixel (uint32\n"
        "HxW, the `count` channel `rll render` writes; None where the file has none),\n"
        "info['attributes'] the header's string attributes, info['channels'] its other float\n"
        "channels (name -> HxW; `rll render --aov` writes aov.NAME), info['share'] the `rll.share` "
        "header\n"
        "(the settings and share a render was made with, parsed from JSON; None if absent).");
  m.def(
      "write_exr", &py_write_exr, py::arg("path"), py::arg("image"), py::arg("count") = py::none(),
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
  m.def("cell_colours", &py_cell_colours, py::arg("cells"),
        "A false colour per cell id of an HxW cell image (Render.aov['cell']): HxWx3 float32,\n"
        "neighbouring ids in unrelated colours, black where there is no cell (-1).");
  bind_measure(m);
}
