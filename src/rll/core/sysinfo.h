// Process facts for statistics: peak resident memory.
#pragma once

#include <cstddef>

namespace rll {

// Peak resident set size of this process in bytes (0 where unknown).
size_t peak_rss_bytes();

}  // namespace rll
