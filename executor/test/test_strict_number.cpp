// cmake/include/cairn/strict_number.hpp: the whole-string number parser every package's tools, the launch
// spec, parameter YAML and QoS overrides share.
#include "cairn/strict_number.hpp"

#include <gtest/gtest.h>

#include "cairn/launch.hpp"

namespace sn = cairn::strict_number;

TEST(StrictNumber, FiniteNumbersAreWholeDecimalTexts) {
  EXPECT_EQ(sn::parse_finite("3"), 3.0);
  EXPECT_EQ(sn::parse_finite("-0.5"), -0.5);
  EXPECT_EQ(sn::parse_finite("+2"), 2.0);
  EXPECT_EQ(sn::parse_finite("1e-3"), 1e-3);
  EXPECT_EQ(sn::parse_finite(".5"), 0.5);
  for (const char* bad : {"", "+", "-", " 3", "3 ", "3m", "+-3", "++3", "-+3", "0x10", "inf", "-inf", "nan", "1e400",
                          "1,5", "3.0.0"})
    EXPECT_FALSE(sn::parse_finite(bad).has_value()) << "'" << bad << "'";
}

TEST(StrictNumber, IntegersRejectFractionsExponentsAndOverflow) {
  EXPECT_EQ(sn::parse_integer("42"), 42);
  EXPECT_EQ(sn::parse_integer("-7"), -7);
  EXPECT_EQ(sn::parse_integer("+3"), 3);
  EXPECT_EQ(sn::parse_integer("9223372036854775807"), 9223372036854775807LL);
  for (const char* bad : {"", "+", "2.5", "1e3", "9223372036854775808", "-9223372036854775809", "+-1", " 1", "1 ",
                          "0x10", "12abc"})
    EXPECT_FALSE(sn::parse_integer(bad).has_value()) << "'" << bad << "'";
}

TEST(StrictNumber, LaunchParseNumberIsTheSameParser) {
  EXPECT_EQ(cairn::parse_number("+2.5"), 2.5);
  EXPECT_FALSE(cairn::parse_number("+-3").has_value());  // the launch's own copy accepted it as -3
  EXPECT_FALSE(cairn::parse_number("nan").has_value());
}
