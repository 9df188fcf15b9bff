// Named parameters given as `--set key=value`: typed access, and an error for any key that no
// component asked for (a typo must never become a silent default).
#pragma once

#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace rll {

// Text that a user or a file gave (a key, a value, an argument, a name) as a message shows it:
// UTF-8 as it is; control characters and bytes that are not UTF-8 as \xNN (and, when
// `escape_backslash`, a backslash doubled, so that no escape can be forged); at most `max_bytes`
// bytes of it, cut between characters and followed by "...", so that a 100 KB key is not echoed
// whole.
std::string shown_text(std::string_view text, size_t max_bytes = 80, bool escape_backslash = false);

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
  // Records `key` as one that a component reads (read_params: a table's every key, given or
  // not), so that an unknown key's error can list its neighbours.
  void note_known(const std::string& key) const { m_known.insert(key); }
  // Every key a getter asked for or note_known() recorded.
  std::set<std::string> known_keys() const;
  // Throws rll::Error naming every key that no getter asked for and, for each, the known keys
  // that share its prefix ("rll.bogus": rll's keys), or every known key where none does.
  void check_all_used() const;
  // Marks as used every key that `other` (a copy with overrides) had asked for.
  void merge_used(const Params& other) const {
    m_used.insert(other.m_used.begin(), other.m_used.end());
    m_known.insert(other.m_known.begin(), other.m_known.end());
  }
  const std::map<std::string, std::string>& values() const { return m_values; }

 private:
  const std::string* find(const std::string& key) const;
  std::map<std::string, std::string> m_values;
  mutable std::set<std::string> m_used;
  mutable std::set<std::string> m_known;
};

}  // namespace rll
