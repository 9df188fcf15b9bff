// What the Python module's source files share: argument conversions, numpy arrays that own
// their data, and the scene and render objects the functions take and return.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <atomic>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "rll/core/image.h"
#include "rll/lights/light_sampler.h"
#include "rll/session/session.h"

namespace rll::python {

namespace py = pybind11;

// A path argument as str or os.PathLike.
std::string fspath(const py::handle& path);

// The image as a float32 HxWx3 array that owns it (no copy).
py::array image_to_array(Image image);
// An HxWx3 array (any real dtype, converted to float32) as an Image; `name` is for messages.
Image image_from_array(const py::handle& obj, const char* name);

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

// A scene loaded once, with the session that renders it with the default integrator; renders
// with other settings (integrator, params, res) load it again into a session of their own.
struct PyScene {
  SessionSettings settings;
  std::shared_ptr<RenderSession> session;
  std::mutex mutex;  // one render at a time: a session's parameter bookkeeping is not shared

  const Scene& scene() const { return session->scene(); }
};

// A light sampler with the session whose scene and light tree it reads (kept alive together).
struct SamplerHandle {
  std::shared_ptr<RenderSession> session;
  std::shared_ptr<LightSampler> sampler;
};

// Settings for a render or sampler of `scene`: its own, with `params` (`--set` key: value) added.
SessionSettings settings_with(const PyScene& scene, const py::dict& params);
// The scene's session where `settings` are its own, else a new session loaded with them; call
// with the scene's mutex held.
std::shared_ptr<RenderSession> session_for(PyScene& scene, const SessionSettings& settings);
// A fresh sampler by name (a variant may carry parameters, as `rll compare` takes them), its
// errors naming the argument: "sampler: ..." or "params: ...".
std::shared_ptr<LightSampler> named_sampler(const RenderSession& session, const std::string& spec);

// Watches a render run by run_watched(): Ctrl-C (Python's SIGINT handler raising
// KeyboardInterrupt, seen by check_signals on the main thread) raises `cancel` as SIGINT cancels
// `rll render`, and between passes, on the rendering thread, `progress(dict)` (None: none) runs
// with the GIL; an exception of it (or of another signal handler) cancels too and is rethrown by
// rethrow(). Its members are touched only with the GIL held.
struct PassWatcher {
  explicit PassWatcher(py::object progress_callback) : progress(std::move(progress_callback)) {}
  void operator()(const RenderProgress& p);
  // Runs Python's pending signal handlers (a no-op off the main thread); call with the GIL.
  void check_signals();
  void rethrow() const;
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

// The learnt state of a sampler that has one (rll, fermat, oracle) as a Python object, or None.
py::object state_object(const SamplerHandle& h);

// Adds rll.State and rll.load_state.
void bind_state(py::module_& m);
// Adds rll.reference and rll.compare.
void bind_measure(py::module_& m);

}  // namespace rll::python
