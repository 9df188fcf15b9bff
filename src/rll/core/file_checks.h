// Checks of the files rll reads and writes, shared by every command and by the atomic writer:
// no output replaces what is not a regular file (a device, a pipe, a folder, a read-only file),
// no input that is not a regular file is opened, and no file is both an input and an output.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace rll {

// Refuses, naming `what`, a path with a NUL byte: the system's calls end the name there, so
// "victim.exr\0.tmp.exr" would read or replace victim.exr. Every check below starts with it.
void check_path_text(const std::filesystem::path& path, const std::string& what);

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
// room for the temporary written beside it. A symbolic link is judged by its target: refused
// where the target's extension is not the link's (`-o v.exr` linked to notes.txt would replace
// the text with an image), or where the target does not exist and neither does its folder (no
// folder is created through a link: as root, a dangling link could make them anywhere).
void check_output_file(const std::filesystem::path& path, const std::string& what);

// Creates folder `dir` and its missing parents, refusing (naming `what`) where one of them is a
// symbolic link to nothing: no folder is created through a dangling link.
void create_output_folder(const std::filesystem::path& dir, const std::string& what);

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

// The files of one output that must be replaced together or not at all (a scene and the files
// written beside it: a new .mtl beside an old .obj is a broken scene). While a batch is open on
// a thread, the atomic writers (core/image.h) leave each file's temporary in place and hand it to
// the batch; commit() then puts every one in place, or, when one cannot be, puts back what was
// there before; a batch destroyed without commit() (a later write failed) deletes its temporaries
// and changes nothing. Batches do not nest.
class WriteBatch {
 public:
  WriteBatch();
  ~WriteBatch();
  WriteBatch(const WriteBatch&) = delete;
  WriteBatch& operator=(const WriteBatch&) = delete;
  // Renames every temporary over its target; on a failure, restores the targets already
  // replaced and throws rll::Error naming the file that could not be written.
  void commit();
  // For the atomic writers: when a batch is open on this thread, it takes `tmp` (the written
  // temporary of `target`; `shown` names it in messages) and true is returned.
  static bool defer(const std::filesystem::path& tmp, const std::filesystem::path& target,
                    const std::filesystem::path& shown);

 private:
  struct Entry {
    std::filesystem::path tmp, target, shown;
  };
  std::vector<Entry> m_entries;
  bool m_done = false;
};

}  // namespace rll
