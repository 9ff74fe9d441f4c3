// Body meshes (grid/body_mesh.hpp): element volumes and their sum, elements turned to a positive
// orientation, degenerate elements and bad indices refused naming the element, and the shape
// quality of the regular simplices.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "grid/body_mesh.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

// The unit cube cut into six tetrahedra around its diagonal (0,0,0)-(1,1,1) (Kuhn: one per
// order of the axes), five of them listed with a negative orientation.
BodyMesh<3> kuhn_cube() {
  std::vector<Vec<3>> x;
  for (int k = 0; k < 8; ++k) x.emplace_back(k & 1, (k >> 1) & 1, (k >> 2) & 1);
  const std::vector<BodyMesh<3>::Element> e = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7},
                                               {0, 6, 2, 7}, {0, 4, 6, 7}, {0, 5, 4, 7}};
  return BodyMesh<3>(x, e, {11, 12, 13, 14, 15, 16}, {0, 0, 0, 1, 1, 1}, {"a", "b"}, "cube");
}

TEST(BodyMesh, VolumesArePositiveAndSumToTheBody) {
  const BodyMesh<3> m = kuhn_cube();
  for (Index e = 0; e < m.num_elements(); ++e) EXPECT_NEAR(m.element_volume(e), 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(m.volume(), 1.0, 1e-15);
  EXPECT_EQ(m.lower(), Vec<3>::Zero());
  EXPECT_EQ(m.upper(), Vec<3>::Ones());
  EXPECT_EQ(m.tag(3), 14u);
  // Turned elements are right-handed afterwards.
  for (Index e = 0; e < m.num_elements(); ++e) {
    const auto& t = m.element(e);
    Mat<3> J;
    for (int d = 0; d < 3; ++d)
      J.col(d) = m.vertex(t[static_cast<std::size_t>(d) + 1]) - m.vertex(t[0]);
    EXPECT_GT(J.determinant(), 0.0) << e;
  }
  // A triangle listed clockwise.
  const BodyMesh<2> tri({Vec<2>(0, 0), Vec<2>(0, 1), Vec<2>(1, 0)}, {{0, 1, 2}}, {1}, {-1}, {},
                        "triangle");
  EXPECT_NEAR(tri.volume(), 0.5, 1e-16);
}

TEST(BodyMesh, DegenerateElementsAndBadIndicesAreRefused) {
  auto refusal = [](auto make) {
    try {
      make();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string flat = refusal([] {
    BodyMesh<3>({Vec<3>(0, 0, 0), Vec<3>(1, 0, 0), Vec<3>(0, 1, 0), Vec<3>(1, 1, 0)},
                {{0, 1, 2, 3}}, {42}, {-1}, {}, "flat.msh");
  });
  EXPECT_NE(flat.find("flat.msh: tetrahedron 42"), std::string::npos) << flat;
  EXPECT_NE(flat.find("zero volume"), std::string::npos) << flat;
  const std::string index = refusal([] {
    BodyMesh<2>({Vec<2>(0, 0), Vec<2>(1, 0), Vec<2>(0, 1)}, {{0, 1, 3}}, {7}, {-1}, {}, "t.msh");
  });
  EXPECT_NE(index.find("triangle 7 refers to vertex 3"), std::string::npos) << index;
  const std::string none =
      refusal([] { BodyMesh<2>({Vec<2>(0, 0)}, {}, {}, {}, {}, "empty.msh"); });
  EXPECT_NE(none.find("empty.msh: no triangles"), std::string::npos) << none;
}

TEST(BodyMesh, TheRegularSimplicesHaveTheirAngles) {
  const BodyMesh<2> tri({Vec<2>(0, 0), Vec<2>(1, 0), Vec<2>(0.5, std::sqrt(0.75))}, {{0, 1, 2}},
                        {1}, {-1}, {}, "equilateral");
  EXPECT_NEAR(tri.min_angle(0), 60.0, 1e-12);
  const BodyMesh<3> tet({Vec<3>(1, 1, 1), Vec<3>(1, -1, -1), Vec<3>(-1, 1, -1), Vec<3>(-1, -1, 1)},
                        {{0, 1, 2, 3}}, {1}, {-1}, {}, "regular");
  EXPECT_NEAR(tet.min_angle(0), std::acos(1.0 / 3.0) * 180.0 / std::acos(-1.0), 1e-12);
  // A Kuhn tetrahedron's dihedral angles are 45, 60 and 90 degrees.
  EXPECT_NEAR(kuhn_cube().min_angle(0), 45.0, 1e-12);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
