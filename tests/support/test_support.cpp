#include "support/test_support.h"
#include "support/power.h"

#include <fmt/format.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "rll/accel/accel.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"
#include "rll/lights/light_sampler.h"
#include "rll/lighttree/light_tree.h"
#include "rll/render/render.h"
#include "rll/scene/builtin.h"

namespace rll::test {
namespace fs = std::filesystem;

TempDir::TempDir() {
  std::string templ = (fs::temp_directory_path() / "rll-test-XXXXXX").string();
  if (!::mkdtemp(templ.data())) throw std::runtime_error("mkdtemp failed");
  m_path = templ;
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(m_path, ec);
}

fs::path TempDir::write(const std::string& name, const std::string& text) const {
  fs::path p = m_path / name;
  if (p.has_parent_path()) fs::create_directories(p.parent_path());
  std::ofstream f(p, std::ios::binary);
  f << text;
  return p;
}

namespace {
std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) {
    if (c == '\'')
      q += "'\\''";
    else
      q += c;
  }
  return q + "'";
}
}  // namespace

CommandResult run_rll(const std::vector<std::string>& args, int timeout_seconds, double* wall) {
  std::string cmd = shell_quote(RLL_BINARY);
  if (timeout_seconds > 0) cmd = "timeout -s KILL " + std::to_string(timeout_seconds) + " " + cmd;
  for (const auto& a : args) cmd += " " + shell_quote(a);
  cmd += " 2>&1";
  const auto t0 = std::chrono::steady_clock::now();
  CommandResult r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  if (wall) *wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

std::string read_text(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

Scene small_builtin_scene(const std::string& name, int width, int height) {
  Scene s = make_builtin_scene(name);
  s.width = width;
  s.height = height;
  s.finalize();
  return s;
}

Image render_scene(const Scene& given, const RenderRequest& req) {
  return render_scene_wrapped(given, req, {});
}

Image render_scene(const Scene& scene, const LightTree& tree, const RenderRequest& req) {
  return render_scene_wrapped(scene, tree, req, {});
}

Image render_scene_wrapped(const Scene& given, const RenderRequest& req, const SamplerWrap& wrap) {
  // As a render session renders it: with a light tree of its own, the lights in its order.
  Scene scene = given;
  const LightTree tree = build_light_tree(scene);
  return render_scene_wrapped(scene, tree, req, wrap);
}

Image render_scene_wrapped(const Scene& scene, const LightTree& tree, const RenderRequest& req,
                           const SamplerWrap& wrap) {
  ThreadLimit limit(req.threads);
  Params params = Params::parse(req.set);
  Accel accel(scene.mesh);
  auto named = make_light_sampler(req.sampler, scene, tree, params, &accel);
  params.check_all_used();
  auto wrapped = wrap ? wrap(*named, scene, tree) : nullptr;
  LightSampler& sampler = wrapped ? *wrapped : *named;
  Integrator integrator(scene, accel, sampler, req.integrator);
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = req.spp;
  rs.seed = req.seed;
  rs.points = req.points;
  render(scene, integrator, sampler, film, rs);
  return film.resolve();
}

void expect_clean_failure(const std::vector<std::string>& args,
                          std::initializer_list<std::string> mentions) {
  CommandResult r = run_rll(args);
  std::string cmd;
  for (const auto& a : args) cmd += " " + a;
  SCOPED_TRACE("rll" + cmd + "\n" + r.output);
  EXPECT_GE(r.exit_code, 1);
  EXPECT_LT(r.exit_code, 128);
  for (const auto& m : mentions) EXPECT_NE(r.output.find(m), std::string::npos) << "missing: " << m;
}

std::string render_refused(const TempDir& dir, const std::filesystem::path& scene,
                           std::initializer_list<std::string> mentions, const std::string& output) {
  const std::filesystem::path out = dir / output;
  auto r = run_rll({"render", scene.string(), "-o", out.string(), "--quiet", "--spp", "1"});
  EXPECT_GE(r.exit_code, 1) << r.output;
  EXPECT_LT(r.exit_code, 128) << r.output;  // 128 + signal: a crash
  for (const auto& m : mentions)
    EXPECT_NE(r.output.find(m), std::string::npos) << "'" << m << "' not in: " << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
  return r.output;
}

double image_mean(const Image& image) {
  double s = 0;
  for (const auto& p : image.pixels()) s += double(p.x) + p.y + p.z;
  return s / (3.0 * image.pixel_count());
}

namespace {
Estimate blocks_of(const std::vector<double>& values, int blocks) {
  const size_t n = values.size();
  blocks = int(std::min<size_t>(size_t(blocks), n));
  std::vector<double> means(size_t(blocks), 0.0);
  std::vector<size_t> counts(size_t(blocks), 0);
  for (size_t i = 0; i < n; ++i) {
    size_t b = i * size_t(blocks) / n;
    means[b] += values[i];
    ++counts[b];
  }
  double mean = 0;
  for (int b = 0; b < blocks; ++b) mean += (means[b] /= double(counts[b]));
  mean /= blocks;
  double var = 0;
  for (double m : means) var += (m - mean) * (m - mean);
  var /= std::max(1, blocks - 1);
  return {mean, std::sqrt(var / blocks)};
}
}  // namespace

Estimate block_estimate(const Image& image, int blocks) {
  std::vector<double> v(image.pixel_count());
  for (size_t i = 0; i < v.size(); ++i) v[i] = (double(image[i].x) + image[i].y + image[i].z) / 3.0;
  return blocks_of(v, blocks);
}

Estimate difference_estimate(const Image& a, const Image& b) {
  std::vector<double> v(a.pixel_count());
  for (size_t i = 0; i < v.size(); ++i)
    v[i] = (double(a[i].x) + a[i].y + a[i].z - b[i].x - b[i].y - b[i].z) / 3.0;
  // Per-pixel differences are independent: the standard error is the sample sd / sqrt(n).
  double mean = 0;
  for (double x : v) mean += x;
  mean /= double(v.size());
  double var = 0;
  for (double x : v) var += (x - mean) * (x - mean);
  var /= double(v.size() - 1);
  return {mean, std::sqrt(var / double(v.size()))};
}

bool agree(const Estimate& a, const Estimate& b, double z, double abs_tol) {
  double se = std::sqrt(a.stderr_ * a.stderr_ + b.stderr_ * b.stderr_);
  return std::abs(a.mean - b.mean) <= z * se + abs_tol;
}

Image image_region(const Image& image, int rx, int ry, int nx, int ny) {
  const int x0 = rx * image.width() / nx, x1 = (rx + 1) * image.width() / nx;
  const int y0 = ry * image.height() / ny, y1 = (ry + 1) * image.height() / ny;
  Image region(x1 - x0, y1 - y0);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) region.at(x - x0, y - y0) = image.at(x, y);
  return region;
}

std::vector<Estimate> region_differences(const Image& a, const Image& b, int nx, int ny) {
  std::vector<Estimate> out;
  for (int ry = 0; ry < ny; ++ry)
    for (int rx = 0; rx < nx; ++rx)
      out.push_back(
          difference_estimate(image_region(a, rx, ry, nx, ny), image_region(b, rx, ry, nx, ny)));
  return out;
}

std::string region_disagreement(const Image& a, const Image& b) {
  constexpr double z = 4.5;
  const Estimate d = difference_estimate(a, b);
  if (std::abs(d.mean) > z * d.stderr_ + 1e-6)
    return fmt::format("image: difference {} +- {}", d.mean, d.stderr_);
  const auto regions = region_differences(a, b, 4, 4);
  for (size_t i = 0; i < regions.size(); ++i)
    if (std::abs(regions[i].mean) > z * regions[i].stderr_ + 1e-6)
      return fmt::format("region {}: difference {} +- {}", i, regions[i].mean, regions[i].stderr_);
  return {};
}

void expect_images_agree(const Image& a, const Image& b, const std::string& what) {
  Estimate d = difference_estimate(a, b);
  EXPECT_LE(std::abs(d.mean), 4.5 * d.stderr_)
      << what << ": mean difference " << d.mean << " +- " << d.stderr_ << " (means "
      << image_mean(a) << ", " << image_mean(b) << ")";
  ::testing::Test::RecordProperty(
      what, fmt::format("{} +- {} (mean {})", d.mean, d.stderr_, image_mean(a)));
  const auto regions = region_differences(a, b, 4, 4);
  for (size_t i = 0; i < regions.size(); ++i)
    EXPECT_LE(std::abs(regions[i].mean), 4.5 * regions[i].stderr_)
        << what << ", region " << i << ": difference " << regions[i].mean << " +- "
        << regions[i].stderr_;
  bound_power(a, b, what);
}

namespace {
Image brighter(Image a, double bias) {
  for (Rgb& p : a.pixels()) p = p * float(1 + bias);
  return a;
}
bool rejects(const Estimate& d) {
  return std::abs(d.mean) > 4.5 * d.stderr_;
}
// The smallest bias (in steps of 0.5%, up to 100%) that the whole-image bound sees both ways: a
// made that much brighter and that much darker are both rejected against b. A bias proportional to
// the image, as a wrong sampler's or integrator's is, also adds the image's own structure to the
// per-pixel differences, so this is larger than 4.5 standard errors of the unbiased difference.
double smallest_seen_bias(const Image& a, const Image& b) {
  for (int k = 1; k <= 200; ++k) {
    const double s = 0.005 * k;
    if (rejects(difference_estimate(brighter(a, s), b)) &&
        rejects(difference_estimate(brighter(a, -s), b)))
      return s;
  }
  return 1e9;
}
}  // namespace

std::string bound_power(const Image& a, const Image& b, const std::string& what, int nx, int ny) {
  int regions = 0;
  for (const Estimate& r : region_differences(brighter(a, 0.05), b, nx, ny)) regions += rejects(r);
  const std::string figure =
      fmt::format("sees a bias of {:.1f}% of the image; {} of {} regions see a 5% bias in them",
                  100 * smallest_seen_bias(a, b), regions, nx * ny);
  std::printf("[ power    ] %s: %s\n", what.c_str(), figure.c_str());
  ::testing::Test::RecordProperty(what + " power", figure);
  return figure;
}

void expect_bound_sees(const Image& a, const Image& b, const std::string& what, double bias) {
  const std::string figure = bound_power(a, b, what);
  EXPECT_LE(smallest_seen_bias(a, b), bias + 1e-9)
      << what << ": the bound cannot see a bias of " << 100 * bias << "% (" << figure << ")";
}

RenderRequest request(const std::string& sampler, const std::string& integrator, int max_depth,
                      const std::string& strategy, int spp, uint64_t seed, PointSet points) {
  RenderRequest r;
  r.sampler = sampler;
  std::vector<std::string> set;
  if (!strategy.empty()) set.push_back(integrator + ".strategy=" + strategy);
  r.integrator = make_integrator_settings(integrator, max_depth, Params::parse(set));
  r.spp = spp;
  r.seed = seed;
  r.points = points;
  return r;
}

void run_in_bounded_memory(const std::function<void()>& read, size_t extra_bytes,
                           bool may_succeed) {
  long pages = 0;
  std::ifstream("/proc/self/statm") >> pages;
  const rlim_t cap = rlim_t(pages) * rlim_t(sysconf(_SC_PAGESIZE)) + rlim_t(extra_bytes);
  const rlimit limit{cap, cap};
  setrlimit(RLIMIT_AS, &limit);
  try {
    read();
  } catch (const Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    // An allocation that failed under the cap, passed on as an rll::Error, is no refusal.
    std::_Exit(std::string(e.what()).find("bad_alloc") == std::string::npos ? 0 : 3);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "not an rll::Error: %s\n", e.what());
    std::_Exit(1);
  }
  std::_Exit(may_succeed ? 0 : 2);
}

SeedEstimates over_seeds(const std::vector<Image>& renders) {
  const int n = 4;
  std::vector<std::vector<double>> values(1 + n * n);
  for (const Image& img : renders) {
    values[0].push_back(image_mean(img));
    for (int ry = 0; ry < n; ++ry)
      for (int rx = 0; rx < n; ++rx)
        values[1 + ry * n + rx].push_back(image_mean(image_region(img, rx, ry, n, n)));
  }
  std::vector<Estimate> e;
  for (const std::vector<double>& v : values) {
    double mean = 0, var = 0;
    for (double x : v) mean += x;
    mean /= double(v.size());
    for (double x : v) var += (x - mean) * (x - mean);
    var /= double(v.size() - 1);
    e.push_back({mean, std::sqrt(var / double(v.size()))});
  }
  return {e[0], std::vector<Estimate>(e.begin() + 1, e.end())};
}

}  // namespace rll::test
