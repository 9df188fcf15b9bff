// Encodings written once for every layer: PNG files in memory (write_image's .png, the reports'
// figures), base64 for data URIs (the reports, glTF's embedded buffer), and escaping text for
// HTML and SVG.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace rll {

// An 8-bit image (1 or 3 channels, rows top to bottom) as the bytes of a PNG file.
std::string png_bytes(const std::vector<uint8_t>& pixels, int width, int height, int channels);
// Standard base64 (RFC 4648) with padding.
std::string base64(const std::string& bytes);
// Text safe inside HTML/XML elements and quoted attributes (& < > " ' escaped).
std::string escape_markup(const std::string& text);

}  // namespace rll
