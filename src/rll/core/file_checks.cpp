#include "rll/core/file_checks.h"

#include <fmt/format.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "rll/core/error.h"
#include "rll/core/params.h"
#include "rll/core/paths.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

std::string kind_of(mode_t mode) {
  if (S_ISREG(mode)) return {};
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// The longest ".tmp-PID-N" that temp_sibling appends.
constexpr size_t kTempSuffixMax = 5 + 10 + 1 + 10;

// The PID of NAME.tmp-PID-N when `name` is one of temp_sibling's names for `stem` (any stem when
// `stem` is empty); 0 otherwise.
long temporary_pid(const std::string& name, const std::string& stem) {
  const size_t at = name.rfind(".tmp-");
  if (at == std::string::npos || (!stem.empty() && name.compare(0, at, stem) != 0) ||
      (!stem.empty() && at != stem.size()))
    return 0;
  const size_t dash = name.find('-', at + 5);
  if (dash == std::string::npos || dash + 1 == name.size()) return 0;
  char* end = nullptr;
  const long pid = std::strtol(name.c_str() + at + 5, &end, 10);
  if (end != name.c_str() + dash || pid <= 0) return 0;
  for (size_t i = dash + 1; i < name.size(); ++i)
    if (!std::isdigit(static_cast<unsigned char>(name[i]))) return 0;
  return pid;
}

int remove_temporaries(const fs::path& dir, const std::string& stem) {
  std::error_code ec;
  const fs::path folder = dir.empty() ? fs::path(".") : dir;
  if (!fs::is_directory(folder, ec)) return 0;
  int removed = 0;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const long pid = temporary_pid(entry.path().filename().string(), stem);
    // A running process may still be writing it (ours included); kill() answers EPERM for a
    // process of another user, which is not ours to judge either.
    if (pid == 0 || pid == long(::getpid()) || ::kill(pid_t(pid), 0) == 0 || errno != ESRCH)
      continue;
    if (entry.is_regular_file(ec) && fs::remove(entry.path(), ec)) ++removed;
  }
  return removed;
}

}  // namespace

void check_path_text(const fs::path& path, const std::string& what) {
  const std::string& text = path.native();
  const size_t nul = text.find('\0');
  if (nul == std::string::npos) return;
  fail("{} '{}': the path holds a NUL byte, where the system would end it (at '{}'): refusing it",
       what, shown_text(text, 256), shown_text(text.substr(0, nul), 256));
}

std::string non_regular_kind(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return {};
  return kind_of(st.st_mode);
}

void check_input_file(const fs::path& path, const std::string& what) {
  check_path_text(path, what);
  const std::string kind = non_regular_kind(path);
  if (!kind.empty())
    fail("{} '{}' is {}, not a file: refusing to read it", what, path.string(), kind);
}

fs::path write_target(const fs::path& path) {
  check_path_text(path, "output");
  fs::path p = path;
  // A loop of links is reported by the write itself; 40 is the kernel's own limit.
  for (int i = 0; i < 40; ++i) {
    std::error_code ec;
    if (!fs::is_symlink(p, ec)) return p;
    const fs::path link = fs::read_symlink(p, ec);
    if (ec) return p;
    p = link.is_absolute() ? link : p.parent_path() / link;
  }
  fail("'{}': too many levels of symbolic links", path.string());
}

void check_output_file(const fs::path& path, const std::string& what) {
  check_path_text(path, what);
  const fs::path target = write_target(path);
  const std::string via =
      target == path ? std::string() : fmt::format(" (the target of link '{}')", path.string());
  struct stat st {};
  const bool exists = ::stat(target.c_str(), &st) == 0;
  if (target != path) {
    // A link is judged by the file it would change: its name says what that file is.
    const std::string ext = lower_extension(path), target_ext = lower_extension(target);
    auto kind = [](const std::string& e) { return e.empty() ? std::string("no extension") : e; };
    if (ext != target_ext)
      fail(
          "{} '{}' is a symbolic link to '{}', a file of another kind ({} rather than {}): "
          "refusing to write through it (remove the link, or choose another output)",
          what, path.string(), target.string(), kind(target_ext), kind(ext));
    std::error_code ec;
    if (!exists && target.has_parent_path() && !fs::is_directory(target.parent_path(), ec))
      fail(
          "{} '{}' is a symbolic link to '{}', in folder '{}', which does not exist: refusing to "
          "create folders through a link (create the folder, or remove the link)",
          what, path.string(), target.string(), target.parent_path().string());
  }
  if (exists) {
    const std::string kind = kind_of(st.st_mode);
    if (!kind.empty())
      fail("{} '{}'{} is {}, not a file: refusing to replace it", what, target.string(), via, kind);
    // Root may write any file: the permission bits say what its owner meant.
    if ((st.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH)) == 0 || ::access(target.c_str(), W_OK) != 0)
      fail(
          "{} '{}'{} is read-only: refusing to replace it (make it writable or choose another "
          "output)",
          what, target.string(), via);
  }
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  long name_max = ::pathconf(dir.c_str(), _PC_NAME_MAX);
  if (name_max <= 0) name_max = NAME_MAX;
  const size_t name_size = target.filename().string().size();
  if (name_size + kTempSuffixMax > size_t(name_max))
    fail("{} '{}': the file name is {} bytes long; rll writes names of at most {} bytes there",
         what, shown_text(path.string(), 256), name_size, size_t(name_max) - kTempSuffixMax);
  std::error_code ec;
  if (fs::absolute(target, ec).string().size() + kTempSuffixMax >= PATH_MAX)
    fail("{} '{}': the path is too long (at most {} bytes)", what, shown_text(path.string(), 256),
         PATH_MAX - 1 - kTempSuffixMax);
}

void create_output_folder(const fs::path& dir, const std::string& what) {
  check_path_text(dir, what);
  std::error_code ec;
  if (dir.empty() || fs::is_directory(dir, ec)) return;
  // The missing folders from the deepest up to the first that exists: one of them that is a link
  // to nothing would have its target created (a link is followed as a folder is made in it).
  for (fs::path p = dir; !p.empty(); p = p.parent_path()) {
    if (fs::is_symlink(p, ec) && !fs::exists(p, ec))
      fail(
          "{}: '{}' is a symbolic link to '{}', which does not exist: refusing to create folders "
          "through a link (create its target, or remove the link)",
          what, p.string(), fs::read_symlink(p, ec).string());
    if (fs::exists(p, ec) || p == p.parent_path()) break;
  }
  if (!fs::create_directories(dir, ec) && !fs::is_directory(dir, ec))
    fail("{}: cannot create folder '{}': {}", what, dir.string(),
         ec ? ec.message() : "a file of that name is in the way");
}

bool same_file(const fs::path& a, const fs::path& b) {
  struct stat sa {
  }, sb{};
  if (::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0)
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  std::error_code ea, eb;
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ea), ea);
  const fs::path cb = fs::weakly_canonical(fs::absolute(b, eb), eb);
  return !ea && !eb && ca == cb;
}

void check_folder_writable(const fs::path& dir, const std::string& what) {
  const fs::path probe =
      (dir.empty() ? fs::path(".") : dir) / fmt::format(".rll-write-test-{}", ::getpid());
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  int err = f ? 0 : errno;
  if (f) {
    if (std::fputc('x', f) == EOF) err = errno;
    if (std::fclose(f) != 0 && !err) err = errno;
    std::error_code ec;
    fs::remove(probe, ec);
  }
  if (err)
    fail("{}: cannot write in folder '{}': {}", what, dir.empty() ? "." : dir.string(),
         std::strerror(err));
}

fs::path temp_sibling(const fs::path& target) {
  static std::atomic<unsigned> counter{0};
  fs::path tmp = target;
  tmp += fmt::format(".tmp-{}-{}", ::getpid(), counter++);
  return tmp;
}

namespace {
thread_local WriteBatch* g_batch = nullptr;
}  // namespace

WriteBatch::WriteBatch() {
  if (g_batch) fail("internal error: a batch of writes opened inside another");
  g_batch = this;
}

WriteBatch::~WriteBatch() {
  if (g_batch == this) g_batch = nullptr;
  if (m_done) return;
  std::error_code ec;
  for (const Entry& e : m_entries) fs::remove(e.tmp, ec);
}

bool WriteBatch::defer(const fs::path& tmp, const fs::path& target, const fs::path& shown) {
  if (!g_batch) return false;
  for (Entry& e : g_batch->m_entries)
    if (e.target == target) {  // written again: the later bytes win, as without a batch
      std::error_code ec;
      fs::remove(e.tmp, ec);
      e = {tmp, target, shown};
      return true;
    }
  g_batch->m_entries.push_back({tmp, target, shown});
  return true;
}

void WriteBatch::commit() {
  if (g_batch == this) g_batch = nullptr;
  m_done = true;
  std::error_code ec;
  // Each present target is first linked to a temporary name beside it (no data is copied), so
  // that a rename failing after others succeeded can put every earlier file back. Where the file
  // system has no hard links, that file is replaced without a way back.
  std::vector<fs::path> backups(m_entries.size());
  std::vector<bool> existed(m_entries.size(), false);
  for (size_t i = 0; i < m_entries.size(); ++i) {
    struct stat st {};
    existed[i] = ::lstat(m_entries[i].target.c_str(), &st) == 0;
    if (existed[i] && S_ISREG(st.st_mode)) {
      const fs::path backup = temp_sibling(m_entries[i].target);
      if (::link(m_entries[i].target.c_str(), backup.c_str()) == 0) backups[i] = backup;
    }
  }
  for (size_t i = 0; i < m_entries.size(); ++i) {
    fs::rename(m_entries[i].tmp, m_entries[i].target, ec);
    if (!ec) continue;
    const std::string why = ec.message();
    for (size_t j = 0; j < m_entries.size(); ++j) {
      std::error_code ignored;
      if (j < i && !backups[j].empty())
        fs::rename(backups[j], m_entries[j].target, ignored);
      else if (j < i && !existed[j])
        fs::remove(m_entries[j].target, ignored);
      else if (j >= i)
        fs::remove(m_entries[j].tmp, ignored);
      if (j >= i && !backups[j].empty()) fs::remove(backups[j], ignored);
    }
    fail("cannot write '{}': {} (the files written with it were put back as they were)",
         m_entries[i].shown.string(), why);
  }
  for (const fs::path& b : backups)
    if (!b.empty()) fs::remove(b, ec);
}

int remove_stale_temporaries(const fs::path& target) {
  const std::string stem = target.filename().string();
  return stem.empty() ? 0 : remove_temporaries(target.parent_path(), stem);
}

int remove_stale_temporaries_in(const fs::path& dir) {
  return remove_temporaries(dir, {});
}

}  // namespace rll
