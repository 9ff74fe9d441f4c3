// The --methods argument of `mpm study` (app/study.cpp, parse_methods).
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "app/study.hpp"
#include "core/types.hpp"

namespace mpm {
namespace {

using Keys = std::vector<std::pair<std::string, std::string>>;

TEST(StudyMethods, BasisNamesEndingInADigitAreNotDegrees) {
  // cpdi2 is a basis of its own: it must not become CPDI with method.degree = 2 (issue 16, 8).
  const auto m = parse_methods("cpdi2/direct, bspline3/tls/consistent, cpdi/mls");
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0].label, "cpdi2/direct");
  EXPECT_EQ(m[0].keys, (Keys{{"method.basis", "cpdi2"}, {"method.mapping", "direct"}}));
  EXPECT_EQ(m[1].keys, (Keys{{"method.basis", "bspline"},
                             {"method.degree", "3"},
                             {"method.mapping", "tls"},
                             {"method.mass", "consistent"}}));
  EXPECT_EQ(m[2].keys, (Keys{{"method.basis", "cpdi"}, {"method.mapping", "mls"}}));
}

TEST(StudyMethods, OnlyBSplinesTakeADegree) {
  for (const char* item : {"linear2/direct", "cpdi3/direct", "ugimp1/tls"}) {
    try {
      parse_methods(item);
      ADD_FAILURE() << item << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("only bspline takes a degree"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_THROW(parse_methods("spline2/direct"), InputError);
  EXPECT_THROW(parse_methods("bspline/direct/lumpy"), InputError);
}

}  // namespace
}  // namespace mpm
