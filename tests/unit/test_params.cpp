#include <gtest/gtest.h>

#include "rll/core/error.h"
#include "rll/core/params.h"

using namespace rll;

TEST(Params, TypedValuesAndDefaults) {
  Params p = Params::parse({"a.x=0.25", "a.n=7", "a.flag=true", "a.mode=tree"});
  EXPECT_FLOAT_EQ(p.get_float("a.x", 1), 0.25f);
  EXPECT_EQ(p.get_int("a.n", 1), 7);
  EXPECT_TRUE(p.get_bool("a.flag", false));
  EXPECT_EQ(p.get_choice("a.mode", "uniform", {"uniform", "tree"}), "tree");
  EXPECT_EQ(p.get_int("a.missing", 42), 42);
  EXPECT_NO_THROW(p.check_all_used());
}

TEST(Params, UnknownKeyIsAnError) {
  Params p = Params::parse({"rll.alpah=0.1"});
  p.get_float("rll.alpha", 0.2f);
  try {
    p.check_all_used();
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("rll.alpah"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("rll.alpha"), std::string::npos);  // lists known keys
  }
}

TEST(Params, MalformedValuesAreErrors) {
  EXPECT_THROW(Params::parse({"novalue"}), Error);
  EXPECT_THROW(Params::parse({"=3"}), Error);
  EXPECT_THROW(Params::parse({"a=1", "a=2"}), Error);
  Params p = Params::parse({"x=abc", "n=1.5", "b=maybe", "c=nan"});
  EXPECT_THROW(p.get_double("x", 0), Error);
  EXPECT_THROW(p.get_int("n", 0), Error);
  EXPECT_THROW(p.get_bool("b", false), Error);
  EXPECT_THROW(p.get_double("c", 0), Error);
  EXPECT_THROW(p.get_choice("x", "u", {"u", "v"}), Error);
}
