#include "rll/core/params.h"

#include <charconv>
#include <cmath>

#include "rll/core/error.h"

namespace rll {

Params Params::parse(const std::vector<std::string>& assignments) {
  Params p;
  for (const auto& a : assignments) {
    auto eq = a.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == a.size())
      fail("--set '{}': expected key=value", a);
    std::string key = a.substr(0, eq);
    if (p.has(key)) fail("--set: '{}' given twice", key);
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
    fail("--set {}={}: not a number", key, *v);
  return out;
}

long Params::get_int(const std::string& key, long fallback) const {
  const std::string* v = find(key);
  if (!v) return fallback;
  long out = 0;
  auto [ptr, ec] = std::from_chars(v->data(), v->data() + v->size(), out);
  if (ec != std::errc() || ptr != v->data() + v->size()) fail("--set {}={}: not an integer", key, *v);
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
  fail("--set {}={}: expected true or false", key, *v);
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
  fail("--set {}={}: must be one of {}", key, v, list);
}

void Params::check_all_used() const {
  std::string unknown;
  for (const auto& [k, v] : m_values)
    if (!m_used.count(k)) unknown += (unknown.empty() ? "" : ", ") + k;
  if (unknown.empty()) return;
  std::string known;
  for (const auto& k : m_used)
    if (!m_values.count(k)) known += (known.empty() ? "" : ", ") + k;
  fail("--set: unknown parameter(s): {} (known here: {})", unknown, known.empty() ? "none" : known);
}

}  // namespace rll
