// libFuzzer target for the OBJ and MTL parsers (see fuzz_input.h for how one input holds both;
// `make fuzz` runs it).
#include <cstddef>
#include <cstdint>

#include "fuzz_input.h"
#include "rll/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    rll::fuzz::parse_untrusted(rll::fuzz::Format::Obj,
                               std::string_view(reinterpret_cast<const char*>(data), size));
  } catch (const rll::Error&) {
    // a clean rejection
  }
  return 0;
}
