// Image error metrics against a reference (MSE, relMSE, trimmed relMSE, MRSE), with the
// reference's own noise subtracted when its variance is known, per-pixel error maps and their
// false-colour rendering for reports.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "rll/core/image.h"

namespace rll {

// The constant in relMSE's denominator, (x - ref)^2 / (ref^2 + eps): it keeps black pixels of
// the reference from dominating the mean.
inline constexpr double kRelMseEpsilon = 0.01;

// The constant of MRSE as pbrt-v4 defines it: (x - ref)^2 / (ref + eps)^2.
inline constexpr double kMrseEpsilon = 0.01;
// The share of pixels trimmed relMSE leaves out: the worst 0.1% by their own relative error.
inline constexpr double kTrimmedFraction = 0.001;

// The four errors of an image against a reference, each a mean over pixels and channels:
//   mse            (x - ref)^2
//   relmse         (x - ref)^2 / (ref^2 + kRelMseEpsilon)
//   trimmed_relmse relMSE with the worst kTrimmedFraction of pixels (ranked by their own
//                  relative error, the relative_error_map) left out, so that a few fireflies
//                  cannot decide a comparison alone
//   mrse           (x - ref)^2 / (ref + kMrseEpsilon)^2
// With `reference_variance` (per pixel and channel, the variance of the reference's value),
// every squared difference has it subtracted: for an image independent of the reference,
// E[(x - ref)^2] = E[(x - truth)^2] + Var(ref), so the result estimates the error against the
// noise-free image without bias. It can then come out negative when the image is as close to
// the truth as the reference's noise lets one tell. Pixels are still ranked for trimming by their
// uncorrected error. Throws rll::Error when the sizes differ.
struct ErrorMetrics {
  double mse = 0, relmse = 0, trimmed_relmse = 0, mrse = 0;
};
ErrorMetrics error_metrics(const Image& image, const Image& reference,
                           const Image* reference_variance = nullptr);
// What an image is to a measurement, for its checks and its messages.
enum class MeasuredRole { image, reference, reference_variance };
// Reads an image that is measured against a reference, or is one, or is its variance, and
// checks it as both `rll error` and `rll compare` do, with the same message naming the file:
// a linear high-dynamic-range file (.exr or .hdr: an 8-bit format holds sRGB values clamped at
// 1, not radiance), R, G and B (a Y-only EXR is refused: see LuminanceOnly), and every pixel
// finite and non-negative (a NaN would make every error NaN; radiance and variance are never
// negative). Throws rll::Error otherwise.
Image read_measured_image(const std::filesystem::path& path, MeasuredRole role);
// The pixel checks of read_measured_image, for an image already in memory; `file` names it.
void check_measured_pixels(const Image& image, const std::string& file, MeasuredRole role);

// Names of the metrics as they appear in summary.json, --plot-metric and tables.
inline constexpr const char* kMetricNames[] = {"relmse", "trimmed_relmse", "mrse", "mse"};
// The metric of that name; throws rll::Error listing the names for an unknown one.
double metric_by_name(const ErrorMetrics& m, const std::string& name);
// How the metric of that name is written for readers ("relMSE", "trimmed relMSE", ...).
std::string metric_label(const std::string& name);

// Single metrics, without noise subtraction (see error_metrics).
double mse(const Image& image, const Image& reference);
double relmse(const Image& image, const Image& reference);
double trimmed_relmse(const Image& image, const Image& reference);
double mrse(const Image& image, const Image& reference);

// The variance of the mean of two independent, equally sampled renders a and b, per pixel and
// channel: (a - b)^2 / 4 is an unbiased estimate of Var((a + b) / 2).
Image variance_of_mean_of_halves(const Image& a, const Image& b);
// The reference's own noise, in relMSE units: the mean of Var(ref) / (ref^2 + kRelMseEpsilon).
double reference_noise_relmse(const Image& ref, const Image& variance);

// Per pixel, the mean over channels of (x - ref)^2 / (ref^2 + kRelMseEpsilon): its mean over
// pixels is relmse(image, reference).
std::vector<float> relative_error_map(const Image& image, const Image& reference);
// A one-channel map as a grey image (for .exr output).
Image grey_image(const std::vector<float>& values, int width, int height);

struct Rgb8 {
  uint8_t r = 0, g = 0, b = 0;
};
// The colour scale of error maps (perceptually ordered, dark = low) at t in [0, 1].
Rgb8 colour_scale(float t);
// Maps values to colour_scale on a logarithmic axis from lo (t = 0) to hi (t = 1), clamping
// outside; values <= 0 and NaN map to t = 0. Returns RGB triples, 3 bytes per value.
std::vector<uint8_t> false_colour(const std::vector<float>& values, float lo, float hi);

// The q-quantile (q in [0, 1]) of the finite values, by partial sort of a copy; 0 if none.
double quantile(std::vector<float> values, double q);

}  // namespace rll
