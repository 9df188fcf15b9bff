#include "rll/lights/sampler_state.h"

#include <fmt/format.h>

#include "rll/core/binary_io.h"
#include "rll/core/error.h"
#include "rll/core/hash.h"
#include "rll/core/image.h"
#include "rll/io/text_scan.h"
#include "rll/lights/light_sampler.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

constexpr char kMagic[] = "rll sampler state\n";
constexpr size_t kMagicSize = sizeof(kMagic) - 1;

uint64_t checksum(const std::string& bytes, size_t begin, size_t end) {
  Hasher h;
  h.bytes(bytes.data() + begin, end - begin);
  return h.value();
}

std::string parameters_of(const LightSampler& sampler) {
  const nlohmann::json d = sampler.describe();
  return d.contains("parameters") ? d["parameters"].dump() : std::string("{}");
}

// "cut_size 128 (this render: 64), alpha 0.05 (this render: 0.02)".
std::string parameter_differences(const std::string& saved, const std::string& ours) {
  const nlohmann::json a = nlohmann::json::parse(saved, nullptr, false),
                       b = nlohmann::json::parse(ours, nullptr, false);
  if (!a.is_object() || !b.is_object()) return "(unreadable parameters)";
  std::string out;
  // Parameters are floats held as doubles: 0.1f shows as 0.1, not 0.10000000149011612.
  auto text = [](const nlohmann::json& v) {
    return v.is_number_float() ? fmt::format("{:.7g}", v.get<double>()) : v.dump();
  };
  auto note = [&](const std::string& key, const std::string& va, const std::string& vb) {
    out += fmt::format("{}{} {} (this render: {})", out.empty() ? "" : ", ", key, va, vb);
  };
  for (auto it = a.begin(); it != a.end(); ++it) {
    if (!b.contains(it.key()))
      note(it.key(), text(it.value()), "none");
    else if (b[it.key()] != it.value())
      note(it.key(), text(it.value()), text(b[it.key()]));
  }
  for (auto it = b.begin(); it != b.end(); ++it)
    if (!a.contains(it.key())) note(it.key(), "none", text(it.value()));
  return out;
}

}  // namespace

void check_sampler_has_state(const LightSampler& sampler, const char* flag) {
  if (!sampler.has_state())
    fail("{}: sampler '{}' learns nothing that can be saved (rll and fermat do)", flag, sampler.name());
}

void save_sampler_state(const fs::path& path, const LightSampler& sampler, uint64_t scene_fingerprint) {
  check_sampler_has_state(sampler, "--rll-state");
  BinaryWriter w;
  w.put_array(kMagic, kMagicSize);
  w.put(kSamplerStateVersion);
  w.put(scene_fingerprint);
  w.put_string(sampler.name());
  w.put_string(parameters_of(sampler));
  const size_t size_at = w.bytes().size();
  w.put(uint64_t(0));  // payload size, filled in below
  const size_t begin = w.bytes().size();
  sampler.save_state(w);
  const uint64_t payload = w.bytes().size() - begin;
  std::memcpy(w.bytes().data() + size_at, &payload, sizeof payload);
  w.put(checksum(w.bytes(), 0, w.bytes().size()));
  write_file_atomic(path, w.bytes());
}

void load_sampler_state(const fs::path& path, LightSampler& sampler, uint64_t scene_fingerprint) {
  check_sampler_has_state(sampler, "--rll-state");
  const std::string name = path.string();
  std::error_code ec;
  if (fs::is_directory(path, ec)) fail("cannot read '{}': it is a folder, not a sampler state", name);
  const std::string bytes = read_text_file(path);
  if (bytes.size() < kMagicSize || bytes.compare(0, kMagicSize, kMagic) != 0)
    fail("cannot read '{}': it is not an rll sampler state (written by --rll-state)", name);
  BinaryReader r(bytes, name, kMagicSize);
  const uint32_t version = r.get<uint32_t>();
  if (version != kSamplerStateVersion)
    fail("cannot read '{}': it is a sampler state of format version {}, and this rll reads "
         "version {} only: render it again to learn a new state",
         name, version, kSamplerStateVersion);
  const uint64_t fingerprint = r.get<uint64_t>();
  const std::string sampler_name = r.get_string(), parameters = r.get_string();
  const uint64_t payload = r.get<uint64_t>();
  const size_t begin = r.position();
  if (payload > r.remaining() || r.remaining() - payload < sizeof(uint64_t)) r.truncated();
  const size_t end = begin + size_t(payload);
  uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + end, sizeof stored);
  if (end + sizeof stored != bytes.size() || stored != checksum(bytes, 0, end))
    fail("cannot read '{}': the file is damaged (its checksum does not match its content)", name);
  if (fingerprint != scene_fingerprint)
    fail("cannot use '{}': it was learnt on another scene or resolution (scene fingerprint "
         "{:016x}; this render's is {:016x})",
         name, fingerprint, scene_fingerprint);
  if (sampler_name != sampler.name())
    fail("cannot use '{}': it holds the state of sampler '{}', and this render's sampler is '{}'",
         name, sampler_name, sampler.name());
  if (const std::string ours = parameters_of(sampler); parameters != ours)
    fail("cannot use '{}': it was learnt with other {} parameters: {}", name, sampler.name(),
         parameter_differences(parameters, ours));
  BinaryReader body(bytes, name, begin, end);
  sampler.load_state(body);
}

}  // namespace rll
