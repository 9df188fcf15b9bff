// Process and machine facts for statistics and reports: peak resident memory, the CPU and memory
// of the machine, the commit rll was built from.
#pragma once

#include <cstddef>
#include <string>

namespace rll {

// Peak resident set size of this process in bytes (0 where unknown).
size_t peak_rss_bytes();
// The memory this process can expect to allocate: the machine's physical memory, or less where
// a resource limit (RLIMIT_AS, RLIMIT_DATA) says so. 0 where unknown.
size_t usable_memory_bytes();
// Starts a new peak at the current resident size (Linux /proc/self/clear_refs), so that
// peak_rss_bytes() afterwards measures one phase of the program; false where unsupported.
bool reset_peak_rss();

// The machine in one line, e.g. "AMD EPYC 7B13, 16 logical cores, 125.8 GiB": the CPU model
// from /proc/cpuinfo ("unknown CPU" where absent), the logical cores this process may use and
// the physical memory.
std::string machine_description();

// The commit rll was built from: `git rev-parse --short HEAD` at configure time, with "-dirty"
// when the working tree had changes then, or "unknown" when git was unavailable.
std::string build_commit();

}  // namespace rll
