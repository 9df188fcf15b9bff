// rll.State: what a learning sampler (rll, fermat) learnt, or what the oracle knows, as numpy
// arrays: its cells (key, anchor, level, rewards), each cell's cut and baked cluster
// probabilities, the light tree's nodes, and the sampler's pmf() of any light at a cell.
#include <pybind11/stl.h>

#include <cmath>

#include "module.h"
#include "rll/core/error.h"
#include "rll/lights/light_dispatch.h"
#include "rll/lights/rll_sampler.h"
#include "rll/lights/rll_view.h"
#include "rll/lights/sampler_state.h"
#include "rll/lighttree/light_tree.h"
#include "rll/render/aov.h"

namespace rll::python {

namespace {

struct PyState {
  SamplerHandle handle;
  const RllLightSampler* rll = nullptr;

  const CutStore& cuts() const { return rll->cuts(); }
  const CellTable& table() const { return rll->table(); }
  const LightTree& tree() const { return handle.session->light_tree(); }

  std::vector<uint32_t> cells() const {
    std::vector<uint32_t> ids;
    for (uint32_t c = 0; c < table().capacity(); ++c)
      if (table().in_use(c)) ids.push_back(c);
    return ids;
  }
  void check_cell(long long cell) const {
    if (cell < 0 || cell >= (long long)table().capacity() || !table().in_use(uint32_t(cell)))
      fail("cell: {} is not a cell in use (State.cells['id'] lists them)", cell);
  }
  // The cut the sampler samples for `cell`: its own, or the shared initial cut before it has one.
  detail::RllCut cut(uint32_t cell) const {
    const CutStore& s = cuts();
    if (s.active(cell)) return {s.size(cell), s.ends(cell), s.nodes(cell), s.cdf(cell)};
    return {s.initial_size(), s.initial_ends(), s.initial_nodes(), nullptr};
  }
  // The shading point the sampler is asked about: the cell's anchor (or the given point).
  LightContext context(uint32_t cell, const std::optional<std::array<float, 3>>& point,
                       const std::optional<std::array<float, 3>>& normal) const {
    const CellAnchor& a = cuts().anchor(cell);
    LightContext ctx;
    ctx.p = a.p;
    ctx.n = a.n;
    if (point) ctx.p = Vec3((*point)[0], (*point)[1], (*point)[2]);
    if (normal) ctx.n = normalize(Vec3((*normal)[0], (*normal)[1], (*normal)[2]));
    ctx.ns = ctx.n;
    ctx.cell = cell;
    return ctx;
  }
};

py::dict cells_dict(const PyState& s) {
  const std::vector<uint32_t> ids = s.cells();
  const size_t n = ids.size();
  std::vector<uint64_t> key(n);
  std::vector<float> anchor(3 * n), normal(3 * n), rewards(n), defensive(n);
  std::vector<int32_t> level(n);
  std::vector<uint32_t> size(n);
  std::vector<uint8_t> learnt(n);
  const CutStore& cuts = s.cuts();
  for (size_t i = 0; i < n; ++i) {
    const uint32_t c = ids[i];
    const CellAnchor& a = cuts.anchor(c);
    key[i] = s.table().key_of(c);
    for (int d = 0; d < 3; ++d) {
      anchor[3 * i + d] = a.p[d];
      normal[3 * i + d] = a.n[d];
    }
    level[i] = a.level;
    rewards[i] = cuts.rewards_seen(c);
    size[i] = cuts.size(c);
    learnt[i] = cuts.active(c) && cuts.learnt(c);
    defensive[i] = cuts.active(c) ? cuts.defensive_weight(c) : 1.0f;
  }
  const auto rows = py::ssize_t(n);
  py::dict d;
  d["id"] = numpy_of(ids);
  d["key"] = numpy_of(std::move(key));
  d["anchor"] = numpy_of(std::move(anchor), {rows, 3});
  d["normal"] = numpy_of(std::move(normal), {rows, 3});
  d["level"] = numpy_of(std::move(level));
  d["rewards"] = numpy_of(std::move(rewards));
  d["size"] = numpy_of(std::move(size));
  d["learnt"] = numpy_of(std::move(learnt)).attr("astype")("bool");
  d["defensive"] = numpy_of(std::move(defensive));
  return d;
}

py::dict cut_dict(const PyState& s, const Arg<long long>& cell_arg) {
  const long long cell = Call{"State.cut"}.get(cell_arg, "cell");
  s.check_cell(cell);
  const uint32_t c = uint32_t(cell);
  const detail::RllCut cut = s.cut(c);
  const CutStore& store = s.cuts();
  const bool own = store.active(c);
  std::vector<uint32_t> nodes(cut.nodes, cut.nodes + cut.size), end(cut.ends, cut.ends + cut.size),
      begin(cut.size);
  std::vector<float> prob(cut.size), q(cut.size, -1.0f), m2(cut.size, 0.0f);
  for (uint32_t k = 0; k < cut.size; ++k) {
    begin[k] = detail::rll_begin(cut, k);
    // The baked table's probability of cluster k, exactly as sampling and pmf() read it. A cell
    // without a cut of its own samples by the light tree: no table (NaN).
    // A guided cell (rll.sampling=guided) has factors for a descent instead of a table (NaN).
    prob[k] = own && !store.settings().guided ? detail::rll_cdf_width(cut, k) : NAN;
    if (own) {
      q[k] = store.q(c)[k];
      m2[k] = store.m2(c)[k];
    }
  }
  py::dict d;
  d["nodes"] = numpy_of(std::move(nodes));
  d["begin"] = numpy_of(std::move(begin));
  d["end"] = numpy_of(std::move(end));
  d["probability"] = numpy_of(std::move(prob));
  d["q"] = numpy_of(std::move(q));
  d["m2"] = numpy_of(std::move(m2));
  d["own"] = own;
  return d;
}

py::dict tree_dict(const LightTree& tree) {
  const size_t n = tree.node_count();
  std::vector<float> lo(3 * n), hi(3 * n), axis(3 * n), power(n), cos_o(n), cos_e(n);
  std::vector<uint32_t> begin(n), end(n), child(n), parent(n);
  std::vector<uint8_t> leaf(n);
  for (size_t i = 0; i < n; ++i) {
    const LightTreeNode& nd = tree.node(uint32_t(i));
    for (int d = 0; d < 3; ++d) {
      lo[3 * i + d] = nd.bounds.box.lo[d];
      hi[3 * i + d] = nd.bounds.box.hi[d];
      axis[3 * i + d] = nd.bounds.axis[d];
    }
    power[i] = nd.bounds.power;
    cos_o[i] = nd.bounds.cos_theta_o;
    cos_e[i] = nd.bounds.cos_theta_e;
    begin[i] = nd.begin;
    end[i] = nd.end;
    child[i] = nd.child;
    parent[i] = nd.parent;
    leaf[i] = nd.is_leaf();
  }
  const auto rows = py::ssize_t(n);
  py::dict d;
  d["lo"] = numpy_of(std::move(lo), {rows, 3});
  d["hi"] = numpy_of(std::move(hi), {rows, 3});
  d["power"] = numpy_of(std::move(power));
  d["axis"] = numpy_of(std::move(axis), {rows, 3});
  d["cos_theta_o"] = numpy_of(std::move(cos_o));
  d["cos_theta_e"] = numpy_of(std::move(cos_e));
  d["begin"] = numpy_of(std::move(begin));
  d["end"] = numpy_of(std::move(end));
  d["child"] = numpy_of(std::move(child));
  d["parent"] = numpy_of(std::move(parent));
  d["leaf"] = numpy_of(std::move(leaf)).attr("astype")("bool");
  return d;
}

py::object pmf(const PyState& s, const Arg<long long>& cell_arg,
               const Arg<std::optional<long long>>& light_arg, const Arg<Point3>& point_arg,
               const Arg<Point3>& normal_arg) {
  const Call c{"State.pmf"};
  const long long cell = c.get(cell_arg, "cell");
  const std::optional<long long> light = c.get(light_arg, "light");
  const auto point = c.point(point_arg, "point"), normal = c.point(normal_arg, "normal");
  s.check_cell(cell);
  const LightContext ctx = s.context(uint32_t(cell), point, normal);
  const SamplerView view = s.handle.sampler->sampler_view();
  const uint32_t lights = uint32_t(s.tree().light_count());
  if (!light) {
    std::vector<float> all(lights);
    {
      py::gil_scoped_release release;
      for (uint32_t l = 0; l < lights; ++l) all[l] = light_pmf(view, ctx, l);
    }
    return numpy_of(std::move(all));
  }
  const long long l = *light;
  if (l < 0 || l >= (long long)lights) fail("light: {} is not in [0, {})", l, lights);
  return py::float_(light_pmf(view, ctx, uint32_t(l)));
}

}  // namespace

py::object state_object(const SamplerHandle& h) {
  const RllLightSampler* r = sampler_cells(*h.sampler);
  if (!r) return py::none();
  PyState s;
  s.handle = h;
  s.rll = r;
  return py::cast(std::move(s));
}

void bind_state(py::module_& m) {
  py::class_<PyState>(m, "State",
                      "The learnt state of rll or fermat (or the oracle's knowledge): cells, cuts, "
                      "baked cluster probabilities and the light tree, as numpy arrays "
                      "(Render.state, rll.load_state). Lights are numbered in the tree's order, as "
                      "the scene holds them.")
      .def_property_readonly(
          "sampler", [](const PyState& s) { return s.handle.sampler->name(); },
          "The sampler's name (rll, fermat or oracle).")
      .def_property_readonly(
          "passes", [](const PyState& s) { return s.rll->passes(); },
          "Passes (ends of pass) the state has seen.")
      .def_property_readonly(
          "capacity", [](const PyState& s) { return s.table().capacity(); },
          "Cells the table holds at most (cell ids are below it).")
      .def_property_readonly(
          "lights", [](const PyState& s) { return s.tree().light_count(); }, "Number of lights.")
      .def_property_readonly("cells", &cells_dict,
                             "The cells in use, one row each in id order, as a dict of arrays: "
                             "id (uint32), key (uint64, the hash of its grid coordinates), anchor "
                             "(Nx3, a point of the surfaces it covers), normal (Nx3), level (edge "
                             "= scene diameter x 2^level), rewards (received in earlier passes), "
                             "size (clusters of its own cut; 0: none yet, it samples by the light "
                             "tree), learnt (bool), defensive (weight of the prior in its table).")
      .def("cut", &cut_dict, py::arg("cell"),
           "The cut of cell `cell` (an id): dict of arrays over its clusters, in light order: "
           "nodes (light-tree node ids), begin and end (light ranges [begin, end)), "
           "probability (the baked table's probability of each cluster: they sum to 1, NaN for "
           "a cell without a cut of its own or with rll.sampling=guided), q and m2 (learnt mean "
           "and second moment of the "
           "cluster's reward, -1 and 0 where never rewarded), own (False: the shared initial "
           "cut).")
      .def_property_readonly(
          "initial_cut",
          [](const PyState& s) {
            const CutStore& c = s.cuts();
            return numpy_of(
                std::vector<uint32_t>(c.initial_nodes(), c.initial_nodes() + c.initial_size()));
          },
          "Node ids of the shared initial cut (the clusters of a cell without a cut).")
      .def_property_readonly(
          "tree", [](const PyState& s) { return tree_dict(s.tree()); },
          "The light tree's nodes as a dict of arrays (node 0 is the root; a node's children "
          "are child and child + 1): lo and hi (Nx3 bounding box), power, axis (Nx3) with "
          "cos_theta_o and cos_theta_e (orientation cone), begin and end (lights [begin, end)), "
          "child (0 for a leaf), parent (2^32 - 1 for the root), leaf (bool).")
      .def("pmf", &pmf, py::arg("cell"), py::arg("light") = py::none(),
           py::arg("point") = py::none(), py::arg("normal") = py::none(),
           "The sampler's pmf() of `light` at cell `cell`, asked at the cell's anchor (or at "
           "`point` with `normal`); with light None, a float32 array over every light. With the "
           "default defensive term (folded into the cell's table), a cluster's lights' pmfs sum "
           "to its cut()['probability'].")
      .def(
          "save",
          [](const PyState& s, const Arg<PathLike>& path) {
            const std::string p = Call{"State.save"}.path(path, "path");
            py::gil_scoped_release release;
            save_sampler_state(p, *s.handle.sampler, s.handle.session->scene().fingerprint());
          },
          py::arg("path"),
          "Saves the state as `rll render --rll-state FILE` does (loaded by a render of the same "
          "scene, resolution, sampler and parameters, or by rll.load_state).")
      .def("__repr__", [](const PyState& s) {
        return "<rll.State of " + s.handle.sampler->name() + ": " +
               std::to_string(s.table().used()) + " cells, " + std::to_string(s.rll->passes()) +
               " passes>";
      });

  m.def(
      "load_state",
      [](const Arg<PathLike>& path, const Arg<PyScene>& scene_arg,
         const Arg<std::string>& sampler_arg, const Arg<py::dict>& params_arg) {
        const Call c{"load_state"};
        const std::string p = c.path(path, "path");
        const std::shared_ptr<PyScene> scene = c.scene(scene_arg, "scene");
        const std::string sampler = c.get(sampler_arg, "sampler");
        const SessionSettings settings = settings_with(*scene, c.params(params_arg, "params"));
        // The lock is taken without the GIL, as render() takes it.
        std::unique_lock<std::mutex> lock(scene->mutex, std::defer_lock);
        {
          py::gil_scoped_release release;
          lock.lock();
        }
        SamplerHandle h;
        h.session = session_for(*scene, settings);
        h.sampler = named_sampler(*h.session, sampler);
        check_sampler_has_state(*h.sampler, "sampler");
        {
          py::gil_scoped_release release;
          load_sampler_state(p, *h.sampler, h.session->scene().fingerprint());
        }
        return state_object(h);
      },
      py::arg("path"), py::arg("scene"), py::arg("sampler") = "rll", py::arg("params") = py::dict(),
      "Reads a learnt state saved by `rll render --rll-state FILE` (or State.save) for `scene`,\n"
      "into a fresh `sampler` made with `params` (as the render that saved it); raises\n"
      "rll.Error with rll's message when it belongs to another scene, sampler or parameters,\n"
      "or is damaged.");
}

}  // namespace rll::python
