// Checks of the files rll reads and writes, shared by every command and by the atomic writer:
// no output replaces what is not a regular file (a device, a pipe, a folder, a read-only file),
// no input that is not a regular file is opened, and no file is both an input and an output.
#pragma once

#include <filesystem>
#include <string>

namespace rll {

// What a path is, in words ("a FIFO (named pipe)", "a folder", ...), following symbolic links;
// empty when it is a regular file or does not exist.
std::string non_regular_kind(const std::filesystem::path& path);

// Refuses, naming `what` (a flag, or "scene") and the file, an input that exists and is not a
// regular file: reading a FIFO hangs, reading a device may never end. A missing file is left
// to the reader, which says where it looked.
void check_input_file(const std::filesystem::path& path, const std::string& what);

// The file that writing `path` changes: `path` itself, or the file its symbolic links end at
// (written through, never replaced by a file of its own).
std::filesystem::path write_target(const std::filesystem::path& path);

// Refuses, naming `what` and the file, an output path that exists and is not a regular file, or
// that is read-only (by its permission bits, which root's writes ignore), or whose name leaves no
// room for the temporary written beside it.
void check_output_file(const std::filesystem::path& path, const std::string& what);

// Whether `a` and `b` are the same file after following links: device and inode where both
// exist, the canonical paths where one does not.
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

// Creates and removes a file in `dir`, so that a folder that cannot be written is reported
// before the work rather than after it; throws rll::Error starting with `what`.
void check_folder_writable(const std::filesystem::path& dir, const std::string& what);

// The temporary that an atomic write of `target` uses: TARGET.tmp-PID-N beside it.
std::filesystem::path temp_sibling(const std::filesystem::path& target);

// Deletes TARGET.tmp-PID-N files beside `target` (or every NAME.tmp-PID-N in folder `dir`) left
// by rll processes that no longer run. Returns how many were deleted.
int remove_stale_temporaries(const std::filesystem::path& target);
int remove_stale_temporaries_in(const std::filesystem::path& dir);

}  // namespace rll
