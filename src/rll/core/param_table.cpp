#include "rll/core/param_table.h"

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "rll/core/error.h"

namespace rll {

bool ParamRange::contains(double v) const {
  if (v == also) return true;
  if (!std::isfinite(v)) return false;
  const bool above = lo_open ? v > lo : v >= lo;
  const bool below = hi_open ? v < hi : v <= hi;
  return above && below;
}

std::string ParamRange::text() const {
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  std::string t;
  if (has_lo && has_hi)
    t = fmt::format("in {}{}, {}{}", lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]");
  else if (has_lo && lo == 0)
    t = lo_open ? "positive" : "at least 0";
  else if (has_lo)
    t = fmt::format("{} {}", lo_open ? "greater than" : "at least", lo);
  else if (has_hi)
    t = fmt::format("{} {}", hi_open ? "less than" : "at most", hi);
  else
    t = "finite";
  if (!std::isnan(also)) t += fmt::format(" (or {})", also);
  return t;
}

namespace detail {

namespace {
std::string choice_list(const std::vector<std::string>& choices) {
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  return list;
}
}  // namespace

void check_param(const std::string& key, ParamKind kind, const ParamRange& range,
                 const std::vector<std::string>& choices, double value, const char* note) {
  if (kind == ParamKind::Choice) {
    if (!(value >= 0 && value < double(choices.size())))
      fail("--set {}: must be one of {}", key, choice_list(choices));
    return;
  }
  if (!range.contains(value))
    fail("--set {}: must be {} (got {}){}{}", key, range.text(), value, *note ? ": " : "", note);
}

double read_param(const Params& params, const std::string& key, ParamKind kind,
                  const ParamRange& range, const std::vector<std::string>& choices,
                  const char* note) {
  double v = 0;
  if (kind == ParamKind::Int) {
    v = double(params.get_int(key, 0));
  } else if (kind == ParamKind::Float) {
    v = params.get_double(key, 0);
  } else {
    const std::string name = params.get_choice(key, choices.at(0), choices);
    for (size_t i = 0; i < choices.size(); ++i)
      if (choices[i] == name) v = double(i);
  }
  check_param(key, kind, range, choices, v, note);
  return v;
}

std::string describe_param(const std::string& key, ParamKind kind, const ParamRange& range,
                           const std::vector<std::string>& choices, double value) {
  if (kind == ParamKind::Choice) {
    const size_t i = size_t(value);
    return fmt::format("{}={}  (one of {})", key, i < choices.size() ? choices[i] : "?",
                       choice_list(choices));
  }
  if (kind == ParamKind::Float) return fmt::format("{}={}  ({})", key, float(value), range.text());
  return fmt::format("{}={}  ({})", key, value, range.text());
}

void put_param(nlohmann::json& out, const char* key, ParamKind kind,
               const std::vector<std::string>& choices, double value) {
  if (out.contains(key)) fail("parameter '{}' is in two of a sampler's tables", key);
  if (kind == ParamKind::Choice)
    out[key] = choices.at(size_t(value));
  else if (kind == ParamKind::Int)
    out[key] = static_cast<long long>(value);
  else
    out[key] = value;  // a float field's value exactly, as the field itself would be written
}

}  // namespace detail
}  // namespace rll
