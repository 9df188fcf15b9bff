#include "rll/eval/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "rll/core/error.h"
#include "rll/core/paths.h"

namespace rll {

namespace {

void check_sizes(const Image& image, const Image& reference) {
  if (image.width() != reference.width() || image.height() != reference.height())
    fail("image is {}x{} but the reference is {}x{}", image.width(), image.height(),
         reference.width(), reference.height());
  if (image.pixel_count() == 0) fail("cannot measure the error of an empty image");
}

double relative_squared_error(float x, float ref) {
  const double d = double(x) - ref;
  return d * d / (double(ref) * ref + kRelMseEpsilon);
}

const char* role_name(MeasuredRole role) {
  switch (role) {
    case MeasuredRole::image:
      return "image";
    case MeasuredRole::reference:
      return "reference";
    case MeasuredRole::reference_variance:
      return "reference variance";
  }
  return "image";
}

}  // namespace

Image read_measured_image(const std::filesystem::path& path, MeasuredRole role) {
  const std::string ext = lower_extension(path);
  if (ext != ".exr" && ext != ".hdr")
    fail(
        "{} '{}': a {} file holds 8-bit values (sRGB, clamped at 1), not a rendering's "
        "radiance; errors are measured on linear images: give it as .exr (or .hdr)",
        role_name(role), path.string(), ext.empty() ? "extensionless" : ext);
  Image image = read_image(path, /*srgb=*/false, LuminanceOnly::refuse);
  check_measured_pixels(image, path.string(), role);
  return image;
}

void check_measured_pixels(const Image& image, const std::string& file, MeasuredRole role) {
  size_t bad = 0, first = 0;
  int first_channel = 0;
  for (size_t i = image.pixel_count(); i-- > 0;)
    for (int c = 3; c-- > 0;)
      if (!std::isfinite(image[i][c]) || image[i][c] < 0) bad++, first = i, first_channel = c;
  if (!bad) return;
  const float v = image[first][first_channel];
  const size_t w = size_t(std::max(1, image.width()));
  fail(
      "{} '{}': {} of its values are NaN, infinite or negative, the first {} in channel {} of "
      "pixel "
      "({}, {}); a {} must be finite and non-negative, or every error measured with it is "
      "meaningless",
      role_name(role), file, bad, v, "RGB"[first_channel], first % w, first / w, role_name(role));
}

ErrorMetrics error_metrics(const Image& image, const Image& reference,
                           const Image* reference_variance) {
  check_sizes(image, reference);
  if (reference_variance) check_sizes(*reference_variance, reference);
  const size_t n = image.pixel_count();
  // Per pixel: its uncorrected relative error (for ranking) and its corrected relMSE term.
  std::vector<std::pair<double, double>> rel(n);
  double sum_mse = 0, sum_rel = 0, sum_mrse = 0;
  for (size_t i = 0; i < n; ++i) {
    double raw = 0, corrected = 0;
    for (int c = 0; c < 3; ++c) {
      const double ref = reference[i][c];
      const double d = double(image[i][c]) - ref;
      const double sq = d * d - (reference_variance ? double((*reference_variance)[i][c]) : 0.0);
      const double rel_denominator = ref * ref + kRelMseEpsilon;
      raw += d * d / rel_denominator;
      corrected += sq / rel_denominator;
      sum_mse += sq;
      sum_mrse += sq / ((ref + kMrseEpsilon) * (ref + kMrseEpsilon));
    }
    // NaN pixels count as the worst, so they are dropped first.
    rel[i] = {std::isnan(raw) ? std::numeric_limits<double>::infinity() : raw, corrected};
    sum_rel += corrected;
  }
  ErrorMetrics m;
  const double values = 3.0 * double(n);
  m.mse = sum_mse / values;
  m.relmse = sum_rel / values;
  m.mrse = sum_mrse / values;
  const size_t keep = n - size_t(std::floor(double(n) * kTrimmedFraction));
  std::nth_element(rel.begin(), rel.begin() + ptrdiff_t(keep - 1), rel.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  double kept = 0;
  for (size_t i = 0; i < keep; ++i) kept += rel[i].second;
  m.trimmed_relmse = kept / (3.0 * double(keep));
  return m;
}

double metric_by_name(const ErrorMetrics& m, const std::string& name) {
  if (name == "relmse") return m.relmse;
  if (name == "trimmed_relmse") return m.trimmed_relmse;
  if (name == "mrse") return m.mrse;
  if (name == "mse") return m.mse;
  fail("unknown metric '{}' (valid: relmse, trimmed_relmse, mrse, mse)", name);
}

std::string metric_label(const std::string& name) {
  if (name == "relmse") return "relMSE";
  if (name == "trimmed_relmse") return "trimmed relMSE";
  if (name == "mrse") return "MRSE";
  if (name == "mse") return "MSE";
  fail("unknown metric '{}' (valid: relmse, trimmed_relmse, mrse, mse)", name);
}

double mse(const Image& image, const Image& reference) {
  return error_metrics(image, reference).mse;
}
double relmse(const Image& image, const Image& reference) {
  return error_metrics(image, reference).relmse;
}
double trimmed_relmse(const Image& image, const Image& reference) {
  return error_metrics(image, reference).trimmed_relmse;
}
double mrse(const Image& image, const Image& reference) {
  return error_metrics(image, reference).mrse;
}

Image variance_of_mean_of_halves(const Image& a, const Image& b) {
  check_sizes(a, b);
  Image v(a.width(), a.height());
  for (size_t i = 0; i < a.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double d = double(a[i][c]) - b[i][c];
      v[i][c] = float(d * d / 4);
    }
  return v;
}

std::vector<float> relative_error_map(const Image& image, const Image& reference) {
  check_sizes(image, reference);
  std::vector<float> map(image.pixel_count());
  for (size_t i = 0; i < map.size(); ++i) {
    double s = 0;
    for (int c = 0; c < 3; ++c) s += relative_squared_error(image[i][c], reference[i][c]);
    map[i] = float(s / 3.0);
  }
  return map;
}

Image grey_image(const std::vector<float>& values, int width, int height) {
  if (values.size() != size_t(width) * size_t(height))
    fail("grey_image: {} values for a {}x{} image", values.size(), width, height);
  Image img(width, height);
  for (size_t i = 0; i < values.size(); ++i) img[i] = Rgb(values[i]);
  return img;
}

Rgb8 colour_scale(float t) {
  // Stops of the viridis scale (dark blue-violet -> teal -> yellow), interpolated linearly.
  static constexpr std::array<std::array<float, 3>, 9> stops = {{{68, 1, 84},
                                                                 {71, 44, 122},
                                                                 {59, 81, 139},
                                                                 {44, 113, 142},
                                                                 {33, 144, 141},
                                                                 {39, 173, 129},
                                                                 {92, 200, 99},
                                                                 {170, 220, 50},
                                                                 {253, 231, 37}}};
  if (!(t > 0)) t = 0;  // also NaN
  t = std::min(t, 1.0f) * float(stops.size() - 1);
  const size_t i = std::min(size_t(t), stops.size() - 2);
  const float f = t - float(i);
  auto channel = [&](int c) {
    return uint8_t(std::lround(stops[i][c] + f * (stops[i + 1][c] - stops[i][c])));
  };
  return {channel(0), channel(1), channel(2)};
}

std::vector<uint8_t> false_colour(const std::vector<float>& values, float lo, float hi) {
  if (!(lo > 0) || !(hi > lo)) fail("false_colour: needs 0 < lo < hi (got {}, {})", lo, hi);
  const double log_lo = std::log(double(lo)), inv_range = 1.0 / (std::log(double(hi)) - log_lo);
  std::vector<uint8_t> rgb(3 * values.size());
  for (size_t i = 0; i < values.size(); ++i) {
    const float v = values[i];
    const float t = v > 0 ? float((std::log(double(v)) - log_lo) * inv_range) : 0;  // +inf -> 1
    const Rgb8 c = colour_scale(t);
    rgb[3 * i] = c.r;
    rgb[3 * i + 1] = c.g;
    rgb[3 * i + 2] = c.b;
  }
  return rgb;
}

double quantile(std::vector<float> values, double q) {
  std::erase_if(values, [](float v) { return !std::isfinite(v); });
  if (values.empty()) return 0;
  const size_t k = std::min(values.size() - 1,
                            size_t(std::clamp(q, 0.0, 1.0) * double(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(k), values.end());
  return values[k];
}

double reference_noise_relmse(const Image& ref, const Image& variance) {
  double sum = 0;
  for (size_t i = 0; i < ref.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c)
      sum += double(variance[i][c]) / (double(ref[i][c]) * ref[i][c] + kRelMseEpsilon);
  return sum / (3.0 * double(ref.pixel_count()));
}

}  // namespace rll
