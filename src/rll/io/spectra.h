// pbrt-v4's named spectra and blackbodies, reduced to linear sRGB triples (rll renders in RGB).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "rll/core/math.h"

namespace rll {

// The RGB triple of one of pbrt-v4's named spectra ("metal-Cu-eta", "metal-Au-k", ...), or
// nullopt for a name rll does not know. Where the numbers come from is in spectra.cpp.
std::optional<Rgb> named_spectrum_rgb(std::string_view name);
// The names named_spectrum_rgb knows, for messages: "metal-{Cu,Au,...}-{eta,k}".
std::string named_spectrum_names();

// The colour of a blackbody at `kelvin`, in linear sRGB with luminance 1 (pbrt-v4 normalizes
// a blackbody emitter to one nit before `scale`).
Rgb blackbody_rgb(double kelvin);

}  // namespace rll
