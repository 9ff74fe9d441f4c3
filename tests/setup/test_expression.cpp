// mpm::Expression: muparser wrapper for user fields of position and time.
#include "setup/expression.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

#include "core/types.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

using std::numbers::pi;

TEST(Expression, DefaultIsZero) {
  const Expression e;
  EXPECT_EQ(e.text(), "0");
  EXPECT_EQ(e(0.3, 0.1, 0.2, 5.0), 0.0);
  EXPECT_TRUE(e.is_constant());
}

TEST(Expression, EvaluatesWithUserConstants) {
  const Expression e("0.28*sin(pi*x/L)", {{"L", 2.0}});
  for (double x : {0.0, 0.25, 0.5, 1.0, 1.7}) {
    EXPECT_NEAR(e(x), 0.28 * std::sin(pi * x / 2.0), 1e-15) << "x = " << x;
  }
  EXPECT_EQ(e.text(), "0.28*sin(pi*x/L)");
}

TEST(Expression, VariablesConstantsAndFunctions) {
  const Expression e("x + 10*y + 100*z + 1000*t", {});
  EXPECT_DOUBLE_EQ(e(1, 2, 3, 4), 4321.0);
  EXPECT_DOUBLE_EQ(Expression("e", {})(0), std::numbers::e);
  EXPECT_DOUBLE_EQ(Expression("pi", {})(0), pi);
  EXPECT_DOUBLE_EQ(Expression("sqrt(abs(-16)) + max(1, 3) + exp(0) + 2^3", {})(0), 16.0);
  EXPECT_DOUBLE_EQ(Expression("x < 0.5 ? 1 : -1", {})(0.25), 1.0);
  EXPECT_DOUBLE_EQ(Expression("x < 0.5 ? 1 : -1", {})(0.75), -1.0);
  // Scientific notation is not confused with the constant e.
  EXPECT_DOUBLE_EQ(Expression("1e-3 + 2E2", {})(0), 200.001);
}

TEST(Expression, ReportsWhichVariablesAreUsed) {
  const Expression pos("sin(x)", {});
  EXPECT_TRUE(pos.uses_position());
  EXPECT_FALSE(pos.uses_time());
  EXPECT_FALSE(pos.is_constant());

  const Expression time("2*t", {});
  EXPECT_FALSE(time.uses_position());
  EXPECT_TRUE(time.uses_time());

  const Expression both("y*t", {});
  EXPECT_TRUE(both.uses_position());
  EXPECT_TRUE(both.uses_time());

  const Expression constant("L*pi", {{"L", 3.0}});
  EXPECT_TRUE(constant.is_constant());
  EXPECT_DOUBLE_EQ(constant(7.0, 0, 0, 9.0), 3.0 * pi);
}

TEST(Expression, SyntaxErrorThrowsInputErrorWithText) {
  try {
    Expression("0.28*sin(", {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("invalid expression \"0.28*sin(\": "), std::string::npos) << msg;
    EXPECT_GT(msg.size(), std::string("invalid expression \"0.28*sin(\": ").size()) << msg;
  }
}

TEST(Expression, UnknownNameAndMultipleResultsAreErrors) {
  try {
    Expression("x/L", {{"M", 1.0}});  // L not defined
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("names available: x, y, z, t, pi, e, M"),
              std::string::npos)
        << e.what();
  }
  try {
    Expression("1, 2", {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("single value"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Expression("", {}), InputError);
}

// "x=5" was accepted as the value 5 (and assigned x; issue 16, 12); comparisons still work.
TEST(Expression, AssignmentsAreRefused) {
  for (const char* text : {"x=5", "x = 5", "t=1+x", "(y=2)*3"}) {
    try {
      Expression(text, {});
      ADD_FAILURE() << text << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("an assignment ('=')"), std::string::npos) << e.what();
    }
  }
  EXPECT_DOUBLE_EQ(Expression("x == 2", {})(2.0, 0.0, 0.0, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(Expression("(x <= 1) + (x >= 3) + (x != 2)", {})(2.0, 0.0, 0.0, 0.0), 0.0);
}

TEST(Expression, CopyOutlivesOriginal) {
  auto original = std::make_unique<Expression>("a*x + t", std::map<std::string, double>{{"a", 2}});
  const Expression copy(*original);
  Expression assigned;
  assigned = *original;
  original.reset();
  EXPECT_DOUBLE_EQ(copy(3.0, 0, 0, 1.0), 7.0);
  EXPECT_DOUBLE_EQ(assigned(3.0, 0, 0, 1.0), 7.0);
  EXPECT_EQ(copy.text(), "a*x + t");
  EXPECT_TRUE(copy.uses_position());
  EXPECT_TRUE(copy.uses_time());
}

TEST(Expression, CopiesAndMovesAreIndependent) {
  Expression a("x", {});
  Expression b = a;
  EXPECT_DOUBLE_EQ(a(1.0), 1.0);
  EXPECT_DOUBLE_EQ(b(2.0), 2.0);
  EXPECT_DOUBLE_EQ(a(3.0), 3.0);

  std::vector<Expression> v;
  for (int i = 0; i < 20; ++i)
    v.emplace_back("x*" + std::to_string(i), std::map<std::string, double>{});
  for (int i = 0; i < 20; ++i) EXPECT_DOUBLE_EQ(v[i](2.0), 2.0 * i);  // survived reallocation

  Expression moved = std::move(b);
  EXPECT_DOUBLE_EQ(moved(5.0), 5.0);
}

TEST(Expression, ReservedNames) {
  for (const char* name : {"x", "y", "z", "t", "pi", "e", "sin", "sqrt", "min", "_pi"}) {
    EXPECT_TRUE(Expression::is_reserved_name(name)) << name;
  }
  for (const char* name : {"L", "v0", "rho", "E"}) {
    EXPECT_FALSE(Expression::is_reserved_name(name)) << name;
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
