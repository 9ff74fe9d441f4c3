// The stepper units of a build (CMakeLists.txt, MPM_STEPPERS_1D/2D/3D; driver/stepper.cpp): every
// unit the build compiled makes its stepper, and a unit left out is refused with an input error
// that names the option. The default build compiles every unit of each dimension;
// scripts/sanitize.sh leaves out those its tests do not run, so there the refusal is exercised.
#include <gtest/gtest.h>
#include <cstddef>
#include <string>

#include "../support/stepper.hpp"
#include "core/types.hpp"
#include "driver/stepper.hpp"
#include "model/problem.hpp"
#include "mpm/stepper_units.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

template <int Dim>
void check_units() {
  IVec<Dim> cells;
  cells.fill(8);  // max-ent needs 5 or more
  const Grid<Dim> g(Vec<Dim>::Zero(), Vec<Dim>::Ones(), cells);
  const auto P =
      seed_particles<Dim>(g, Vec<Dim>::Constant(0.25), Vec<Dim>::Constant(0.75), 2, 1000.0);
  const Material law = Dim == 1 ? Material(Elastic1DSmall{ElasticParameters{1000.0, 1e6, 0.0}})
                                : Material(NeoHookean{ElasticParameters{1000.0, 1e6, 0.3}});
  int compiled = 0, refused = 0;
  for (const BasisKind& kind : test::basis_kinds<Dim>()) {
    SCOPED_TRACE(::testing::Message()
                 << Dim << "D, basis kind " << kind.index() << " (" << basis_name(kind) << ")");
    const test::StepperSpec<Dim> spec{.grid = g, .particles = P, .material = law, .basis = kind};
    if (driver::stepper_compiled(Dim, kind.index())) {
      auto stepper = test::compiled_stepper<Dim>(spec);
      ASSERT_NE(stepper, nullptr);
      stepper->step(1e-6);
      for (const auto& x : stepper->state().particles.x) ASSERT_TRUE(x.allFinite());
      ++compiled;
    } else {
      try {
        test::compiled_stepper<Dim>(spec);
        ADD_FAILURE() << "a unit left out of the build made a stepper";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("MPM_STEPPERS_" + std::to_string(Dim) + "D"),
                  std::string::npos)
            << e.what();
        // The unit by its name in CMakeLists.txt's list (MPM_BASIS_KIND_UNITS), not a position.
        const std::string unit(driver::kStepperUnitNames[kind.index()]);
        EXPECT_NE(std::string(e.what()).find("leaving out \"" + unit + "\""), std::string::npos)
            << e.what();
      }
      ++refused;
    }
  }
  EXPECT_GT(compiled, 0);
  EXPECT_EQ(compiled + refused, static_cast<int>(test::basis_kinds<Dim>().size()));
}

TEST(StepperUnits, CompiledUnitsStepAndLeftOutUnitsAreRefusedByName) {
  check_units<1>();
  check_units<2>();
  check_units<3>();
}

TEST(StepperUnits, KindsWithoutADimensionHaveNoUnit) {
  // CPDI2 and the triangle kinds are 2D only; max-ent is 1D and 2D.
  for (std::size_t kind : {4u, 12u, 13u}) {
    EXPECT_FALSE(driver::stepper_compiled(1, kind));
    EXPECT_FALSE(driver::stepper_compiled(3, kind));
  }
  EXPECT_FALSE(driver::stepper_compiled(3, 11));
  EXPECT_FALSE(driver::stepper_compiled(0, 0));
  EXPECT_FALSE(driver::stepper_compiled(4, 0));
  EXPECT_FALSE(driver::stepper_compiled(2, std::variant_size_v<BasisKind>));
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
