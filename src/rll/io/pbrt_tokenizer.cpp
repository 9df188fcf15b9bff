// The pbrt reader's tokens and token stream (see pbrt_internal.h).
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>

#include "rll/io/pbrt_internal.h"

namespace rll::pbrt {

bool Tokenizer::next(Token& t) {
  const size_t n = m_text.size();
  for (;;) {
    while (m_pos < n && is_space(m_text[m_pos])) {
      if (m_text[m_pos] == '\n') ++m_line;
      ++m_pos;
    }
    if (m_pos >= n) return false;
    if (m_text[m_pos] != '#') break;
    while (m_pos < n && m_text[m_pos] != '\n') ++m_pos;
  }
  t.line = m_line;
  t.file = m_file;
  t.quoted = false;
  const char c = m_text[m_pos];
  if (c == '"') {
    const size_t start = ++m_pos;
    while (m_pos < n && m_text[m_pos] != '"') {
      if (m_text[m_pos] == '\n')
        fail("{}{}:{}: a string runs past the end of the line", m_included_from, m_name, t.line);
      if (m_text[m_pos] == '\\') ++m_pos;  // an escaped character, whatever it is
      ++m_pos;
    }
    if (m_pos >= n) fail("{}{}:{}: a string is not closed", m_included_from, m_name, t.line);
    t.text = m_text.substr(start, m_pos - start);
    t.quoted = true;
    ++m_pos;
    return true;
  }
  if (c == '[' || c == ']') {
    t.text = m_text.substr(m_pos++, 1);
    return true;
  }
  const size_t start = m_pos;
  while (m_pos < n && !is_space(m_text[m_pos]) && m_text[m_pos] != '"' && m_text[m_pos] != '[' &&
         m_text[m_pos] != ']' && m_text[m_pos] != '#')
    ++m_pos;
  t.text = m_text.substr(start, m_pos - start);
  return true;
}

std::string unescape(std::string_view s) {
  std::string r;
  r.reserve(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '\\' || i + 1 == s.size()) {
      r += s[i];
      continue;
    }
    switch (char e = s[++i]) {
      case 'n':
        r += '\n';
        break;
      case 't':
        r += '\t';
        break;
      case 'r':
        r += '\r';
        break;
      case 'b':
        r += '\b';
        break;
      case 'f':
        r += '\f';
        break;
      default:
        r += e;
        break;
    }
  }
  return r;
}

void PbrtReader::push_file(std::string_view text, const std::string& name, const std::string& key,
                           const std::string& included_from) {
  if (m_tokenizers.size() >= size_t(kMaxIncludeDepth))
    fail("{}: includes nested more than {} deep", name, kMaxIncludeDepth);
  m_names.push_back(name);
  m_included_from.push_back(included_from);
  m_begun.push_back(false);
  m_tokenizers.emplace_back(text, uint32_t(m_names.size() - 1), name, included_from);
  m_open.push_back(key);
}

std::optional<Token> PbrtReader::take() {
  if (m_peeked) {
    auto t = m_peeked;
    m_peeked.reset();
    return t;
  }
  Token t;
  while (!m_tokenizers.empty()) {
    if (m_tokenizers.back().next(t)) return t;
    m_tokenizers.pop_back();
    m_open.pop_back();
  }
  return std::nullopt;
}

const Token* PbrtReader::peek() {
  if (!m_peeked) m_peeked = take();
  return m_peeked ? &*m_peeked : nullptr;
}

std::string PbrtReader::where(size_t file, size_t line) const {
  return fmt::format("{}{}:{}", m_included_from[file], m_names[file], line);
}

void PbrtReader::warn(const std::string& key, const std::string& message) {
  auto it = m_warning_index.find(key);
  if (it != m_warning_index.end()) {
    ++m_warnings[it->second].second;
    return;
  }
  m_warning_index[key] = m_warnings.size();
  m_warnings.push_back({message, 1});
}

bool PbrtReader::is_directive(const Token& t) const {
  return !t.quoted && !t.text.empty() && std::isalpha(static_cast<unsigned char>(t.text[0])) &&
         t.text != "true" && t.text != "false";
}

double PbrtReader::number(const Token& t) const {
  if (t.quoted) syntax(t, fmt::format("expected a number, got \"{}\"", printable(t.text)));
  float f = 0;
  switch (parse_float(t.text, f)) {
    case NumberStatus::Ok:
      return f;
    case NumberStatus::NonFinite:
      syntax(t, fmt::format("'{}' is not a finite number", printable(t.text)));
    case NumberStatus::Malformed:
      break;
  }
  syntax(t, fmt::format("expected a number, got '{}'", printable(t.text)));
}

int64_t PbrtReader::integer(const Token& t, const std::string& what,
                            const std::string& param) const {
  std::string_view s = t.text;
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  int64_t v = 0;
  const char* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, v);
  if (r.ec == std::errc() && r.ptr == end) return v;
  if (r.ec == std::errc::result_out_of_range && r.ptr == end)
    syntax(t, fmt::format("{}: parameter \"integer {}\": {} is out of range (beyond 64 bits)", what,
                          printable(param), printable(t.text)));
  float f = 0;
  if (parse_float(t.text, f) == NumberStatus::Malformed)
    syntax(t, fmt::format("expected a number, got '{}'", printable(t.text)));
  // A whole number in float notation ("2.0", "2e0", as some exporters write integers) is taken
  // where a double holds it exactly (up to 2^53); anything else is refused, never rounded.
  double d = 0;
  const auto rd = std::from_chars(s.data(), end, d);
  if (rd.ec == std::errc() && rd.ptr == end && std::isfinite(d) && std::floor(d) == d) {
    if (std::abs(d) <= 0x1p53) return int64_t(d);
    syntax(t, fmt::format("{}: parameter \"integer {}\": {} is out of range (a whole number in float "
                          "notation must be at most 2^53)",
                          what, printable(param), printable(t.text)));
  }
  syntax(t, fmt::format("{}: parameter \"integer {}\" must be an integer (got '{}')", what,
                        printable(param), printable(t.text)));
}

Token PbrtReader::expect_token(const Token& after, const char* what) {
  auto t = take();
  if (!t) fail("{}: the file ends where {} was expected", where(after), what);
  return *t;
}

std::string PbrtReader::expect_string(const Token& after) {
  Token t = expect_token(after, "a quoted string");
  if (!t.quoted) syntax(t, fmt::format("expected a quoted string, got '{}'", printable(t.text)));
  return unescape(t.text);
}

// Numbers in [ ... ] (or, where `bare` is set, the same count without brackets).
std::vector<double> PbrtReader::number_list(const Token& after, size_t count, bool bare) {
  std::vector<double> v;
  const Token* p = peek();
  const bool bracket = p && !p->quoted && p->text == "[";
  if (!bracket && !bare) fail("{}: expected [ and {} numbers", where(after), count);
  if (bracket) take();
  while (v.size() < count) v.push_back(expect_number(after));
  if (bracket) {
    Token close = expect_token(after, "]");
    if (close.quoted || close.text != "]")
      syntax(close, fmt::format("expected ] after {} numbers", count));
  }
  return v;
}

// Skips the arguments of a directive rll does not render, up to the next directive.
void PbrtReader::skip_arguments() {
  int depth = 0;
  while (const Token* p = peek()) {
    if (is_directive(*p) && depth == 0) break;
    Token t = *take();
    if (!t.quoted && t.text == "[") ++depth;
    if (!t.quoted && t.text == "]" && --depth < 0) syntax(t, "] without [");
  }
}

void PbrtReader::unsupported(const Token& t, const std::string& what) {
  warn(what, fmt::format("{}: {} is not supported; skipped", where(t), what));
}

}  // namespace rll::pbrt
