// What the Python module's source files share: argument conversions, numpy arrays that own
// their data, and the scene and render objects the functions take and return.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <array>
#include <atomic>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/lights/light_sampler.h"
#include "rll/session/session.h"

namespace rll::python {

namespace py = pybind11;

// A scene loaded once, with the session that renders it with the default integrator; renders
// with other settings (integrator, params, res) load it again into a session of their own.
struct PyScene {
  SessionSettings settings;
  std::shared_ptr<RenderSession> session;
  std::mutex mutex;  // one render at a time: a session's parameter bookkeeping is not shared

  const Scene& scene() const { return session->scene(); }
};

// Errors about an argument: a wrong type (None where an object is needed too) raises
// rll.ArgumentTypeError, a TypeError, and a wrong value that Python's own functions answer with
// a ValueError (a path holding a NUL byte, an int out of range) rll.ArgumentValueError; both are
// rll.Error as well, as every error of the module was before they existed.
struct ArgumentTypeError : Error {
  using Error::Error;
};
struct ArgumentValueError : Error {
  using Error::Error;
};

// An argument as the Python object it is, converted in the function (Call) rather than by
// pybind11: pybind11 made None a null pointer for a class argument (rll.load_state(path, None)
// crashed the interpreter) and answers other wrong types with "incompatible function arguments"
// or "Unable to cast Python instance", naming neither the argument nor what it takes.
// Signatures in docstrings show ArgName<T>::name.
template <typename T>
struct Arg {
  py::object obj;
};

// Arguments that take several kinds of object, for Arg<>.
struct PathLike {};       // str, bytes or os.PathLike
struct ArrayLike {};      // a numpy array or what numpy makes one of (nested lists)
struct Callback {};       // a callable or None
struct Resolution {};     // None, 'WIDTHxHEIGHT' or (width, height)
struct NameList {};       // None, 'a,b' or a sequence of str
struct Point3 {};         // None or three numbers
struct JsonObject {};     // None or a dict of JSON values
struct ReferenceLike {};  // None, an array or a path

template <typename T>
struct ArgName {
  static constexpr auto name = py::detail::make_caster<T>::name;
};
template <typename T>
struct ArgName<std::optional<T>> {
  static constexpr auto name =
      py::detail::const_name("Optional[") + ArgName<T>::name + py::detail::const_name("]");
};
#define RLL_PY_ARG_NAME(TYPE, TEXT)                            \
  template <>                                                  \
  struct ArgName<TYPE> {                                       \
    static constexpr auto name = py::detail::const_name(TEXT); \
  }
RLL_PY_ARG_NAME(PathLike, "Union[str, bytes, os.PathLike]");
RLL_PY_ARG_NAME(ArrayLike, "numpy.typing.ArrayLike");
RLL_PY_ARG_NAME(Callback, "Optional[Callable]");
RLL_PY_ARG_NAME(Resolution, "Union[None, str, Tuple[int, int]]");
RLL_PY_ARG_NAME(NameList, "Union[None, str, Sequence[str]]");
RLL_PY_ARG_NAME(Point3, "Optional[Sequence[float]]");
RLL_PY_ARG_NAME(JsonObject, "Optional[dict]");
RLL_PY_ARG_NAME(ReferenceLike, "Union[None, str, bytes, os.PathLike, numpy.typing.ArrayLike]");
#undef RLL_PY_ARG_NAME

// "None", or the type's name ("str", "numpy.ndarray"): what an argument was, for messages.
std::string type_name_of(const py::handle& obj);
// repr(obj), cut to `max_chars` (a long argument is not echoed whole).
std::string short_repr(const py::handle& obj, size_t max_chars = 80);
// The path a str or bytes names, for messages and results: os.fsdecode of its bytes.
py::str path_to_python(const std::string& path);

template <typename T>
struct IsOptional : std::false_type {};
template <typename T>
struct IsOptional<std::optional<T>> : std::true_type {};

// Converts the arguments of one call of the function `fn` ("render", "State.cut"), naming it and
// the argument in every error.
struct Call {
  const char* fn;

  // "render(): argument 'spp' must be an int, not str" as rll.ArgumentTypeError.
  [[noreturn]] void type_error(const char* arg, const std::string& expected,
                               const py::handle& got) const;
  // "render(): argument 'aov' must be a sequence of str, not one holding int".
  [[noreturn]] void item_type_error(const char* arg, const std::string& expected,
                                    const py::handle& item) const;
  [[noreturn]] void value_error(const char* arg, const std::string& what) const;

  // An int (any integral T, range-checked), float, bool, str, list of str or dict; optional<T>
  // takes None as nullopt. None is refused for the others.
  template <typename T>
  T get(const Arg<T>& a, const char* arg) const {
    return convert<T>(a.obj, arg);
  }
  // The scene (kept alive by the pointer).
  std::shared_ptr<PyScene> scene(const Arg<PyScene>& a, const char* arg) const;
  // The bytes of a path given as str (encoded as the file system's: os.fsencode), bytes or
  // os.PathLike, as Python's open() takes it; one holding a NUL byte is refused, since the
  // system would read it only up to that byte (write_exr("victim.exr\0.tmp.exr") wrote
  // victim.exr).
  std::string path(const py::handle& obj, const char* arg) const;
  std::string path(const Arg<PathLike>& a, const char* arg) const { return path(a.obj, arg); }
  // `--set` parameters as "key=value" from a dict of str keys and values that are not None (a
  // value as str() writes it; Python's True is "true").
  std::vector<std::string> params(const Arg<py::dict>& a, const char* arg) const;
  // A str as UTF-8; one that UTF-8 cannot encode (a lone surrogate) or that holds a NUL (which
  // would end the name where rll's messages and files read it) is refused.
  std::string text(const py::handle& str, const char* arg) const;
  // A callable, or None.
  py::object callback(const Arg<Callback>& a, const char* arg) const;
  // "WIDTHxHEIGHT" from None (empty: the scene's own), a str or a (width, height) pair.
  std::string resolution(const Arg<Resolution>& a, const char* arg) const;
  // A comma-separated list from None (empty), 'a,b' or a sequence of str.
  std::string name_list(const Arg<NameList>& a, const char* arg) const;
  // Three numbers, or nullopt for None.
  std::optional<std::array<float, 3>> point(const Arg<Point3>& a, const char* arg) const;

  // An HxWx3 array (any real dtype, converted to float32) as an Image. Its shape is checked
  // against rll's image limits and the memory budget before anything is copied: numpy's
  // conversion would materialise a broadcast view (np.broadcast_to of 20000x20000x3 takes a
  // few bytes) at its full size, gigabytes before the check.
  Image image(const py::handle& obj, const char* arg) const;
  // The numpy array of `obj` without a copy (nested lists made into one), with a real dtype
  // (bool, integer or float) and `ndim` dimensions; `shape_text` says which ("HxWx3").
  py::array real_array(const py::handle& obj, const char* arg, int ndim,
                       const char* shape_text) const;
  // Checks that an HxW image of `bytes_per_pixel` fits rll's image limits and the memory budget.
  void check_image_size(const char* arg, py::ssize_t height, py::ssize_t width,
                        size_t bytes_per_pixel) const;

 private:
  template <typename T>
  T convert(const py::object& obj, const char* arg) const;
  template <typename T>
  static std::string expected();
};

template <typename T>
std::string Call::expected() {
  if constexpr (std::is_same_v<T, bool>)
    return "a bool";
  else if constexpr (std::is_integral_v<T>)
    return "an int";
  else if constexpr (std::is_floating_point_v<T>)
    return "a float";
  else if constexpr (std::is_same_v<T, std::string>)
    return "a str";
  else if constexpr (std::is_same_v<T, std::vector<std::string>>)
    return "a list of str";
  else if constexpr (std::is_same_v<T, py::dict>)
    return "a dict";
  else
    static_assert(sizeof(T) == 0, "no conversion for this argument type");
}

template <typename T>
T Call::convert(const py::object& obj, const char* arg) const {
  if constexpr (IsOptional<T>::value) {
    if (obj.is_none()) return std::nullopt;
    return convert<typename T::value_type>(obj, arg);
  } else {
    if (obj.is_none()) type_error(arg, expected<T>(), obj);
    // pybind11 would take a str as a list of one-character str, and any object with __bool__
    // as a bool (None as False).
    if constexpr (std::is_same_v<T, std::vector<std::string>>) {
      if (py::isinstance<py::str>(obj) || py::isinstance<py::bytes>(obj) ||
          !py::isinstance<py::sequence>(obj))
        type_error(arg, expected<T>(), obj);
      std::vector<std::string> items;
      for (const auto& item : obj) {
        if (!py::isinstance<py::str>(item)) item_type_error(arg, expected<T>(), item);
        items.push_back(text(item, arg));
      }
      return items;
    }
    if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
      // An int out of T's range is a ValueError that says the range, not a wrong type.
      if (PyIndex_Check(obj.ptr())) {
        const auto v = py::reinterpret_steal<py::int_>(PyNumber_Index(obj.ptr()));
        if (!v) throw py::error_already_set();
        const py::int_ lo(std::numeric_limits<T>::min()), hi(std::numeric_limits<T>::max());
        if (v < lo || v > hi)
          value_error(arg, short_repr(obj) + " is not in [" +
                               std::to_string(std::numeric_limits<T>::min()) + ", " +
                               std::to_string(std::numeric_limits<T>::max()) + "]");
      }
    }
    if constexpr (std::is_same_v<T, std::string>)
      if (py::isinstance<py::str>(obj)) return text(obj, arg);
    // pybind11 would make a dict of any iterable of pairs.
    if constexpr (std::is_same_v<T, py::dict>) {
      if (!py::isinstance<py::dict>(obj)) type_error(arg, expected<T>(), obj);
      return py::reinterpret_borrow<py::dict>(obj);
    }
    try {
      return obj.cast<T>();
    } catch (const py::cast_error&) {
      type_error(arg, expected<T>(), obj);
    }
  }
}

// The image as a float32 HxWx3 array that owns it (no copy).
py::array image_to_array(Image image);

// A numpy array of `shape` that owns `values` (moved, no copy).
template <typename T>
py::array_t<T> numpy_of(std::vector<T> values, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(values));
  py::capsule free_values(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(shape, owned->data(), free_values);
}
template <typename T>
py::array_t<T> numpy_of(std::vector<T> values) {
  const auto n = py::ssize_t(values.size());
  return numpy_of(std::move(values), {n});
}

// A light sampler with the session whose scene and light tree it reads (kept alive together).
struct SamplerHandle {
  std::shared_ptr<RenderSession> session;
  std::shared_ptr<LightSampler> sampler;
};

// Settings for a render or sampler of `scene`: its own, with `params` (`--set` key=value, as
// Call::params makes them) added.
SessionSettings settings_with(const PyScene& scene, const std::vector<std::string>& params);
// The scene's session where `settings` are its own, else a new session loaded with them; call
// with the scene's mutex held.
std::shared_ptr<RenderSession> session_for(PyScene& scene, const SessionSettings& settings);
// A fresh sampler by name (a variant may carry parameters, as `rll compare` takes them), its
// errors naming the argument: "sampler: ..." or "params: ...". Call with the GIL: it is released
// while the sampler is made.
std::shared_ptr<LightSampler> named_sampler(const RenderSession& session, const std::string& spec);

// Watches a render run by run_watched(): Ctrl-C (Python's SIGINT handler raising
// KeyboardInterrupt, seen by check_signals on the main thread) raises `cancel` as SIGINT cancels
// `rll render`, and between passes, on the rendering thread, `progress(dict)` (None: none) runs
// with the GIL; an exception of it (or of another signal handler) cancels too and is rethrown by
// rethrow(). Its members are touched only with the GIL held.
struct PassWatcher {
  explicit PassWatcher(py::object progress_callback = py::none())
      : progress(std::move(progress_callback)) {}
  void operator()(const RenderProgress& p);
  // Runs Python's pending signal handlers (a no-op off the main thread); call with the GIL.
  void check_signals();
  void rethrow() const;
  // rethrow(), then KeyboardInterrupt where Ctrl-C cancelled the work: for calls that have no
  // partial result to return.
  void rethrow_or_interrupt() const;
  py::object progress;
  std::atomic<bool> cancel{false};
  bool interrupted = false;
  std::exception_ptr callback_error;
};
// Runs `work` (a render that reads `watch.cancel`) on a thread of its own while this thread, the
// caller's with the GIL, waits without it and every kSignalPollMs takes it for
// watch.check_signals(): Ctrl-C is seen within that time, inside a pass as between passes, and
// the render stops at its next look at the flag (render/render.h). Rethrows `work`'s exception.
inline constexpr int kSignalPollMs = 20;
void run_watched(PassWatcher& watch, const std::function<void()>& work);
// A render's progress as the callback gets it: passes, spp, spp_target, seconds, samples.
py::dict progress_dict(const RenderProgress& p);
// JSON as Python's json.loads makes it.
py::object to_python(const nlohmann::json& j);
// Python's json.loads of `text`; where it is not JSON, rll.Error naming `where` ("x.exr: the
// rll.share header"), the line and column, and `what_to_do`.
py::object parse_json(const std::string& text, const std::string& where,
                      const std::string& what_to_do);

// The learnt state of a sampler that has one (rll, fermat, oracle) as a Python object, or None.
py::object state_object(const SamplerHandle& h);

// Adds rll.State and rll.load_state.
void bind_state(py::module_& m);
// Adds rll.reference and rll.compare.
void bind_measure(py::module_& m);

}  // namespace rll::python

namespace pybind11::detail {
// Arg<T> takes any object; the function converts it (Call).
template <typename T>
struct type_caster<rll::python::Arg<T>> {
  PYBIND11_TYPE_CASTER(rll::python::Arg<T>, rll::python::ArgName<T>::name);
  bool load(handle src, bool) {
    value.obj = reinterpret_borrow<object>(src);
    return true;
  }
  static handle cast(const rll::python::Arg<T>& a, return_value_policy, handle) {
    return a.obj.inc_ref();
  }
};
}  // namespace pybind11::detail
