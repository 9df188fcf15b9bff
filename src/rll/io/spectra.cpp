// pbrt-v4's named spectra and blackbodies as linear sRGB (see spectra.h).
#include "rll/io/spectra.h"

#include <cmath>
#include <string>

#include "rll/scene/transform.h"

namespace rll {

namespace {

// pbrt-v4's named conductor spectra ("metal-X-eta", "metal-X-k") as RGB. rll has no spectral
// data offline to integrate against sRGB's primaries, so these are published RGB reductions:
// - Cu, Au, Ag, Al, CuZn: the RGB complex indices of refraction tabulated for RGB renderers from
//   the same measured data pbrt's spectra come from (Palik's handbook via Mitsuba's tables), as
//   listed, for example, in the Tungsten renderer's table of complex IORs (Bitterli); these are
//   the values rll used before.
// - MgO and TiO2 are dielectrics (k = 0 through the visible range). eta: MgO from its handbook
//   index (1.7355 at 589 nm) with its weak dispersion (Stephens and Malitson 1952, read at
//   roughly 650 / 550 / 450 nm); TiO2 (rutile, ordinary ray) from DeVore's 1951 fit
//   n^2 = 5.913 + 0.2441 / (lambda^2 - 0.0803), lambda in um, evaluated at 0.65, 0.55 and
//   0.45 um: 2.574, 2.648, 2.813.
struct NamedMetal {
  const char* name;
  Rgb eta, k;
};
constexpr NamedMetal kMetals[] = {
    {"Cu", {0.200438f, 0.924033f, 1.10221f}, {3.91295f, 2.45285f, 2.14219f}},
    {"Au", {0.143119f, 0.374957f, 1.44248f}, {3.98316f, 2.38572f, 1.60322f}},
    {"Ag", {0.155265f, 0.116723f, 0.138342f}, {4.82835f, 3.12225f, 2.14696f}},
    {"Al", {1.65746f, 0.880369f, 0.521229f}, {9.22387f, 6.26952f, 4.837f}},
    {"CuZn", {0.444f, 0.527f, 1.094f}, {3.695f, 2.765f, 1.829f}},
    {"MgO", {1.7337f, 1.7378f, 1.7480f}, {0, 0, 0}},
    {"TiO2", {2.574f, 2.648f, 2.813f}, {0, 0, 0}},
};

}  // namespace

std::optional<Rgb> named_spectrum_rgb(std::string_view name) {
  for (const auto& m : kMetals) {
    if (name == std::string("metal-") + m.name + "-eta") return m.eta;
    if (name == std::string("metal-") + m.name + "-k") return m.k;
  }
  return std::nullopt;
}

std::string named_spectrum_names() {
  std::string s = "metal-{";
  for (const auto& m : kMetals) s += std::string(&m == kMetals ? "" : ",") + m.name;
  return s + "}-{eta,k}";
}

// The CIE 1931 matching functions are the multi-lobe Gaussian fit of Wyman, Sloan and Shirley
// (2013).
Rgb blackbody_rgb(double kelvin) {
  auto g = [](double l, double mu, double s1, double s2) {
    const double t = (l - mu) / (l < mu ? s1 : s2);
    return std::exp(-0.5 * t * t);
  };
  double X = 0, Y = 0, Z = 0;
  for (double l = 360; l <= 830; l += 1) {
    const double lm = l * 1e-9, c = 299792458.0, h = 6.62606957e-34, kb = 1.3806488e-23;
    const double le =
        2 * h * c * c / (std::pow(lm, 5) * (std::exp(h * c / (lm * kb * kelvin)) - 1));
    X += le * (1.056 * g(l, 599.8, 37.9, 31.0) + 0.362 * g(l, 442.0, 16.0, 26.7) -
               0.065 * g(l, 501.1, 20.4, 26.2));
    Y += le * (0.821 * g(l, 568.8, 46.9, 40.5) + 0.286 * g(l, 530.9, 16.3, 31.1));
    Z += le * (1.217 * g(l, 437.0, 11.8, 36.0) + 0.681 * g(l, 459.0, 26.0, 13.8));
  }
  X /= Y;
  Z /= Y;
  Y = 1;
  Rgb c(to_float(3.2406 * X - 1.5372 * Y - 0.4986 * Z),
        to_float(-0.9689 * X + 1.8758 * Y + 0.0415 * Z),
        to_float(0.0557 * X - 0.2040 * Y + 1.0570 * Z));
  return max(c, Rgb(0));
}

}  // namespace rll
