// A settings struct's parameters as one table: each entry's key, its range or choices and the
// field of the struct it sets, written once. read_params reads every entry given as
// `--set PREFIX.KEY=VALUE` and checks it as it reads, check_params checks every entry of a
// struct (for callers that fill it in code), describe_params lists them with their defaults
// (`rll samplers --params NAME`) and params_json with a struct's values (a sampler's describe(),
// and so a saved state's identity); an error names the sampler's own key (`fermat.alpha`, never
// `rll.alpha`).
#pragma once

#include <cmath>
#include <limits>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <type_traits>
#include <vector>

#include "rll/core/params.h"

namespace rll {

// A numeric range: [lo, hi], each end open or closed; an infinite end is no bound (NaN and
// infinities are always out). `also`, if not NaN, is one more value allowed outside it
// (q_init's -1).
struct ParamRange {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
  double also = std::numeric_limits<double>::quiet_NaN();

  static ParamRange closed(double lo, double hi) { return {lo, hi, false, false}; }
  static ParamRange open_closed(double lo, double hi) { return {lo, hi, true, false}; }
  static ParamRange at_least(double lo) { return {lo}; }
  static ParamRange positive() { return {0, std::numeric_limits<double>::infinity(), true}; }
  ParamRange or_value(double v) const {
    ParamRange r = *this;
    r.also = v;
    return r;
  }
  bool contains(double v) const;
  // "in (0, 1]", "at least 1", "positive", "at least 0 (or -1)": what an error says.
  std::string text() const;
};

// What one entry sets, as functions of the struct (field<S, member pointers...>() makes them).
template <class S>
struct ParamField {
  double (*get)(const S&);
  void (*set)(S&, double);
};

namespace detail {
template <auto P, auto... Rest, class T>
constexpr auto& param_member(T& s) {
  if constexpr (sizeof...(Rest) == 0)
    return s.*P;
  else
    return param_member<Rest...>(s.*P);
}
template <class F>
void param_assign(F& f, double v) {
  if constexpr (std::is_same_v<F, bool>)
    f = v != 0;
  else if constexpr (std::is_enum_v<F> || std::is_integral_v<F>)
    f = static_cast<F>(static_cast<long long>(v));
  else
    f = static_cast<F>(v);
}
template <class F>
double param_value(const F& f) {
  if constexpr (std::is_enum_v<F>)
    return double(static_cast<long long>(f));
  else
    return double(f);
}
}  // namespace detail

// The field s.*P (or (s.*P).*Q, ...): a number, a bool or an enum (choices by index).
template <class S, auto... Path>
ParamField<S> field() {
  return {[](const S& s) { return detail::param_value(detail::param_member<Path...>(s)); },
          [](S& s, double v) { detail::param_assign(detail::param_member<Path...>(s), v); }};
}

enum class ParamKind { Int, Float, Choice };

template <class S>
struct ParamSpec {
  const char* key;
  ParamKind kind;
  ParamRange range;                  // Int and Float
  std::vector<std::string> choices;  // Choice: the names, the field holding the index
  ParamField<S> field;
  const char* note = "";  // said after a range error ("it keeps the estimator unbiased")
};

template <class S>
ParamSpec<S> int_param(const char* key, ParamRange r, ParamField<S> f, const char* note = "") {
  return {key, ParamKind::Int, r, {}, f, note};
}
template <class S>
ParamSpec<S> float_param(const char* key, ParamRange r, ParamField<S> f, const char* note = "") {
  return {key, ParamKind::Float, r, {}, f, note};
}
template <class S>
ParamSpec<S> choice_param(const char* key, std::vector<std::string> names, ParamField<S> f) {
  return {key, ParamKind::Choice, {}, std::move(names), f, ""};
}

namespace detail {
// The value of one entry given in `params`, checked against its range or choices.
double read_param(const Params& params, const std::string& key, ParamKind kind,
                  const ParamRange& range, const std::vector<std::string>& choices,
                  const char* note);
void check_param(const std::string& key, ParamKind kind, const ParamRange& range,
                 const std::vector<std::string>& choices, double value, const char* note);
std::string describe_param(const std::string& key, ParamKind kind, const ParamRange& range,
                           const std::vector<std::string>& choices, double value);
void put_param(nlohmann::json& out, const char* key, ParamKind kind,
               const std::vector<std::string>& choices, double value);
}  // namespace detail

// Reads every entry of `table` given as PREFIX.KEY in `params` into `s` (marking it used, and
// every entry's key as known to the unknown-key error); throws rll::Error naming PREFIX.KEY on a
// value out of its range or choices.
template <class S>
void read_params(const std::vector<ParamSpec<S>>& table, const Params& params,
                 const std::string& prefix, S& s) {
  for (const auto& e : table) {
    const std::string key = prefix + "." + e.key;
    params.note_known(key);  // listed when a key of this prefix is unknown (a typo)
    if (!params.has(key)) continue;
    const double v = detail::read_param(params, key, e.kind, e.range, e.choices, e.note);
    e.field.set(s, v);
    // Again as stored (a float that rounds to 0; ranges keep integers inside their fields).
    detail::check_param(key, e.kind, e.range, e.choices, e.field.get(s), e.note);
  }
}

// Checks every entry of `s` against its range; the error names PREFIX.KEY.
template <class S>
void check_params(const std::vector<ParamSpec<S>>& table, const std::string& prefix, const S& s) {
  for (const auto& e : table)
    detail::check_param(prefix + "." + e.key, e.kind, e.range, e.choices, e.field.get(s), e.note);
}

// One line per entry: PREFIX.KEY, its value in `s` (the default) and its range or choices.
template <class S>
std::vector<std::string> describe_params(const std::vector<ParamSpec<S>>& table,
                                         const std::string& prefix, const S& s) {
  std::vector<std::string> out;
  for (const auto& e : table)
    out.push_back(detail::describe_param(prefix + "." + e.key, e.kind, e.range, e.choices,
                                         e.field.get(s)));
  return out;
}

// Adds every entry of `table` to the JSON object `out` as KEY: its value in `s` (an Int as an
// integer, a Float as a number, a Choice by its name). A sampler's describe() reports its
// parameters so, and a saved state (lights/sampler_state.h) is matched against them: made from
// the tables, that identity holds every key the sampler reads. A key already in `out` (two tables
// of one sampler naming one key) throws rll::Error.
template <class S>
void params_json(const std::vector<ParamSpec<S>>& table, const S& s, nlohmann::json& out) {
  for (const auto& e : table) detail::put_param(out, e.key, e.kind, e.choices, e.field.get(s));
}

}  // namespace rll
