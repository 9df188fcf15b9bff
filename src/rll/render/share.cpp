#include "rll/render/share.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>

#include "rll/core/error.h"
#include "rll/render/film.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

constexpr int kMaxTasks = 1000000;

nlohmann::json to_json(const ShareInfo& s) {
  return {{"version", kShareVersion}, {"settings", s.settings}, {"tasks", s.tasks},
          {"task_spp", s.task_spp},   {"held", s.held},         {"scene", s.scene},
          {"rll_commit", s.commit}};
}

// A list of shares: "0, 1, 3".
std::string list(const std::vector<int>& v) { return fmt::format("{}", fmt::join(v, ", ")); }

}  // namespace

RenderTask parse_task(const std::string& text, const char* flag) {
  auto whole = [&](size_t b, size_t e) -> long long {
    long long n = -1;
    const char* last = text.data() + e;
    auto [ptr, ec] = std::from_chars(text.data() + b, last, n);
    if (b >= e || ptr != last || ec != std::errc()) return -1;
    return n;
  };
  const size_t slash = text.find('/');
  const long long i = slash == std::string::npos ? -1 : whole(0, slash);
  const long long n = slash == std::string::npos ? -1 : whole(slash + 1, text.size());
  if (i < 0 || n < 0)
    fail("{} '{}': expected I/N, share I (counted from 0) of N, e.g. 0/4", flag, text);
  if (n < 1 || n > kMaxTasks) fail("{} '{}': N must be in [1, {}]", flag, text, kMaxTasks);
  if (i >= n) fail("{} '{}': I counts from 0, so it must be below N = {}", flag, text, n);
  return {int(i), int(n)};
}

ExrFile share_file(const Film& film, const ShareInfo& info) {
  ExrFile f;
  f.image = film.resolve();
  f.counts = film.counts();
  f.attributes.emplace_back(kShareAttribute, to_json(info).dump());
  return f;
}

ShareInfo read_share_info(const ExrFile& exr, const std::string& file) {
  const std::string* text = exr.attribute(kShareAttribute);
  if (!text)
    fail("'{}' is not an rll render share: it has no '{}' metadata (render shares with "
         "`rll render --task I/N ... -o SHARE.exr`)",
         file, kShareAttribute);
  const nlohmann::json j = nlohmann::json::parse(*text, nullptr, false);
  auto damaged = [&](const char* what) -> ShareInfo {
    fail("'{}' has damaged share metadata ({})", file, what);
  };
  if (!j.is_object()) return damaged("not JSON");
  if (!j.contains("version") || !j["version"].is_number_integer()) return damaged("no version");
  if (j["version"] != kShareVersion)
    fail("'{}' is a share of format version {}; this rll merges version {}", file,
         j["version"].dump(), kShareVersion);
  ShareInfo s;
  try {
    s.settings = j.at("settings");
    s.tasks = j.at("tasks").get<int>();
    s.task_spp = j.at("task_spp").get<int>();
    s.held = j.at("held").get<std::vector<int>>();
    s.scene = j.at("scene").get<std::string>();
    s.commit = j.at("rll_commit").get<std::string>();
  } catch (const nlohmann::json::exception&) {
    return damaged("a field is missing or of the wrong type");
  }
  if (!s.settings.is_object() || s.tasks < 1 || s.tasks > kMaxTasks || s.task_spp < 0 ||
      s.held.empty())
    return damaged("a field is out of range");
  for (size_t k = 0; k < s.held.size(); ++k)
    if (s.held[k] < 0 || s.held[k] >= s.tasks || (k > 0 && s.held[k] <= s.held[k - 1]))
      return damaged("its list of shares is not increasing within [0, tasks)");
  if (exr.counts.size() != exr.image.pixel_count())
    fail("'{}' has no per-pixel sample counts (channel 'count'): it cannot be merged exactly", file);
  return s;
}

MergeResult merge_shares(const std::vector<fs::path>& inputs) {
  if (inputs.empty()) fail("merge: no input images");
  MergeResult out;
  std::vector<double> sum;
  std::vector<uint64_t> count;
  std::vector<std::string> owner;  // per share: the input holding it
  std::string first;
  for (const fs::path& path : inputs) {
    const std::string name = path.string();
    ExrFile exr = read_exr_file(path);
    ShareInfo s = read_share_info(exr, name);
    if (first.empty()) {
      first = name;
      out.info = s;
      out.info.held.clear();
      out.file.image = Image(exr.image.width(), exr.image.height());
      sum.assign(3 * exr.image.pixel_count(), 0.0);
      count.assign(exr.image.pixel_count(), 0);
      owner.assign(size_t(s.tasks), "");
    } else {
      auto refuse = [&](const std::string& field, const std::string& a, const std::string& b) {
        fail("cannot merge '{}' with '{}': they are not shares of one render, their {} differs "
             "({} and {})",
             name, first, field, b, a);
      };
      const ShareInfo& f = out.info;
      for (auto it = f.settings.begin(); it != f.settings.end(); ++it)
        if (!s.settings.contains(it.key()))
          refuse(it.key(), it.value().dump(), "none");
        else if (s.settings[it.key()] != it.value())
          refuse(it.key(), it.value().dump(), s.settings[it.key()].dump());
      for (auto it = s.settings.begin(); it != s.settings.end(); ++it)
        if (!f.settings.contains(it.key())) refuse(it.key(), "none", it.value().dump());
      if (s.tasks != f.tasks) refuse("number of shares", std::to_string(f.tasks), std::to_string(s.tasks));
      if (s.task_spp != f.task_spp)
        refuse("samples per pixel of each share", std::to_string(f.task_spp), std::to_string(s.task_spp));
      if (exr.image.width() != out.file.image.width() || exr.image.height() != out.file.image.height())
        refuse("image size", fmt::format("{}x{}", out.file.image.width(), out.file.image.height()),
               fmt::format("{}x{}", exr.image.width(), exr.image.height()));
      if (s.commit != f.commit)
        out.warnings.push_back(fmt::format("'{}' was rendered by rll {} and '{}' by rll {}: "
                                           "builds may differ in what they compute",
                                           name, s.commit, first, f.commit));
    }
    for (int t : s.held) {
      if (!owner[size_t(t)].empty())
        fail("cannot merge: share {} of {} is in both '{}' and '{}' (its samples would count twice)",
             t, s.tasks, owner[size_t(t)], name);
      owner[size_t(t)] = name;
      out.info.held.push_back(t);
    }
    uint32_t lo = std::numeric_limits<uint32_t>::max();
    // Each share the file holds gave a pixel at most task_spp samples (--task renders a fixed
    // range of them): a larger count would weigh the pixel's mean above its samples. A whole
    // render (1 share) records the spp of its last complete pass, and an interrupted pass
    // leaves some pixels more; it is never merged with another file, so its counts weigh
    // nothing. (The channel is 32-bit unsigned, which read_exr_file checks: a count cannot be
    // negative, NaN or fractional.)
    const uint64_t most = uint64_t(s.task_spp) * s.held.size();
    for (size_t i = 0; i < exr.counts.size(); ++i) {
      const double n = exr.counts[i];
      if (s.tasks > 1 && exr.counts[i] > most)
        fail(
            "cannot merge '{}': pixel ({}, {}) counts {} samples, but the file holds {} share{} "
            "of {} spp, so at most {}",
            name, i % size_t(exr.image.width()), i / size_t(exr.image.width()), exr.counts[i],
            s.held.size(), s.held.size() == 1 ? "" : "s", s.task_spp, most);
      lo = std::min(lo, exr.counts[i]);
      for (int c = 0; c < 3; ++c) {
        const float v = exr.image[i][c];
        if (!std::isfinite(v) || v < 0)
          fail("cannot merge '{}': pixel ({}, {}) is {} (a render share is finite and "
               "non-negative)",
               name, i % size_t(exr.image.width()), i / size_t(exr.image.width()), v);
        sum[3 * i + c] += n * double(v);
      }
      count[i] += exr.counts[i];
    }
    const long long expected = (long long)s.task_spp * (long long)s.held.size();
    if (s.task_spp > 0 && lo < expected)
      out.warnings.push_back(fmt::format("'{}' holds {} spp where its shares should hold {}: it "
                                         "was interrupted (the merge stays unbiased, with fewer "
                                         "samples there)",
                                         name, lo, expected));
  }
  std::sort(out.info.held.begin(), out.info.held.end());
  for (int t = 0; t < out.info.tasks; ++t)
    if (owner[size_t(t)].empty()) out.missing.push_back(t);
  out.file.counts.resize(count.size());
  out.min_count = std::numeric_limits<uint32_t>::max();
  for (size_t i = 0; i < count.size(); ++i) {
    if (count[i] > std::numeric_limits<uint32_t>::max())
      fail("cannot merge: pixel {} would hold {} samples, more than a share file can count", i, count[i]);
    out.file.counts[i] = uint32_t(count[i]);
    out.min_count = std::min(out.min_count, uint32_t(count[i]));
    out.max_count = std::max(out.max_count, uint32_t(count[i]));
    if (count[i] == 0) continue;
    const double inv = 1.0 / double(count[i]);
    out.file.image[i] = Rgb(float(sum[3 * i] * inv), float(sum[3 * i + 1] * inv), float(sum[3 * i + 2] * inv));
  }
  out.file.attributes.emplace_back(kShareAttribute, to_json(out.info).dump());
  if (!out.missing.empty())
    out.warnings.push_back(fmt::format("{}: the image is unbiased but holds fewer samples than "
                                       "the full render",
                                       missing_shares_text(out.missing, out.info.tasks)));
  return out;
}

std::string missing_shares_text(const std::vector<int>& missing, int tasks) {
  std::vector<std::string> flags;
  for (int t : missing) flags.push_back(fmt::format("--task {}/{}", t, tasks));
  return fmt::format("{} of the {} shares {} missing: {} {} ({})", missing.size(), tasks,
                     missing.size() == 1 ? "is" : "are", missing.size() == 1 ? "share" : "shares",
                     list(missing), fmt::join(flags, ", "));
}

double max_relative_difference(const Image& a, const Image& b) {
  if (a.width() != b.width() || a.height() != b.height()) return std::numeric_limits<double>::infinity();
  double worst = 0;
  for (size_t i = 0; i < a.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double x = a[i][c], y = b[i][c], m = std::max(std::abs(x), std::abs(y));
      if (x != y) worst = std::max(worst, m > 0 && std::isfinite(m) ? std::abs(x - y) / m : 1.0);
    }
  return worst;
}

}  // namespace rll
