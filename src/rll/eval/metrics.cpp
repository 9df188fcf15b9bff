#include "rll/eval/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "rll/core/error.h"

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

}  // namespace

double mse(const Image& image, const Image& reference) {
  check_sizes(image, reference);
  double sum = 0;
  for (size_t i = 0; i < image.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double d = double(image[i][c]) - reference[i][c];
      sum += d * d;
    }
  return sum / (3.0 * double(image.pixel_count()));
}

double relmse(const Image& image, const Image& reference) {
  check_sizes(image, reference);
  double sum = 0;
  for (size_t i = 0; i < image.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) sum += relative_squared_error(image[i][c], reference[i][c]);
  return sum / (3.0 * double(image.pixel_count()));
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

double trimmed_relmse(const Image& image, const Image& reference) {
  std::vector<float> map = relative_error_map(image, reference);
  const size_t drop = size_t(std::floor(double(map.size()) * kTrimmedFraction));
  const size_t keep = map.size() - drop;
  if (keep == 0) return 0;
  // NaN pixels count as the worst, so they are dropped first.
  for (auto& v : map)
    if (std::isnan(v)) v = std::numeric_limits<float>::infinity();
  std::nth_element(map.begin(), map.begin() + ptrdiff_t(keep - 1), map.end());
  double sum = 0;
  for (size_t i = 0; i < keep; ++i) sum += map[i];
  return sum / double(keep);
}

double quantile(std::vector<float> values, double q) {
  std::erase_if(values, [](float v) { return !std::isfinite(v); });
  if (values.empty()) return 0;
  const size_t k = std::min(values.size() - 1,
                            size_t(std::clamp(q, 0.0, 1.0) * double(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(k), values.end());
  return values[k];
}

}  // namespace rll
