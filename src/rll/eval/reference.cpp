#include "rll/eval/reference.h"

#include <fmt/format.h>

#include <bit>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "rll/core/error.h"
#include "rll/core/rng.h"
#include "rll/render/session.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

// A 64-bit streaming hash over 8-byte words (splitmix64 finaliser per word), not cryptographic:
// it only has to tell scenes apart.
class Hasher {
 public:
  void bytes(const void* data, size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    word(n);
    for (; n >= 8; n -= 8, p += 8) {
      uint64_t w;
      std::memcpy(&w, p, 8);
      word(w);
    }
    if (n > 0) {
      uint64_t w = 0;
      std::memcpy(&w, p, n);
      word(w);
    }
  }
  void word(uint64_t w) { m_h = mix64(m_h ^ (w + 0x9e3779b97f4a7c15ull)); }
  void add(float f) { word(std::bit_cast<uint32_t>(f)); }
  void add(const Vec3& v) {
    add(v.x);
    add(v.y);
    add(v.z);
  }
  void add(int64_t i) { word(uint64_t(i)); }
  template <typename T>
  void vector(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes(v.data(), v.size() * sizeof(T));
  }
  uint64_t value() const { return m_h; }

 private:
  uint64_t m_h = 0xcbf29ce484222325ull;
};

static_assert(sizeof(Vec3) == 12 && sizeof(Vec2) == 8, "hashed as packed floats");

std::string entry_stem(const ReferenceKey& key, int spp, uint64_t seed) {
  return fmt::format("{}-{}spp-seed{}", key.hex(), spp, seed);
}

std::optional<nlohmann::json> read_json(const fs::path& p) {
  std::ifstream f(p);
  if (!f) return std::nullopt;
  nlohmann::json j = nlohmann::json::parse(f, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) return std::nullopt;
  return j;
}

std::optional<ReferenceInfo> info_from_json(const nlohmann::json& j, const fs::path& exr) {
  try {
    ReferenceInfo info;
    info.image = exr;
    info.scene = j.at("scene").get<std::string>();
    info.width = j.at("resolution").at(0).get<int>();
    info.height = j.at("resolution").at(1).get<int>();
    info.sampler = j.at("sampler").get<std::string>();
    info.spp = j.at("spp").get<int>();
    info.seed = j.at("seed").get<uint64_t>();
    info.seconds = j.at("seconds").get<double>();
    return info;
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;
  }
}

}  // namespace

uint64_t scene_content_hash(const Scene& s) {
  Hasher h;
  h.vector(s.mesh.positions);
  h.vector(s.mesh.normals);
  h.vector(s.mesh.uvs);
  h.vector(s.mesh.triangles);
  h.vector(s.mesh.material);
  h.vector(s.mesh.light);
  h.word(s.materials.size());
  for (const Material& m : s.materials) {
    h.word(uint64_t(m.type));
    h.add(m.albedo);
    h.add(int64_t(m.albedo_texture));
    h.add(m.specular);
    h.add(m.eta);
    h.add(m.k);
    h.add(m.ior);
    h.add(m.roughness);
    h.add(m.emission);
    h.word(m.two_sided_emission);
  }
  h.word(s.textures.size());
  for (const Image& t : s.textures) {
    h.add(int64_t(t.width()));
    h.add(int64_t(t.height()));
    h.vector(t.pixels());
  }
  h.word(s.lights.size());
  for (const Light& l : s.lights) {
    h.word(uint64_t(l.type));
    h.add(l.p0);
    h.add(l.p1);
    h.add(l.p2);
    h.add(l.n);
    h.add(l.area);
    h.add(l.radiance);
    h.word(l.two_sided);
    h.word(l.triangle);
  }
  h.add(s.camera.position);
  h.add(s.camera.target);
  h.add(s.camera.up);
  h.add(s.camera.fov);
  h.add(int64_t(s.width));
  h.add(int64_t(s.height));
  h.word(s.sky.has_value());
  if (s.sky) {
    h.add(int64_t(s.sky->triangles));
    h.add(s.sky->radiance);
    h.add(s.sky->up);
    h.add(s.sky->radius_scale);
  }
  return h.value();
}

uint64_t integrator_settings_hash(const IntegratorSettings& st) {
  Hasher h;
  h.add(int64_t(kReferenceCacheVersion));
  h.word(uint64_t(st.type));
  h.add(int64_t(st.max_depth));
  h.word(uint64_t(st.strategy));
  h.add(int64_t(st.rr_depth));
  return h.value();
}

std::string ReferenceKey::hex() const {
  return fmt::format("{:016x}{:016x}", scene, settings);
}

ReferenceKey reference_key(const Scene& scene, const IntegratorSettings& settings) {
  return {scene_content_hash(scene), integrator_settings_hash(settings)};
}

fs::path default_cache_dir() {
  const char* env = std::getenv("RLL_CACHE_DIR");
  if (env && *env) return fs::path(env);
  return fs::path("out") / "cache";
}

std::string canonical_scene_spec(const std::string& spec) {
  if (spec.rfind("builtin:", 0) == 0) return spec;
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(spec, ec), ec);
  return ec ? spec : p.string();
}

std::optional<ReferenceInfo> ReferenceCache::find(
    const ReferenceKey& key, int min_spp, const std::function<bool(uint64_t)>& seed_allowed) const {
  std::error_code ec;
  if (!fs::is_directory(m_dir, ec)) return std::nullopt;
  const std::string prefix = key.hex() + "-";
  std::optional<ReferenceInfo> best;
  for (const auto& entry : fs::directory_iterator(m_dir, ec)) {
    const fs::path& p = entry.path();
    if (p.extension() != ".json" || p.filename().string().rfind(prefix, 0) != 0) continue;
    fs::path exr = p;
    exr.replace_extension(".exr");
    if (!fs::exists(exr, ec)) continue;
    auto j = read_json(p);
    if (!j || j->value("key", std::string()) != key.hex()) continue;
    auto info = info_from_json(*j, exr);
    if (!info || info->spp < min_spp || (seed_allowed && !seed_allowed(info->seed))) continue;
    if (!best || info->spp > best->spp) best = info;
  }
  return best;
}

ReferenceInfo ReferenceCache::store(const ReferenceKey& key, const Image& image,
                                    ReferenceInfo info) const {
  std::error_code ec;
  fs::create_directories(m_dir, ec);
  if (!fs::is_directory(m_dir))
    fail("cannot create the reference cache folder '{}': {}", m_dir.string(), ec.message());
  info.width = image.width();
  info.height = image.height();
  const std::string stem = entry_stem(key, info.spp, info.seed);
  info.image = m_dir / (stem + ".exr");
  const std::string settings_hex = fmt::format("{:016x}", key.settings);

  // Entries left behind by an earlier version of this scene can never be found again.
  for (const auto& entry : fs::directory_iterator(m_dir, ec)) {
    const fs::path& p = entry.path();
    if (p.extension() != ".json") continue;
    auto j = read_json(p);
    if (!j || j->value("key", std::string()) == key.hex()) continue;
    auto old = info_from_json(*j, p);
    if (!old || old->scene != info.scene || old->width != info.width ||
        old->height != info.height || j->value("settings_hash", std::string()) != settings_hex)
      continue;
    fs::path exr = p;
    exr.replace_extension(".exr");
    fs::remove(exr, ec);
    fs::remove(p, ec);
  }

  write_image(info.image, image);
  nlohmann::json j;
  j["key"] = key.hex();
  j["scene_hash"] = fmt::format("{:016x}", key.scene);
  j["settings_hash"] = settings_hex;
  j["scene"] = info.scene;
  j["resolution"] = {info.width, info.height};
  j["sampler"] = info.sampler;
  j["spp"] = info.spp;
  j["seed"] = info.seed;
  j["seconds"] = info.seconds;
  j["cache_version"] = kReferenceCacheVersion;
  // The metadata goes last: an entry without it is never found, so a crash mid-store is harmless.
  write_file_atomic(m_dir / (stem + ".json"), j.dump(2) + "\n");
  return info;
}

ObtainedReference obtain_reference(const RenderSession& session, const ReferenceCache& cache,
                                   const ReferenceRequest& request, bool show_progress,
                                   const std::atomic<bool>* cancel) {
  if (request.spp < 1) fail("the reference needs at least 1 spp (got {})", request.spp);
  const ReferenceKey key = reference_key(session.scene(), session.integrator());
  ObtainedReference out;
  if (!request.force) {
    if (auto hit = cache.find(key, request.spp, request.seed_allowed)) {
      out.image = read_image(hit->image);
      if (out.image.width() == session.scene().width &&
          out.image.height() == session.scene().height) {
        out.info = *hit;
        out.from_cache = true;
        return out;
      }
    }
  }
  auto sampler = session.make_sampler(request.sampler);
  Film film(session.scene().width, session.scene().height);
  RenderSettings rs;
  rs.spp = request.spp;
  rs.seed = request.seed;
  rs.pass_spp = request.pass_spp;
  rs.max_pass_spp = request.max_pass_spp;
  const RenderProgress p = session.render(*sampler, film, rs, "reference", show_progress, cancel);
  out.image = film.resolve();
  out.info.scene = canonical_scene_spec(session.settings().scene);
  out.info.sampler = request.sampler;
  out.info.spp = p.spp_done;
  out.info.seed = request.seed;
  out.info.seconds = p.seconds;
  out.info.width = out.image.width();
  out.info.height = out.image.height();
  out.complete = !p.cancelled && p.spp_done >= request.spp;
  if (out.complete) out.info = cache.store(key, out.image, out.info);
  return out;
}

}  // namespace rll
