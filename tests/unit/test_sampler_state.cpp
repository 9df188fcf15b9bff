// Learnt sampler states in files (--rll-state): a loaded sampler is the saved one (the same pmf
// for every light at the same points, the same samples), and a state of another scene, sampler,
// parameters or version, a truncated or a damaged file is refused with an rll::Error; a state's
// parameters are every key of the sampler's tables, so that a state saved before a key joined a
// table is refused too.
#include <gtest/gtest.h>

#include <cstring>
#include <set>

#include "rll/accel/accel.h"
#include "rll/core/hash.h"
#include "rll/core/params.h"
#include "rll/lights/ltc_sampler.h"
#include "rll/lights/oracle_sampler.h"
#include "rll/lights/rht_sampler.h"
#include "rll/lights/rll_settings.h"
#include "rll/lights/sampler_state.h"
#include "support/sampler_contexts.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

struct Trained {
  Scene scene = small_builtin_scene("cornell-boxes-room", 32, 24);
  LightTree tree = build_light_tree(scene);
  Accel accel{scene.mesh};
  std::unique_ptr<LightSampler> make(const std::string& name, std::vector<std::string> set = {}) const {
    return make_light_sampler(name, scene, tree, Params::parse(set), &accel);
  }
  // Trains `sampler` for a few passes and saves its state to dir/state.bin.
  fs::path train_and_save(LightSampler& sampler, const TempDir& dir) const {
    train_sampler(scene, accel, sampler, 4);
    const fs::path file = dir / "state.bin";
    save_sampler_state(file, sampler, scene.fingerprint());
    return file;
  }
};

// The largest |pmf_a - pmf_b| over every light at `contexts`, each prepared by its sampler with
// the same random number.
float largest_pmf_difference(const LightSampler& a, const LightSampler& b,
                             const std::vector<LightContext>& contexts, size_t lights) {
  float worst = 0;
  for (size_t i = 0; i < contexts.size(); ++i) {
    LightContext ca = contexts[i], cb = contexts[i];
    const float u = float(i % 97) / 97.0f;
    prepare_point(a.sampler_view(), ca, u);
    prepare_point(b.sampler_view(), cb, u);
    for (uint32_t l = 0; l < lights; ++l)
      worst = std::max(
          worst, std::abs(light_pmf(a.sampler_view(), ca, l) - light_pmf(b.sampler_view(), cb, l)));
  }
  return worst;
}

// The parameters a saved state holds, and the state with `parameters` in their place (its
// checksum made again): the header is the 18-byte magic, the version (4 bytes), the scene's
// fingerprint (8), then the sampler's name and parameters, each an 8-byte length and its bytes.
constexpr size_t kNameAt = 18 + 4 + 8;
size_t parameters_at(const std::string& bytes) {
  uint64_t name_len = 0;
  std::memcpy(&name_len, bytes.data() + kNameAt, 8);
  return kNameAt + 8 + name_len;
}
std::string parameters_of_state(const std::string& bytes) {
  uint64_t len = 0;
  std::memcpy(&len, bytes.data() + parameters_at(bytes), 8);
  return bytes.substr(parameters_at(bytes) + 8, len);
}
std::string with_parameters(const std::string& bytes, const std::string& parameters) {
  const size_t at = parameters_at(bytes), rest = at + 8 + parameters_of_state(bytes).size();
  const uint64_t len = parameters.size();
  std::string out = bytes.substr(0, at);
  out.append(reinterpret_cast<const char*>(&len), 8);
  out += parameters;
  out += bytes.substr(rest, bytes.size() - 8 - rest);
  Hasher h;
  h.bytes(out.data(), out.size());
  const uint64_t sum = h.value();
  out.append(reinterpret_cast<const char*>(&sum), 8);
  return out;
}

template <class S>
std::set<std::string> keys_of(const std::vector<ParamSpec<S>>& table) {
  std::set<std::string> keys;
  for (const auto& e : table) keys.insert(e.key);
  return keys;
}
std::set<std::string> rll_keys() {
  std::set<std::string> keys;
  const RllSettings defaults;
  for_each_rll_table(defaults, [&](const auto& table, const auto&) { keys.merge(keys_of(table)); });
  return keys;
}
// The keys of a JSON object (all of them), or those of them in `among`.
std::set<std::string> keys_in(const nlohmann::json& j, const std::set<std::string>& among = {}) {
  std::set<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it)
    if (among.empty() || among.count(it.key())) keys.insert(it.key());
  return keys;
}

}  // namespace

// describe() reports every key of a sampler's tables (its "parameters", what a state is matched
// against): rll's and fermat's three tables and no other key, ltc's, the oracle's (with rll's,
// which it samples with) and rht's.
TEST(SamplerState, EveryTableKeyIsInTheSamplersDescribe) {
  Trained t;
  const std::set<std::string> rll = rll_keys();
  EXPECT_EQ(rll.size(), cut_params().size() + cell_grid_params().size() + rll_params().size());
  for (const std::string name : {"rll", "fermat"})
    EXPECT_EQ(keys_in(t.make(name)->describe()["parameters"]), rll) << name;
  EXPECT_EQ(keys_in(t.make("ltc")->describe()["parameters"]), keys_of(ltc_params()));
  const nlohmann::json oracle = t.make("oracle", {"oracle.discovery_spp=1", "oracle.points=1",
                                                  "oracle.rays=1", "oracle.refine=0"})
                                    ->describe();
  EXPECT_EQ(keys_in(oracle["parameters"]), rll);
  EXPECT_EQ(keys_in(oracle["oracle"], keys_of(oracle_params())), keys_of(oracle_params()));
  EXPECT_EQ(keys_in(t.make("rht")->describe(), keys_of(rht_params())), keys_of(rht_params()));
}

// A state saved by an rll whose tables lacked one of today's keys (its parameters without it) is
// refused, naming the key, for every key of the tables: a key that joins a table changes the
// state's identity with nothing else to write.
TEST(SamplerState, AStateSavedWithoutAKeyOfTheTablesIsRefused) {
  Trained t;
  auto rll = t.make("rll");
  TempDir dir;
  const std::string bytes = read_text(t.train_and_save(*rll, dir));
  const nlohmann::json saved = nlohmann::json::parse(parameters_of_state(bytes));
  auto fresh = t.make("rll");
  // The rewriting keeps a state whole: with its own parameters it loads.
  dir.write("same.bin", with_parameters(bytes, saved.dump()));
  EXPECT_NO_THROW(load_sampler_state(dir / "same.bin", *fresh, t.scene.fingerprint()));
  for (const std::string& key : rll_keys()) {
    nlohmann::json older = saved;
    ASSERT_EQ(older.erase(key), 1u) << key;
    dir.write("older.bin", with_parameters(bytes, older.dump()));
    expect_mentions(
        error_of([&] { load_sampler_state(dir / "older.bin", *fresh, t.scene.fingerprint()); }),
        {"other rll parameters", key + " none (this render: "});
  }
}

TEST(SamplerState, LoadedSamplerHasTheSavedPmfsAndSamples) {
  // rll's table, Fermat's, rll's guided descent (its factors baked again on loading), and rll
  // pooling in two tiers, by ratio (both tiers' coarse cells saved).
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"rll", {}}, {"fermat", {}}, {"rll", {"rll.sampling=guided"}}, {"rll", {"rll.pool_up=1", "rll.pool_guess=ratio"}}};
  for (const auto& [name, set] : cases) {
    Trained t;
    auto trained = t.make(name, set);
    train_sampler(t.scene, t.accel, *trained, 24);
    TempDir dir;
    const fs::path file = dir / "state.bin";
    save_sampler_state(file, *trained, t.scene.fingerprint());
    auto loaded = t.make(name, set);
    load_sampler_state(file, *loaded, t.scene.fingerprint());
    // Saving the loaded sampler gives the same bytes: nothing was lost or reinterpreted.
    const fs::path again = dir / "again.bin";
    save_sampler_state(again, *loaded, t.scene.fingerprint());
    EXPECT_TRUE(read_text(file) == read_text(again)) << name;
    const std::vector<LightContext> contexts = make_contexts(t.scene, t.accel, 300, 7);
    const size_t lights = t.scene.lights.size();
    EXPECT_EQ(largest_pmf_difference(*trained, *loaded, contexts, lights), 0.0f) << name;
    // The test can fail: the trained state is not the fresh one.
    auto fresh = t.make(name, set);
    EXPECT_GT(largest_pmf_difference(*trained, *fresh, contexts, lights), 1e-3f) << name;
    for (size_t i = 0; i < contexts.size(); ++i) {
      LightContext ca = contexts[i], cb = contexts[i];
      prepare_point(trained->sampler_view(), ca, 0.5f);
      prepare_point(loaded->sampler_view(), cb, 0.5f);
      for (double u : {0.01, 0.3, 0.77, 0.999}) {
        const SampledLight sa = sample_light(trained->sampler_view(), ca, u),
                           sb = sample_light(loaded->sampler_view(), cb, u);
        EXPECT_EQ(sa.light, sb.light);
        EXPECT_EQ(sa.pmf, sb.pmf);
      }
    }
    // Both learn on alike: the state holds all that learning reads (rll's pooled coarse cells
    // included), so the same further passes give the same pmfs.
    train_sampler(t.scene, t.accel, *trained, 4);
    train_sampler(t.scene, t.accel, *loaded, 4);
    EXPECT_EQ(largest_pmf_difference(*trained, *loaded, contexts, lights), 0.0f) << name << ", trained on";
  }
}

TEST(SamplerState, RefusesOtherScenesSamplersAndParameters) {
  Trained t;
  auto rll = t.make("rll");
  TempDir dir;
  const fs::path file = t.train_and_save(*rll, dir);

  Scene other = small_builtin_scene("cornell-boxes-room", 32, 16);
  const LightTree other_tree = build_light_tree(other);
  auto on_other = make_light_sampler("rll", other, other_tree, Params::parse({}), nullptr);
  expect_mentions(error_of([&] { load_sampler_state(file, *on_other, other.fingerprint()); }), {"state.bin", "another scene"});
  auto fermat = t.make("fermat");
  expect_mentions(error_of([&] { load_sampler_state(file, *fermat, t.scene.fingerprint()); }), {"sampler 'rll'", "'fermat'"});
  auto epsilon = t.make("rll", {"rll.epsilon=0.3"});
  expect_mentions(error_of([&] { load_sampler_state(file, *epsilon, t.scene.fingerprint()); }), {"epsilon 0.1", "this render: 0.3"});
  auto tree = t.make("tree");
  expect_mentions(error_of([&] { save_sampler_state(dir / "tree.bin", *tree, t.scene.fingerprint()); }), {"'tree'", "nothing"});
  expect_mentions(error_of([&] { load_sampler_state(dir / "missing.bin", *rll, t.scene.fingerprint()); }), {"missing.bin"});
}

TEST(SamplerState, TruncatedDamagedAndForeignFilesAreErrors) {
  Trained t;
  auto rll = t.make("rll");
  TempDir dir;
  const fs::path file = t.train_and_save(*rll, dir);
  const std::string bytes = read_text(file);
  ASSERT_GT(bytes.size(), 1000u);
  const fs::path bad = dir / "bad.bin";
  auto write_bad = [&](const std::string& content) { dir.write("bad.bin", content); };
  auto load = [&] {
    auto s = t.make("rll");
    load_sampler_state(bad, *s, t.scene.fingerprint());
  };
  // Cut anywhere: never a crash, always a message.
  for (size_t n : {size_t(0), size_t(5), size_t(18), size_t(25), size_t(40), bytes.size() / 3, bytes.size() - 9,
                   bytes.size() - 1}) {
    write_bad(bytes.substr(0, n));
    expect_mentions(error_of(load), {"bad.bin"});
  }
  write_bad(bytes.substr(0, bytes.size() / 2));
  expect_mentions(error_of(load), {"truncated"});
  // One byte changed in the learnt values: the checksum says so.
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x10;
  write_bad(flipped);
  expect_mentions(error_of(load), {"damaged", "checksum"});
  // Not a state at all.
  write_bad("P6\n1 1\n255\n...");
  expect_mentions(error_of(load), {"not an rll sampler state"});
  // Another format version (the 4 bytes after the 18-byte magic).
  std::string version = bytes;
  version[18] = char(kSamplerStateVersion + 1);
  write_bad(version);
  expect_mentions(error_of(load), {"version"});
  // A damaged cell with a consistent checksum: the cut no longer fits the light tree. The first
  // cell's first node id sits after its id (4 bytes), key (8), last use (4) and cut size (4),
  // after the payload's capacity (4), pass (8), resets (8) and cell count (4).
  std::string cut = bytes;
  const size_t magic = 18, name_at = magic + 4 + 8;
  uint64_t name_len = 0, params_len = 0;
  std::memcpy(&name_len, cut.data() + name_at, 8);
  const size_t params_at = name_at + 8 + name_len;
  std::memcpy(&params_len, cut.data() + params_at, 8);
  const size_t payload_at = params_at + 8 + params_len + 8;
  const size_t first_node = payload_at + 4 + 8 + 8 + 4 + 4 + 8 + 4 + 4;
  const uint32_t huge = 0x7fffffff;
  std::memcpy(cut.data() + first_node, &huge, 4);
  Hasher h;
  h.bytes(cut.data(), cut.size() - 8);
  const uint64_t sum = h.value();
  std::memcpy(cut.data() + cut.size() - 8, &sum, 8);
  write_bad(cut);
  expect_mentions(error_of(load), {"damaged", "light tree"});
}
