// Image error metrics against a reference (MSE, relMSE), per-pixel error maps and their
// false-colour rendering for reports.
#pragma once

#include <cstdint>
#include <vector>

#include "rll/core/image.h"

namespace rll {

// The constant in relMSE's denominator, (x - ref)^2 / (ref^2 + eps): it keeps black pixels of
// the reference from dominating the mean.
inline constexpr double kRelMseEpsilon = 0.01;

// Mean over pixels and channels of (x - ref)^2. Throws rll::Error when the sizes differ.
double mse(const Image& image, const Image& reference);
// Mean over pixels and channels of (x - ref)^2 / (ref^2 + kRelMseEpsilon).
double relmse(const Image& image, const Image& reference);
// The share of pixels trimmed relMSE leaves out: the worst 0.1% by their own relative error.
inline constexpr double kTrimmedFraction = 0.001;
// relMSE with the worst kTrimmedFraction of pixels (by their own relative error, the
// relative_error_map) left out, so that a few fireflies cannot decide a comparison alone.
double trimmed_relmse(const Image& image, const Image& reference);
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
