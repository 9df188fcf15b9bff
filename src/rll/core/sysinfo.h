// Process facts for statistics: peak resident memory.
#pragma once

#include <cstddef>

namespace rll {

// Peak resident set size of this process in bytes (0 where unknown).
size_t peak_rss_bytes();
// Starts a new peak at the current resident size (Linux /proc/self/clear_refs), so that
// peak_rss_bytes() afterwards measures one phase of the program; false where unsupported.
bool reset_peak_rss();

}  // namespace rll
