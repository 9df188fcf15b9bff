#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "rll/core/error.h"
#include "rll/core/rng.h"
#include "rll/eval/metrics.h"
#include "support/test_support.h"

using namespace rll;

namespace {
// x = [(1,2,3), (0,0,0)], ref = [(1,1,1), (0.1,0,0.2)]: squared errors 0,1,4 and .01,0,.04.
Image two_pixels(Rgb a, Rgb b) {
  Image img(2, 1);
  img[0] = a;
  img[1] = b;
  return img;
}
const Image kImage = two_pixels({1, 2, 3}, {0, 0, 0});
const Image kReference = two_pixels({1, 1, 1}, {0.1f, 0, 0.2f});
}  // namespace

TEST(Metrics, MseByHand) {
  EXPECT_NEAR(mse(kImage, kReference), 5.05 / 6.0, 1e-7);
  EXPECT_EQ(mse(kReference, kReference), 0.0);
}

TEST(Metrics, RelMseByHand) {
  // Pixel 0: (0 + 1 + 4) / (1 + 0.01); pixel 1: .01/.02 + 0/.01 + .04/.05 = 1.3.
  EXPECT_NEAR(relmse(kImage, kReference), (5.0 / 1.01 + 1.3) / 6.0, 1e-6);
  EXPECT_EQ(relmse(kReference, kReference), 0.0);
}

TEST(Metrics, RelMseOfBlackReferenceUsesEpsilon) {
  const Image black(1, 1, Rgb(0));
  const Image grey(1, 1, Rgb(0.1f));
  EXPECT_NEAR(relmse(grey, black), 0.01 / kRelMseEpsilon, 1e-6);
}

TEST(Metrics, ErrorMapAveragesChannelsAndMeansToRelMse) {
  const auto map = relative_error_map(kImage, kReference);
  ASSERT_EQ(map.size(), 2u);
  EXPECT_NEAR(map[0], 5.0 / 1.01 / 3.0, 1e-6);
  EXPECT_NEAR(map[1], 1.3 / 3.0, 1e-6);
  EXPECT_NEAR((map[0] + map[1]) / 2.0, relmse(kImage, kReference), 1e-6);
}

TEST(Metrics, SizeMismatchIsAnError) {
  EXPECT_THROW(mse(Image(2, 1), Image(1, 2)), Error);
  EXPECT_THROW(relmse(Image(2, 2), Image(2, 1)), Error);
  EXPECT_THROW(relative_error_map(Image(3, 1), Image(2, 1)), Error);
  EXPECT_THROW(mse(Image(), Image()), Error);
}

TEST(Metrics, FalseColourEndsAndClamping) {
  // Log scale from 1e-3 to 1e1: 1e-1 is half way.
  const auto rgb = false_colour({1e-3f, 1e1f, 1e-1f, 0.0f, 1e5f, NAN, INFINITY}, 1e-3f, 1e1f);
  ASSERT_EQ(rgb.size(), 21u);
  auto at = [&](int i) { return Rgb8{rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]}; };
  auto same = [](Rgb8 a, Rgb8 b) { return a.r == b.r && a.g == b.g && a.b == b.b; };
  EXPECT_TRUE(same(at(0), colour_scale(0)));
  EXPECT_TRUE(same(at(1), colour_scale(1)));
  EXPECT_TRUE(same(at(2), colour_scale(0.5f)));
  EXPECT_TRUE(same(at(3), colour_scale(0)));  // zero error: the low end
  EXPECT_TRUE(same(at(4), colour_scale(1)));  // clamped
  EXPECT_TRUE(same(at(5), colour_scale(0)));  // NaN
  EXPECT_TRUE(same(at(6), colour_scale(1)));  // +inf
  EXPECT_THROW(false_colour({1.0f}, 0.0f, 1.0f), Error);
}

TEST(Metrics, ColourScaleIsOrderedDarkToBright) {
  float prev = -1;
  for (int i = 0; i <= 20; ++i) {
    const Rgb8 c = colour_scale(i / 20.0f);
    const float lum = 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
    EXPECT_GT(lum, prev) << "at t = " << i / 20.0f;
    prev = lum;
  }
}

TEST(Metrics, Quantile) {
  EXPECT_EQ(quantile({5, 1, 4, 2, 3}, 0.5), 3);
  EXPECT_EQ(quantile({5, 1, 4, 2, 3}, 0.0), 1);
  EXPECT_EQ(quantile({5, 1, 4, 2, 3}, 1.0), 5);
  EXPECT_EQ(quantile({NAN, 2, INFINITY}, 0.5), 2);
  EXPECT_EQ(quantile({}, 0.5), 0);
}

TEST(Metrics, GreyImage) {
  const Image g = grey_image({0.5f, 2.0f}, 2, 1);
  EXPECT_EQ(g[1].x, 2.0f);
  EXPECT_EQ(g[1].z, 2.0f);
  EXPECT_THROW(grey_image({1.0f}, 2, 1), Error);
}

namespace {
// Trimmed relMSE leaves out the worst 0.1% of pixels: one firefly among 2000 pixels decides
// relMSE but not the trimmed figure, which then equals the relMSE of the remaining pixels.
TEST(Metrics, TrimmedRelMseDropsTheWorstTenthOfAPercent) {
  rll::Image ref(50, 30), img(50, 30);  // 1500 pixels: the worst one is left out
  for (size_t i = 0; i < ref.pixel_count(); ++i) {
    ref[i] = rll::Rgb(1.0f);
    img[i] = rll::Rgb(i % 2 ? 1.1f : 0.9f);  // relative squared error 0.01 / 1.01 everywhere
  }
  const double base = 0.01 / 1.01;
  EXPECT_NEAR(rll::trimmed_relmse(img, ref), base, 1e-6);
  img[777] = rll::Rgb(1000.0f);  // a firefly
  img[1255] = rll::Rgb(1.5f);    // a moderate outlier: within the 99.9% kept
  EXPECT_GT(rll::relmse(img, ref), 100 * base);
  const double kept = (1498 * base + 0.25 / 1.01) / 1499;
  EXPECT_NEAR(rll::trimmed_relmse(img, ref), kept, 1e-6);
}
}  // namespace

TEST(Metrics, MrseByHand) {
  // Pixel 0: (0 + 1 + 4) / 1.01^2; pixel 1: .01/.11^2 + 0/.01^2 + .04/.21^2.
  const double expected = (5.0 / (1.01 * 1.01) + 0.01 / (0.11 * 0.11) + 0.04 / (0.21 * 0.21)) / 6.0;
  EXPECT_NEAR(mrse(kImage, kReference), expected, 1e-5);
  const ErrorMetrics m = error_metrics(kImage, kReference);
  EXPECT_NEAR(m.mrse, expected, 1e-5);
  EXPECT_NEAR(m.relmse, relmse(kImage, kReference), 1e-12);
  EXPECT_NEAR(m.mse, 5.05 / 6.0, 1e-7);
  EXPECT_EQ(metric_by_name(m, "mrse"), m.mrse);
  EXPECT_THROW(metric_by_name(m, "psnr"), Error);
}

TEST(Metrics, SubtractedVarianceComesOffEverySquaredDifference) {
  // Variance 0.5 in every channel of pixel 0 and 0 in pixel 1: MSE drops by 0.5 * 3 / 6.
  Image var(2, 1, Rgb(0));
  var[0] = Rgb(0.5f);
  const ErrorMetrics m = error_metrics(kImage, kReference, &var);
  EXPECT_NEAR(m.mse, (5.05 - 1.5) / 6.0, 1e-7);
  EXPECT_NEAR(m.relmse, ((5.0 - 1.5) / 1.01 + 1.3) / 6.0, 1e-6);
  EXPECT_NEAR(m.mrse, mrse(kImage, kReference) - 1.5 / (1.01 * 1.01) / 6.0, 1e-5);
}

TEST(Metrics, HalvesVarianceIsQuarterOfTheSquaredDifference) {
  const Image a = two_pixels({1, 2, 3}, {0, 0, 0});
  const Image b = two_pixels({1, 0, 3}, {0, 0, 4});
  const Image v = variance_of_mean_of_halves(a, b);
  EXPECT_EQ(v[0].y, 1.0f);
  EXPECT_EQ(v[1].z, 4.0f);
  EXPECT_EQ(v[0].x, 0.0f);
}

// A known image, a reference that is the known image plus noise (the mean of two noisy halves),
// and a render with its own, known error: the noise-corrected errors recover the render's error
// against the noise-free image, where the uncorrected ones are inflated by the reference's noise.
// (The relative metrics divide by the noisy reference: a bias of order (sigma_ref / ref)^2 that
// the correction leaves, 0.5% here, as in a reference with a few hundred samples per pixel.)
TEST(Metrics, NoiseCorrectionRecoversTheErrorAgainstTheTrueImage) {
  const int w = 256, h = 256;
  Image truth(w, h), render(w, h), half_a(w, h), half_b(w, h);
  Pcg32 rng(7);
  auto gauss = [&] {  // Box-Muller
    const double u1 = std::max(1e-12, rng.next_double()), u2 = rng.next_double();
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
  };
  const double sigma_render = 0.05, sigma_half = 0.05;
  for (size_t i = 0; i < truth.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double t = 0.5 + rng.next_double();
      truth[i][c] = float(t);
      render[i][c] = float(t + sigma_render * gauss());
      half_a[i][c] = float(t + sigma_half * gauss());
      half_b[i][c] = float(t + sigma_half * gauss());
    }
  Image reference(w, h);
  for (size_t i = 0; i < reference.pixel_count(); ++i)
    reference[i] = (half_a[i] + half_b[i]) * 0.5f;
  const Image var = variance_of_mean_of_halves(half_a, half_b);
  const ErrorMetrics exact = error_metrics(render, truth);
  const ErrorMetrics raw = error_metrics(render, reference);
  const ErrorMetrics corrected = error_metrics(render, reference, &var);
  // The reference's variance (0.05^2 / 2) is half the render's (0.05^2): raw is ~1.5x too high.
  for (const char* name : kMetricNames) {
    const double e = metric_by_name(exact, name), r = metric_by_name(raw, name),
                 c = metric_by_name(corrected, name);
    EXPECT_GT(r / e, 1.4) << name;
    EXPECT_NEAR(c / e, 1.0, 0.04) << name;
  }
}

// What `rll error` and `rll compare` both refuse to measure with, and the message naming the
// file, the pixel and the value.
TEST(MeasuredImages, AreLinearFiniteNonNegativeRgbFiles) {
  rll::test::TempDir dir;
  Image good(4, 2, Rgb(0.5f));
  write_image(dir / "good.exr", good);
  EXPECT_EQ(read_measured_image(dir / "good.exr", MeasuredRole::reference)[3], Rgb(0.5f));
  auto refusal = [&](const std::string& name, const Image& image, MeasuredRole role) {
    write_image(dir / name, image);
    return rll::test::error_of([&] { read_measured_image(dir / name, role); });
  };
  Image nan = good;
  nan.at(3, 1).y = std::numeric_limits<float>::quiet_NaN();
  rll::test::expect_mentions(
      refusal("nan.exr", nan, MeasuredRole::image),
      {"image '", "nan.exr'", "NaN", "1 of its values", "nan in channel G of pixel (3, 1)"});
  Image negative = good;
  negative.at(1, 0).x = -0.5f;
  negative.at(2, 1).z = -1.0f;
  rll::test::expect_mentions(refusal("neg.exr", negative, MeasuredRole::reference),
                             {"reference '", "neg.exr'", "2 of its values",
                              "-0.5 in channel R of pixel (1, 0)", "non-negative"});
  Image inf = good;
  inf[0].z = std::numeric_limits<float>::infinity();
  rll::test::expect_mentions(
      refusal("var.exr", inf, MeasuredRole::reference_variance),
      {"reference variance '", "var.exr'", "inf in channel B of pixel (0, 0)"});
  rll::test::expect_mentions(refusal("ldr.png", good, MeasuredRole::reference),
                             {"reference '", "ldr.png'", "8-bit", ".exr"});
  // The same checks for an image in memory (a cached reference).
  rll::test::expect_mentions(rll::test::error_of([&] {
                               check_measured_pixels(nan, "cache/x.exr", MeasuredRole::reference);
                             }),
                             {"reference 'cache/x.exr'", "pixel (3, 1)"});
  EXPECT_NO_THROW(check_measured_pixels(good, "good.exr", MeasuredRole::reference));
}
