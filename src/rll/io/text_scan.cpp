#include "rll/io/text_scan.h"

#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "rll/core/error.h"
#include "rll/core/file_checks.h"
#include "rll/core/params.h"

namespace rll {

std::string read_text_file(const std::filesystem::path& path) {
  check_input_file(path, "input");  // a FIFO would hang the read, a folder fail it unnamed
  std::ifstream f(path, std::ios::binary);
  if (!f) fail("{}: cannot open the file", path.string());
  std::ostringstream s;
  s << f.rdbuf();
  if (f.bad()) fail("{}: read error", path.string());
  return std::move(s).str();
}

std::string printable(std::string_view bytes, size_t max_bytes) {
  return shown_text(bytes, max_bytes, true);
}

std::string without_control_bytes(std::string_view message) {
  std::string out;
  out.reserve(message.size());
  for (char ch : message) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c == 0x7f)
      out += fmt::format("\\x{:02x}", c);
    else
      out += ch;
  }
  return out;
}

std::string unreadable_reason(const std::filesystem::path& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (std::filesystem::is_regular_file(status)) return "";
  if (std::filesystem::is_directory(status)) return "is a folder, not a file";
  // A device or a pipe could be read forever.
  if (std::filesystem::exists(status)) return "is not a regular file";
  return "not found";
}

bool TextLines::next(std::string_view& line) {
  if (m_pos >= m_text.size()) return false;
  // memchr for '\n' is fast; a '\r' (CRLF, or a lone CR ending a line) is then looked for
  // only within the line found.
  const char* begin = m_text.data() + m_pos;
  const size_t left = m_text.size() - m_pos;
  const void* nl = std::memchr(begin, '\n', left);
  size_t len = nl ? size_t(static_cast<const char*>(nl) - begin) : left;
  const void* cr = std::memchr(begin, '\r', len);
  size_t skip = nl ? 1 : 0;
  if (cr) {
    size_t at = size_t(static_cast<const char*>(cr) - begin);
    skip = (at + 1 < left && begin[at + 1] == '\n') ? 2 : 1;
    len = at;
  }
  line = std::string_view(begin, len);
  m_pos += len + skip;
  ++m_number;
  return true;
}

bool next_token(std::string_view& rest, std::string_view& token) {
  size_t b = 0, n = rest.size();
  while (b < n && (rest[b] == ' ' || rest[b] == '\t')) ++b;
  if (b == n) {
    rest = {};
    return false;
  }
  size_t e = b;
  while (e < n && rest[e] != ' ' && rest[e] != '\t') ++e;
  token = rest.substr(b, e - b);
  rest = rest.substr(e);
  return true;
}

namespace {
std::string_view strip_plus(std::string_view s) {
  // from_chars rejects a leading '+', which OBJ writers do emit.
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  return s;
}
}  // namespace

NumberStatus parse_float(std::string_view s, float& out) {
  s = strip_plus(s);
  const char *b = s.data(), *e = s.data() + s.size();
  auto r = std::from_chars(b, e, out);
  if (r.ec == std::errc() && r.ptr == e)
    return std::isfinite(out) ? NumberStatus::Ok : NumberStatus::NonFinite;
  if (r.ec != std::errc::result_out_of_range || r.ptr != e) return NumberStatus::Malformed;
  // Out of float range: either an overflow (not finite) or an underflow, which rounds to a
  // denormal or zero like any other parser would.
  long double wide = 0;
  auto rw = std::from_chars(b, e, wide);
  if (rw.ec == std::errc()) {
    out = float(wide);
    return std::isfinite(out) ? NumberStatus::Ok : NumberStatus::NonFinite;
  }
  if (s.find("e-") != std::string_view::npos || s.find("E-") != std::string_view::npos) {
    out = 0;
    return NumberStatus::Ok;
  }
  return NumberStatus::NonFinite;
}

bool parse_long(std::string_view s, long& out) {
  s = strip_plus(s);
  auto r = std::from_chars(s.data(), s.data() + s.size(), out);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

}  // namespace rll
