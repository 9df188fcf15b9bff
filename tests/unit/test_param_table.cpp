// The learning samplers' parameter tables (core/param_table.h, learn/cut_params.h,
// lights/rll_settings.h): every key of rll and fermat is refused just outside each end of its
// range and on NaN, infinity or an unknown choice, the error naming the sampler's own key; every
// key reads back what it is given; docs/rll.md's parameter table lists exactly these keys; and
// params_json writes a table's every key, so that a key added to a table joins a sampler's
// describe() and with it a saved state's identity.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>

#include "rll/core/error.h"
#include "rll/core/params.h"
#include "rll/learn/cut_params.h"
#include "rll/lights/rll_settings.h"

namespace rll {
namespace {

struct Entry {
  std::string key;
  ParamKind kind;
  ParamRange range;
  std::vector<std::string> choices;
  std::function<double(const RllSettings&)> get;
};

// The three tables' entries, each read from a whole RllSettings.
std::vector<Entry> all_entries() {
  std::vector<Entry> out;
  for (const auto& e : cut_params())
    out.push_back({e.key, e.kind, e.range, e.choices,
                   [f = e.field](const RllSettings& s) { return f.get(s.cut); }});
  for (const auto& e : cell_grid_params())
    out.push_back({e.key, e.kind, e.range, e.choices,
                   [f = e.field](const RllSettings& s) { return f.get(s.grid); }});
  for (const auto& e : rll_params())
    out.push_back({e.key, e.kind, e.range, e.choices,
                   [f = e.field](const RllSettings& s) { return f.get(s); }});
  return out;
}

RllSettings read(const std::string& prefix, const std::string& assignment) {
  const Params p = Params::parse({prefix + "." + assignment});
  return prefix == "rll" ? rll_settings_from(p) : rll_settings_from(p, prefix, fermat_settings());
}

// The error rll_settings_from throws for one assignment ("" if none).
std::string error_of(const std::string& prefix, const std::string& assignment) {
  try {
    read(prefix, assignment);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::string number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

TEST(ParamTable, EveryKeyIsRefusedOutsideItsRangeNamingTheSamplersKey) {
  const auto entries = all_entries();
  ASSERT_GE(entries.size(), 30u);
  for (const std::string prefix : {"rll", "fermat"}) {
    const std::string other = prefix == "rll" ? "fermat." : "rll.";
    for (const Entry& e : entries) {
      const std::string key = prefix + "." + e.key;
      const ParamRange& r = e.range;
      const bool integer = e.kind == ParamKind::Int;
      std::vector<std::string> bad;
      if (e.kind == ParamKind::Choice) {
        bad = {"no_such_choice", "1"};
      } else {
        ASSERT_TRUE(std::isfinite(r.lo) || std::isfinite(r.hi)) << key << ": no range";
        const double step = integer ? 1 : std::max(1e-3, std::abs(r.lo) * 1e-3);
        if (std::isfinite(r.lo)) bad.push_back(number(r.lo_open ? r.lo : r.lo - step));
        if (std::isfinite(r.hi)) bad.push_back(number(r.hi_open ? r.hi : r.hi + step));
        if (integer)
          bad.push_back("1.5");
        else
          bad.insert(bad.end(), {"nan", "inf", "-inf"});
        // A value below the range that the range allows on its own (q_init's -1) is not bad.
        if (!std::isnan(r.also))
          std::erase_if(bad, [&](const std::string& v) { return v == number(r.also); });
      }
      for (const std::string& v : bad) {
        const std::string err = error_of(prefix, e.key + "=" + v);
        EXPECT_NE(err.find(key), std::string::npos) << key << "=" << v << ": " << err;
        EXPECT_EQ(err.find(other + e.key), std::string::npos) << key << "=" << v << ": " << err;
      }
    }
  }
}

// Inside the range every key sets its field: the lower end (or just above an open one) and, for
// choices, every name (those a rule between keys refuses say what they need).
TEST(ParamTable, EveryKeySetsItsField) {
  for (const std::string prefix : {"rll", "fermat"})
    for (const Entry& e : all_entries()) {
      std::vector<std::pair<std::string, double>> good;
      if (e.kind == ParamKind::Choice) {
        for (size_t i = 0; i < e.choices.size(); ++i) good.push_back({e.choices[i], double(i)});
      } else {
        const double v = e.range.lo_open ? e.range.lo + 1e-3 : e.range.lo;
        good.push_back({number(v), v});
      }
      for (const auto& [text, want] : good) {
        const std::string assignment = e.key + "=" + text;
        try {
          const RllSettings s = read(prefix, assignment);
          EXPECT_NEAR(e.get(s), want, std::abs(want) * 1e-6) << prefix << "." << assignment;
        } catch (const Error& err) {
          EXPECT_EQ(e.kind, ParamKind::Choice) << prefix << "." << assignment << ": " << err.what();
          EXPECT_NE(std::string(err.what()).find("needs"), std::string::npos) << err.what();
        }
      }
    }
}

// The defaults of both samplers pass their own tables, and `rll samplers --params` lists every key.
TEST(ParamTable, DefaultsPassAndEveryKeyIsListed) {
  const auto entries = all_entries();
  for (const std::string prefix : {"rll", "fermat"}) {
    const RllSettings s = prefix == "rll" ? RllSettings{} : fermat_settings();
    EXPECT_NO_THROW(check_params(rll_params(), prefix, s));
    EXPECT_NO_THROW(check_params(cell_grid_params(), prefix, s.grid));
    EXPECT_NO_THROW(check_cut_settings(s.cut, prefix));
    const auto lines = describe_rll_params(s, prefix);
    ASSERT_EQ(lines.size(), entries.size());
    for (size_t i = 0; i < lines.size(); ++i)
      EXPECT_EQ(lines[i].rfind(prefix + "." + entries[i].key + "=", 0), 0u) << lines[i];
  }
  EXPECT_NE(describe_rll_params(RllSettings{}, "rll")[0].find("in [2, 4096]"), std::string::npos);
}

// docs/rll.md's parameter table has a row for every key of the tables and no other.
TEST(ParamTable, DocsListExactlyTheseKeys) {
  std::ifstream in(std::string(RLL_SOURCE_DIR) + "/docs/rll.md");
  ASSERT_TRUE(in) << "docs/rll.md";
  std::set<std::string> documented;
  bool inside = false;
  const std::regex row(R"(^\| `([a-zA-Z_]+)` \|)");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("## ", 0) == 0) inside = line.find("## Parameters") == 0;
    std::smatch m;
    if (inside && std::regex_search(line, m, row)) documented.insert(m[1]);
  }
  std::set<std::string> keys;
  for (const Entry& e : all_entries()) keys.insert(e.key);
  EXPECT_EQ(documented, keys);
}

// A test-only settings struct and table: params_json writes each kind as describe() always
// wrote it, and an entry added to the table is in the JSON with nothing else written by hand.
struct Toy {
  int count = 7;
  float weight = 0.1f;
  bool guided = true;
};

TEST(ParamTable, ParamsJsonWritesEveryKeyOfTheTable) {
  std::vector<ParamSpec<Toy>> table = {
      int_param("count", ParamRange::at_least(0), field<Toy, &Toy::count>()),
      float_param("weight", ParamRange::at_least(0), field<Toy, &Toy::weight>()),
  };
  nlohmann::json j = nlohmann::json::object();
  params_json(table, Toy{}, j);
  // As {{"count", s.count}, {"weight", s.weight}} wrote it: the float's own value, not 0.1.
  EXPECT_EQ(j.dump(), nlohmann::json({{"count", 7}, {"weight", 0.1f}}).dump());
  EXPECT_EQ(j.dump(), R"({"count":7,"weight":0.10000000149011612})");
  table.push_back(choice_param("sampling", {"table", "guided"}, field<Toy, &Toy::guided>()));
  nlohmann::json more = nlohmann::json::object();
  params_json(table, Toy{}, more);
  EXPECT_EQ(more.size(), 3u);
  EXPECT_EQ(more["sampling"], "guided");
  // Two tables of one sampler naming one key would hide one of them: refused.
  EXPECT_THROW(params_json(table, Toy{}, more), Error);
}

// rll's and fermat's "parameters" are the three tables' keys, each with its value, and no other.
TEST(ParamTable, RllParametersJsonHoldsEveryKeyOfTheTables) {
  for (const std::string prefix : {"rll", "fermat"}) {
    const RllSettings s = prefix == "rll" ? RllSettings{} : fermat_settings();
    const nlohmann::json j = rll_parameters_json(s);
    const auto entries = all_entries();
    EXPECT_EQ(j.size(), entries.size());
    for (const Entry& e : entries) {
      ASSERT_TRUE(j.contains(e.key)) << prefix << "." << e.key;
      if (e.kind == ParamKind::Choice)
        EXPECT_EQ(j[e.key], e.choices.at(size_t(e.get(s)))) << e.key;
      else
        EXPECT_EQ(j[e.key].get<double>(), e.get(s)) << e.key;
    }
  }
}

}  // namespace
}  // namespace rll
