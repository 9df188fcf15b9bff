#include "rll/core/params.h"

#include <charconv>
#include <cmath>

#include "rll/core/error.h"

namespace rll {

namespace {

// The length of the UTF-8 sequence that starts at text[i] (its code point in `cp`), or 0 where
// the bytes there are not one: a stray continuation byte, a truncated or overlong sequence, a
// surrogate, or past U+10FFFF.
size_t utf8_sequence(std::string_view text, size_t i, char32_t& cp) {
  const auto byte = [&](size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b = byte(i);
  size_t n = 0;
  char32_t min = 0;
  if (b < 0x80) {
    cp = b;
    return 1;
  } else if ((b & 0xe0) == 0xc0) {
    n = 2, cp = b & 0x1f, min = 0x80;
  } else if ((b & 0xf0) == 0xe0) {
    n = 3, cp = b & 0x0f, min = 0x800;
  } else if ((b & 0xf8) == 0xf0) {
    n = 4, cp = b & 0x07, min = 0x10000;
  } else {
    return 0;
  }
  if (i + n > text.size()) return 0;
  for (size_t k = 1; k < n; ++k) {
    if ((byte(i + k) & 0xc0) != 0x80) return 0;
    cp = (cp << 6) | (byte(i + k) & 0x3f);
  }
  if (cp < min || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) return 0;
  return n;
}

// Characters a terminal acts on rather than shows: C0, DEL, C1, and the bidirectional overrides
// and isolates that can make a shown name read as another.
bool is_control(char32_t cp) {
  return cp < 0x20 || (cp >= 0x7f && cp < 0xa0) || (cp >= 0x202a && cp <= 0x202e) ||
         (cp >= 0x2066 && cp <= 0x2069);
}

}  // namespace

std::string shown_text(std::string_view text, size_t max_bytes, bool escape_backslash) {
  std::string out;
  size_t i = 0;
  while (i < text.size()) {
    char32_t cp = 0;
    const size_t n = utf8_sequence(text, i, cp);
    const size_t len = n == 0 ? 1 : n;
    if (i + len > max_bytes) break;
    if (n == 0 || is_control(cp)) {
      for (size_t k = i; k < i + len; ++k)
        out += fmt::format("\\x{:02x}", static_cast<unsigned char>(text[k]));
    } else if (escape_backslash && cp == '\\') {
      out += "\\\\";
    } else {
      out.append(text.substr(i, len));
    }
    i += len;
  }
  if (i < text.size()) out += "...";
  return out;
}

Params Params::parse(const std::vector<std::string>& assignments) {
  Params p;
  for (const auto& a : assignments) {
    auto eq = a.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == a.size())
      fail("--set '{}': expected key=value", shown_text(a));
    std::string key = a.substr(0, eq);
    if (p.has(key))
      fail("--set: '{}' given twice ({}={} and {}={}): give each key once", shown_text(key),
           shown_text(key), shown_text(p.m_values[key], 40), shown_text(key),
           shown_text(a.substr(eq + 1), 40));
    p.set(key, a.substr(eq + 1));
  }
  return p;
}

const std::string* Params::find(const std::string& key) const {
  m_used.insert(key);
  auto it = m_values.find(key);
  return it == m_values.end() ? nullptr : &it->second;
}

double Params::get_double(const std::string& key, double fallback) const {
  const std::string* v = find(key);
  if (!v) return fallback;
  double out = 0;
  auto [ptr, ec] = std::from_chars(v->data(), v->data() + v->size(), out);
  if (ec != std::errc() || ptr != v->data() + v->size() || !std::isfinite(out))
    fail("--set {}={}: not a number", shown_text(key), shown_text(*v));
  return out;
}

long Params::get_int(const std::string& key, long fallback) const {
  const std::string* v = find(key);
  if (!v) return fallback;
  long out = 0;
  auto [ptr, ec] = std::from_chars(v->data(), v->data() + v->size(), out);
  if (ec != std::errc() || ptr != v->data() + v->size())
    fail("--set {}={}: not an integer", shown_text(key), shown_text(*v));
  return out;
}

long Params::get_int_in(const std::string& key, long fallback, long lo, long hi) const {
  const long v = get_int(key, fallback);
  if (v < lo || v > hi) fail("--set {}={}: must be in [{}, {}]", key, v, lo, hi);
  return v;
}

bool Params::get_bool(const std::string& key, bool fallback) const {
  const std::string* v = find(key);
  if (!v) return fallback;
  if (*v == "1" || *v == "true" || *v == "on") return true;
  if (*v == "0" || *v == "false" || *v == "off") return false;
  fail("--set {}={}: expected true or false", shown_text(key), shown_text(*v));
}

std::string Params::get_string(const std::string& key, const std::string& fallback) const {
  const std::string* v = find(key);
  return v ? *v : fallback;
}

std::string Params::get_choice(const std::string& key, const std::string& fallback,
                               const std::vector<std::string>& choices) const {
  std::string v = get_string(key, fallback);
  for (const auto& c : choices)
    if (c == v) return v;
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  fail("--set {}={}: must be one of {}", shown_text(key), shown_text(v), list);
}

std::set<std::string> Params::known_keys() const {
  std::set<std::string> known = m_known;
  known.insert(m_used.begin(), m_used.end());
  return known;
}

void Params::check_all_used() const {
  std::vector<std::string> unknown;
  for (const auto& [k, v] : m_values)
    if (!m_used.count(k)) unknown.push_back(k);
  if (unknown.empty()) return;
  // Each unknown key with the known keys of its prefix (rll.bogus: rll.*), which are what a
  // typo most likely meant; every known key where its prefix has none.
  const std::set<std::string> known = known_keys();
  std::string text;
  for (const auto& k : unknown) {
    const std::string prefix = k.substr(0, k.find('.') + 1);
    std::string near, all;
    for (const auto& n : known) {
      if (m_values.count(n) && !m_used.count(n)) continue;
      all += (all.empty() ? "" : ", ") + n;
      if (k.find('.') != std::string::npos && n.compare(0, prefix.size(), prefix) == 0)
        near += (near.empty() ? "" : ", ") + n;
    }
    text += fmt::format("{}{}", text.empty() ? "" : "; ", shown_text(k));
    if (!near.empty())
      text += fmt::format(" ({}'s keys: {})", prefix.substr(0, prefix.size() - 1), near);
    else
      text += fmt::format(" (known here: {})", all.empty() ? "none" : all);
  }
  fail("--set: unknown parameter{}: {}", unknown.size() > 1 ? "s" : "", text);
}

}  // namespace rll
