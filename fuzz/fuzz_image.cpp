// libFuzzer target for the image decoder (stb_image's PNG, JPEG, HDR and other formats), as
// glTF images and textures are decoded (see fuzz_input.h; `make fuzz` runs it).
#include <cstddef>
#include <cstdint>

#include "fuzz_input.h"
#include "rll/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    rll::fuzz::parse_untrusted(rll::fuzz::Format::Image,
                               std::string_view(reinterpret_cast<const char*>(data), size));
  } catch (const rll::Error&) {
    // a clean rejection
  }
  return 0;
}
