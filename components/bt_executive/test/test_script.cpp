// The expression language: precedence, types, assignment, errors with columns, binding to typed entries.
#include <gtest/gtest.h>

#include "cairn/bt_executive/script.hpp"

using namespace cairn::bt;

namespace {

Value run(const std::string& code, std::shared_ptr<Blackboard> bb = nullptr, const ScriptEnums* enums = nullptr) {
  if (!bb) bb = Blackboard::create();
  Script s = Script::parse(code, enums);
  s.bind(*bb);
  Value v;
  std::string err;
  EXPECT_TRUE(s.evaluate(v, &err)) << code << ": " << err;
  return v;
}

std::string runtimeError(const std::string& code, std::shared_ptr<Blackboard> bb = nullptr) {
  if (!bb) bb = Blackboard::create();
  Script s = Script::parse(code);
  s.bind(*bb);
  Value v;
  std::string err;
  EXPECT_FALSE(s.evaluate(v, &err)) << code;
  return err;
}

std::size_t syntaxErrorColumn(const std::string& code) {
  try {
    (void)Script::parse(code);
  } catch (const ScriptError& e) {
    return e.column;
  }
  ADD_FAILURE() << "no syntax error in: " << code;
  return 0;
}

TEST(Script, ArithmeticPrecedenceAndTypes) {
  EXPECT_EQ(run("1 + 2 * 3"), Value(std::int64_t{7}));
  EXPECT_EQ(run("(1 + 2) * 3"), Value(std::int64_t{9}));
  EXPECT_EQ(run("7 / 2"), Value(std::int64_t{3}));  // integer division
  EXPECT_EQ(run("7.0 / 2"), Value(3.5));
  EXPECT_EQ(run("7 % 4"), Value(std::int64_t{3}));
  EXPECT_EQ(run("-2 - -3"), Value(std::int64_t{1}));
  EXPECT_EQ(run("1e3 + 0.5"), Value(1000.5));
  EXPECT_EQ(run("0x10 | 1"), Value(std::int64_t{17}));
  EXPECT_EQ(run("6 & 3 ^ 1"), Value(std::int64_t{3}));  // & binds tighter than ^
  EXPECT_EQ(run("~0"), Value(std::int64_t{-1}));
}

TEST(Script, ComparisonsLogicAndTernary) {
  EXPECT_EQ(run("1 < 2 && 2 <= 2 && 3 > 2 && 3 >= 3 && 1 != 2 && 2 == 2.0"), Value(true));
  EXPECT_EQ(run("'abc' < 'abd'"), Value(true));
  EXPECT_EQ(run("'a' == 1"), Value(false));
  EXPECT_EQ(run("!(1 > 2) || x"), Value(true));  // short-circuit: x never read
  EXPECT_EQ(run("false && x"), Value(false));
  EXPECT_EQ(run("1 > 2 ? 'yes' : 'no'"), Value(std::string("no")));
  EXPECT_EQ(run("'n=' .. 3 .. \"!\""), Value(std::string("n=3!")));
  EXPECT_EQ(run("'ab' + 'cd'"), Value(std::string("abcd")));
}

TEST(Script, AssignmentCreatesAndUpdatesEntries) {
  auto bb = Blackboard::create();
  EXPECT_EQ(run("a := 2; b := a * 1.5; a += 3; a *= 2; c := a > 5", bb), Value(true));
  EXPECT_EQ(bb->get<std::int64_t>("a"), 10);
  EXPECT_DOUBLE_EQ(bb->get<double>("b"), 3.0);
  run("@root_key := 'x'", bb);
  EXPECT_EQ(bb->get<std::string>("root_key"), "x");
}

TEST(Script, TypedEntriesKeepTheirType) {
  auto bb = Blackboard::create();
  bb->set<int>("count", 1);
  bb->set<std::string>("name", "r2");
  run("count := count + 41", bb);
  EXPECT_EQ(bb->get<int>("count"), 42);
  EXPECT_NE(runtimeError("count := 1.5", bb).find("cannot assign double"), std::string::npos);
  EXPECT_NE(runtimeError("name = 3", bb).find("of type std::string"), std::string::npos);
  EXPECT_EQ(bb->get<std::string>("name"), "r2");
}

TEST(Script, RuntimeErrors) {
  EXPECT_NE(runtimeError("y + 1").find("'y' is unset"), std::string::npos);
  EXPECT_NE(runtimeError("1 / 0").find("division by zero"), std::string::npos);
  EXPECT_NE(runtimeError("'a' - 1").find("arithmetic"), std::string::npos);
  EXPECT_NE(runtimeError("'a' < 1").find("cannot order"), std::string::npos);
  EXPECT_NE(runtimeError("!'maybe'").find("boolean"), std::string::npos);
}

TEST(Script, SyntaxErrorsReportColumn) {
  EXPECT_EQ(syntaxErrorColumn("a := 1 +"), 9u);
  EXPECT_EQ(syntaxErrorColumn("a := (1 + 2"), 12u);
  EXPECT_EQ(syntaxErrorColumn("a := 'open"), 6u);
  EXPECT_EQ(syntaxErrorColumn("a := 1 $ 2"), 8u);
  EXPECT_EQ(syntaxErrorColumn("1 2"), 3u);
  EXPECT_EQ(syntaxErrorColumn("a ? b"), 6u);
  EXPECT_EQ(syntaxErrorColumn("  "), 1u);
  EXPECT_EQ(syntaxErrorColumn("3abc"), 1u);
}

TEST(Script, BindRejectsUnknownTargetsAndNonScriptTypes) {
  struct Opaque {};
  auto bb = Blackboard::create();
  bb->declare<Opaque>("o");
  Script s = Script::parse("missing = 1");
  EXPECT_THROW(s.bind(*bb), ScriptError);
  Script o = Script::parse("o == 1");
  try {
    o.bind(*bb);
    ADD_FAILURE();
  } catch (const ScriptError& e) {
    EXPECT_EQ(e.column, 1u);
  }
}

TEST(Script, Enums) {
  ScriptEnums enums{{"OK", 0}, {"ERROR", 1}};
  auto bb = Blackboard::create();
  EXPECT_EQ(run("r := ERROR; r == ERROR && r != OK", bb, &enums), Value(true));
  EXPECT_THROW((void)Script::parse("OK := 3", &enums), ScriptError);
}

}  // namespace
