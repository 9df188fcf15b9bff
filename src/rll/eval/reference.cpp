#include "rll/eval/reference.h"

#include <fmt/format.h>

#include <bit>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "rll/core/error.h"
#include "rll/core/file_checks.h"
#include "rll/core/hash.h"
#include "rll/core/rng.h"
#include "rll/eval/metrics.h"
#include "rll/session/session.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

std::string entry_stem(const ReferenceKey& key, int spp, uint64_t seed) {
  return fmt::format("{}-{}spp-seed{}", key.hex(), spp, seed);
}

// The header attribute of a cached image that says how many samples it holds, to be checked
// against its sidecar's "spp".
constexpr const char* kSppAttribute = "rll.reference.spp";

// A sidecar's JSON object; nullopt, with `why` set, for one that is not a readable file of JSON.
std::optional<nlohmann::json> read_json(const fs::path& p, std::string* why = nullptr) {
  auto damaged = [&](std::string text) -> std::optional<nlohmann::json> {
    if (why) *why = fmt::format("{}: {}", p.string(), text);
    return std::nullopt;
  };
  const std::string kind = non_regular_kind(p);
  if (!kind.empty()) return damaged(fmt::format("it is {}, not a file", kind));
  std::ifstream f(p, std::ios::binary);
  if (!f) return damaged(fmt::format("cannot open it: {}", std::strerror(errno)));
  try {
    nlohmann::json j = nlohmann::json::parse(f, nullptr, /*allow_exceptions=*/false);
    if (j.is_discarded() || !j.is_object()) return damaged("it is not a JSON object");
    return j;
  } catch (const std::exception& e) {  // a read error of the stream
    return damaged(fmt::format("cannot read it: {}", e.what()));
  }
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
    info.frame = j.value("frame", -1);
    if (j.value("halves", false)) {
      info.half = exr;
      info.half.replace_extension(".half.exr");
    }
    return info;
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;
  }
}

}  // namespace

uint64_t integrator_settings_hash(const IntegratorSettings& st) {
  Hasher h;
  h.add(int64_t(kReferenceCacheVersion));
  h.word(uint64_t(st.type));
  h.add(int64_t(st.max_depth));
  h.word(uint64_t(st.strategy));
  h.add(int64_t(st.rr_depth));
  // pbrt-v4's coated weight changes what a render converges to; the default adds nothing, so
  // that the references cached before the key existed keep their names.
  if (st.coated_weights != CoatedWeights::Unbiased)
    h.word(0xc0a7ed00ull + uint64_t(st.coated_weights));
  return h.value();
}

std::string ReferenceKey::hex() const {
  return fmt::format("{:016x}{:016x}", scene, settings);
}

ReferenceKey reference_key(const Scene& scene, const IntegratorSettings& settings) {
  return {scene.fingerprint(), integrator_settings_hash(settings)};
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
  std::vector<fs::path> damaged;
  for (const auto& entry : fs::directory_iterator(m_dir, ec)) {
    const fs::path& p = entry.path();
    if (p.extension() != ".json" || p.filename().string().rfind(prefix, 0) != 0) continue;
    fs::path exr = p;
    exr.replace_extension(".exr");
    if (!fs::exists(exr, ec)) continue;
    std::string why;
    auto j = read_json(p, &why);
    if (!j) {
      // A sidecar that cannot be read would hide its entry, and block its name, for ever.
      fmt::print(stderr, "rll: warning: the cached reference {} is damaged ({}); deleted\n",
                 exr.string(), why);
      damaged.push_back(p);
      continue;
    }
    if (j->value("key", std::string()) != key.hex()) continue;
    auto info = info_from_json(*j, exr);
    if (!info || info->spp < min_spp || (seed_allowed && !seed_allowed(info->seed))) continue;
    if (!best || info->spp > best->spp) best = info;
  }
  for (const fs::path& p : damaged) {
    ReferenceInfo info;
    info.image = fs::path(p).replace_extension(".exr");
    info.half = fs::path(p).replace_extension(".half.exr");
    remove(info);
  }
  return best;
}

void ReferenceCache::remove(const ReferenceInfo& info) const {
  std::error_code ec;
  fs::path json = info.image;
  json.replace_extension(".json");
  // First: without it the entry is never found again. A folder in its place is damage too.
  if (fs::is_directory(fs::symlink_status(json, ec)))
    fs::remove_all(json, ec);
  else
    fs::remove(json, ec);
  fs::remove(info.image, ec);
  if (!info.half.empty()) fs::remove(info.half, ec);
}

int ReferenceCache::remove_stale_temporaries() const {
  return remove_stale_temporaries_in(m_dir);
}

// The cache folder is made as outputs' folders are: a link to nothing on the way is refused by
// name (create_directories would say only "File exists"), a file in the way named.
void ReferenceCache::check_writable() const {
  create_output_folder(m_dir, "the reference cache folder");
  check_folder_writable(m_dir, "the reference cache");
}

ReferenceInfo ReferenceCache::store(const ReferenceKey& key, const Image& image, ReferenceInfo info,
                                    const Image* first_half) const {
  create_output_folder(m_dir, "the reference cache folder");
  std::error_code ec;
  info.width = image.width();
  info.height = image.height();
  const std::string stem = entry_stem(key, info.spp, info.seed);
  info.image = m_dir / (stem + ".exr");
  const std::string settings_hex = fmt::format("{:016x}", key.settings);

  // Entries left behind by an earlier version of this scene can never be found again (another
  // frame of an animated scene is not one).
  for (const auto& entry : fs::directory_iterator(m_dir, ec)) {
    const fs::path& p = entry.path();
    if (p.extension() != ".json") continue;
    auto j = read_json(p);
    if (!j || j->value("key", std::string()) == key.hex()) continue;
    auto old = info_from_json(*j, p);
    if (!old || old->scene != info.scene || old->width != info.width ||
        old->height != info.height || old->frame != info.frame ||
        j->value("settings_hash", std::string()) != settings_hex)
      continue;
    fs::path exr = p;
    exr.replace_extension(".exr");
    old->image = exr;
    remove(*old);
  }

  ExrFile file;
  file.image = image;
  file.attributes.emplace_back(kSppAttribute, std::to_string(info.spp));
  write_exr(info.image, file);
  info.half.clear();
  if (first_half) {
    info.half = m_dir / (stem + ".half.exr");
    write_image(info.half, *first_half);
  }
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
  j["halves"] = first_half != nullptr;
  if (info.frame >= 0) j["frame"] = info.frame;
  j["cache_version"] = kReferenceCacheVersion;
  // The metadata goes last: an entry without it is never found, so a crash mid-store is harmless.
  write_file_atomic(m_dir / (stem + ".json"), j.dump(2) + "\n");
  return info;
}

namespace {

// A cached image as it must be: readable, of the scene's size, finite everywhere, and (when
// `spp` is given) holding what its sidecar says. Images of entries stored before the header
// said their sample count are taken at the sidecar's word.
std::optional<Image> read_cached(const fs::path& path, int width, int height, std::string& why,
                                 std::optional<int> spp = std::nullopt) {
  try {
    ExrFile exr = read_exr_file(path);
    if (const std::string* held = spp ? exr.attribute(kSppAttribute) : nullptr;
        held && *held != std::to_string(*spp)) {
      why = fmt::format("{} holds {} spp, its sidecar {} says {}", path.string(), *held,
                        fs::path(path).replace_extension(".json").filename().string(), *spp);
      return std::nullopt;
    }
    Image image = std::move(exr.image);
    if (image.width() != width || image.height() != height) {
      why = fmt::format("{} is {}x{}, not {}x{}", path.string(), image.width(), image.height(),
                        width, height);
      return std::nullopt;
    }
    for (size_t i = 0; i < image.pixel_count(); ++i)
      if (!is_finite(image[i])) {
        why = fmt::format("{} has non-finite pixels", path.string());
        return std::nullopt;
      }
    return image;
  } catch (const Error& e) {
    why = e.what();
    return std::nullopt;
  }
}

}  // namespace

ObtainedReference obtain_reference(const RenderSession& session, const ReferenceCache& cache,
                                   const ReferenceRequest& request, bool show_progress,
                                   const std::atomic<bool>* cancel) {
  if (request.spp < 1) fail("the reference needs at least 1 spp (got {})", request.spp);
  const ReferenceKey key = reference_key(session.scene(), session.integrator());
  const int width = session.scene().width, height = session.scene().height;
  ObtainedReference out;
  cache.remove_stale_temporaries();
  while (!request.force) {
    auto hit = cache.find(key, request.spp, request.seed_allowed);
    if (!hit) break;
    std::string why;
    std::optional<Image> image = read_cached(hit->image, width, height, why, hit->spp);
    std::optional<Image> half;
    if (image && !hit->half.empty() && !(half = read_cached(hit->half, width, height, why)))
      image.reset();
    if (!image) {
      fmt::print(stderr, "rll: warning: the cached reference {} is damaged ({}); deleted\n",
                 hit->image.string(), why);
      cache.remove(*hit);
      continue;  // another entry, or a new render
    }
    out.image = std::move(*image);
    if (half) {
      // The second half is 2 x mean - first half.
      Image second(width, height);
      for (size_t i = 0; i < second.pixel_count(); ++i)
        second[i] = out.image[i] * 2.0f - (*half)[i];
      out.variance = variance_of_mean_of_halves(*half, second);
    }
    out.info = *hit;
    out.from_cache = true;
    return out;
  }
  // A folder that cannot take the result is found before the render, not after it.
  cache.check_writable();
  const int half_spp = (request.spp + 1) / 2;
  Image halves[2];
  std::vector<uint32_t> counts[2];
  out.complete = true;
  out.info.seconds = 0;
  out.info.spp = 0;
  // A reference is never filtered (render/psf.h): the filtered renders are measured against
  // the unbiased estimate, their bias included (its key leaves the filter out).
  IntegratorSettings unfiltered = session.integrator();
  unfiltered.psf = PsfSettings{};
  for (int h = 0; h < 2 && out.complete; ++h) {
    auto sampler = session.make_sampler(request.sampler);  // each half learns from scratch
    Film film(width, height);
    RenderSettings rs;
    rs.spp = half_spp;
    rs.seed = request.seed + uint64_t(h);
    rs.pass_spp = request.pass_spp;
    rs.max_pass_spp = request.max_pass_spp;
    const RenderProgress p =
        session.render(*sampler, film, rs, fmt::format("reference {}/2", h + 1), show_progress,
                       cancel, {}, nullptr, &unfiltered);
    halves[h] = film.resolve();
    counts[h] = film.counts();
    out.info.spp += p.spp_done;
    out.info.seconds += p.seconds;
    out.complete = !p.cancelled && p.spp_done >= half_spp;
  }
  out.info.scene = canonical_scene_spec(session.settings().scene);
  out.info.sampler = request.sampler;
  out.info.seed = request.seed;
  out.info.frame = request.frame;
  out.info.width = width;
  out.info.height = height;
  if (!out.complete) {
    // What was rendered of both halves, each pixel the mean of its samples, with their count.
    out.image = std::move(halves[0]);
    out.counts = std::move(counts[0]);
    if (!counts[1].empty())
      for (size_t i = 0; i < out.image.pixel_count(); ++i) {
        const uint32_t n0 = out.counts[i], n1 = counts[1][i];
        if (n1 == 0) continue;
        out.image[i] = (out.image[i] * float(n0) + halves[1][i] * float(n1)) / float(n0 + n1);
        out.counts[i] = n0 + n1;
      }
    return out;
  }
  out.image = Image(width, height);
  for (size_t i = 0; i < out.image.pixel_count(); ++i)
    out.image[i] = (halves[0][i] + halves[1][i]) * 0.5f;
  out.variance = variance_of_mean_of_halves(halves[0], halves[1]);
  out.info = cache.store(key, out.image, out.info, &halves[0]);
  return out;
}

nlohmann::json reference_json(bool from_cache, const ReferenceInfo& info, const Image& image,
                              const Image& variance) {
  nlohmann::json j = {{"source", from_cache ? "cache" : "rendered"},
                      {"cache_entry", info.image.string()},
                      {"sampler", info.sampler},
                      {"spp", info.spp},
                      {"seed", info.seed},
                      {"seconds", info.seconds}};
  if (variance.pixel_count()) j["noise_relmse"] = reference_noise_relmse(image, variance);
  return j;
}

}  // namespace rll
