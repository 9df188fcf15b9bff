// Named parameters given as `--set key=value`: typed access, and an error for any key that no
// component asked for (a typo must never become a silent default).
#pragma once

#include <map>
#include <set>
#include <string>
#include <vector>

namespace rll {

class Params {
 public:
  Params() = default;
  // Parses "key=value" strings; throws rll::Error on a malformed one or a repeated key.
  static Params parse(const std::vector<std::string>& assignments);

  void set(const std::string& key, const std::string& value) { m_values[key] = value; }
  bool has(const std::string& key) const { return m_values.count(key) > 0; }
  // Typed getters mark the key as used; they throw rll::Error naming the key on a bad value.
  double get_double(const std::string& key, double fallback) const;
  float get_float(const std::string& key, float fallback) const { return float(get_double(key, fallback)); }
  long get_int(const std::string& key, long fallback) const;
  // get_int, and an error naming the key and the range outside [lo, hi].
  long get_int_in(const std::string& key, long fallback, long lo, long hi) const;
  bool get_bool(const std::string& key, bool fallback) const;
  std::string get_string(const std::string& key, const std::string& fallback) const;
  // One of `choices`; an error listing them otherwise.
  std::string get_choice(const std::string& key, const std::string& fallback,
                         const std::vector<std::string>& choices) const;
  // Whether a getter asked for `key`.
  bool used(const std::string& key) const { return m_used.count(key) > 0; }
  // Throws rll::Error listing every key that no getter asked for.
  void check_all_used() const;
  // Marks as used every key that `other` (a copy with overrides) had asked for.
  void merge_used(const Params& other) const { m_used.insert(other.m_used.begin(), other.m_used.end()); }
  const std::map<std::string, std::string>& values() const { return m_values; }

 private:
  const std::string* find(const std::string& key) const;
  std::map<std::string, std::string> m_values;
  mutable std::set<std::string> m_used;
};

}  // namespace rll
