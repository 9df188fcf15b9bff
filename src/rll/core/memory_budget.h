// The one memory budget for what input files ask rll to allocate (inflated data, buffers,
// geometry, the acceleration structure): every reader checks a size read from a file against it
// before allocating, so that a small file cannot claim gigabytes.
#pragma once

#include <cstddef>
#include <string>

namespace rll {

// The bytes a scene load may use: 80% of the memory this process may use (usable_memory_bytes(),
// as the RLL cell table's check), 8 GiB where that is unknown, or what set_memory_budget_bytes()
// set.
size_t memory_budget_bytes();
// Overrides the budget (tests and fuzz targets use a small one); 0 restores the default.
void set_memory_budget_bytes(size_t bytes);

// Throws rll::Error "WHAT needs N GiB, more than the M GiB budget ..." when `bytes` exceed the
// budget. A double, so that a product of claimed counts cannot wrap around.
void check_memory_budget(double bytes, const std::string& what);

// "the 18.4 GiB a scene may use (80% of the memory this process may use)": the budget for messages.
std::string memory_budget_phrase();
// "1.5 GiB", "12.0 MiB", "512 bytes", "2.0 TiB", "more than 1 PiB": a size for messages.
std::string format_bytes(double bytes);

}  // namespace rll
