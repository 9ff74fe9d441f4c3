// The basis kinds answer the rest of the code from their own declarations (methods/kinds.hpp):
// which live on triangles, which carry OTM's advected nodes, their stability factors and
// boundary cells, the mappings they run with, and the stepper units' names.
#include <gtest/gtest.h>

#include <string>
#include <variant>

#include "methods/kinds.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TEST(BasisKinds, AnswerFromTheirTraits) {
  EXPECT_TRUE(on_triangles(TriangleP1Kind{}));
  EXPECT_TRUE(on_triangles(PowellSabinKind{}));
  EXPECT_FALSE(on_triangles(BSplineKind<2>{}));
  EXPECT_EQ(basis_names_where([](const auto& k) { return k.kOnTriangles; }),
            "\"p1_triangles\" or \"powell_sabin\"");
  EXPECT_EQ(basis_names_where([](const auto& k) { return k.kOtmNodes; }),
            "\"linear\" or \"maxent\"");
  EXPECT_EQ(basis_names_where([](const auto& k) { return k.kVertexDofs; }), "\"p1_triangles\"");
  EXPECT_EQ(basis_names_where([](const auto& k) { return k.kUnified; }),
            "\"bspline\" or \"powell_sabin\"");
  EXPECT_TRUE(unified_dofs(PowellSabinKind{}));
  EXPECT_FALSE(unified_dofs(TriangleP1Kind{}));
  // The five B-spline kinds are one name.
  EXPECT_EQ(basis_names_where([](const auto& k) { return k.kDegree > 0; }), "\"bspline\"");
  EXPECT_TRUE(basis_named_has("powell_sabin", [](const auto& k) { return k.kOnTriangles; }));
  EXPECT_FALSE(basis_named_has("linear", [](const auto& k) { return k.kOnTriangles; }));
  EXPECT_FALSE(basis_named_has("no_such_basis", [](const auto&) { return true; }));
}

TEST(BasisKinds, StabilityAndBoundaryFromEachKind) {
  EXPECT_EQ(stability_factor(LinearKind{}), 1.0);
  EXPECT_EQ(stability_factor(BSplineKind<3>{}), bspline_stability_factor(3));
  EXPECT_EQ(boundary_cells(BSplineKind<3>{}), 3);
  EXPECT_EQ(boundary_cells(LinearKind{}), 1);
  MaxEntKind maxent;
  maxent.settings.dmax = 2.5;
  EXPECT_EQ(boundary_cells(maxent), 3);
  EXPECT_EQ(stability_factor(maxent), maxent_stability_factor(maxent.settings));
  // On triangles: the factor on the cell size is the pattern's times the one on the altitude.
  PowellSabinKind ps;
  ps.pattern = TrianglePattern::criss_cross;
  EXPECT_EQ(altitude_stability_factor(ps), bspline_stability_factor(2));
  EXPECT_EQ(stability_factor(ps),
            triangle_stability_factor(TrianglePattern::criss_cross) * bspline_stability_factor(2));
  EXPECT_THROW((void)altitude_stability_factor(LinearKind{}), std::logic_error);
  BasisKind p1 = TriangleP1Kind{};
  set_triangle_pattern(p1, TrianglePattern::criss_cross);
  EXPECT_EQ(triangle_pattern(p1), TrianglePattern::criss_cross);
  EXPECT_FALSE(triangle_pattern(LinearKind{}).has_value());
}

TEST(BasisKinds, MappingsAndUnitNames) {
  EXPECT_TRUE((supports_mapping<LinearKind, TlsMapping>()));
  EXPECT_FALSE((supports_mapping<MaxEntKind, TlsMapping>()));
  EXPECT_TRUE((supports_mapping<MaxEntKind, DirectMapping>()));
  EXPECT_FALSE((supports_mapping<TriangleP1Kind, MlsMapping>()));
  EXPECT_TRUE((supports_mapping<PowellSabinKind, TlsMapping>()));
  static_assert(std::is_same_v<std::variant_alternative_t<basis_kind_index("bspline3"), BasisKind>,
                               BSplineKind<3>>);
  static_assert(std::is_same_v<std::variant_alternative_t<basis_kind_index("linear"), BasisKind>,
                               LinearKind>);
  EXPECT_EQ(basis_kind_index("bspline"), std::variant_size_v<BasisKind>);
  EXPECT_EQ(basis_kind_index("bspline6"), std::variant_size_v<BasisKind>);
  EXPECT_EQ(basis_kind_index("nope"), std::variant_size_v<BasisKind>);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
