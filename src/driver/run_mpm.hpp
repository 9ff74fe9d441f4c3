#pragma once
// The MPM run of one problem with the chosen basis, mapping and scheme (run_mpm.cpp, compiled
// once per dimension; the typed stepping is behind driver/stepper.hpp).
#include "driver/run.hpp"
#include "model/problem.hpp"
#include "scheme/variants.hpp"

namespace mpm::driver {

template <int Dim>
RunResult run_mpm(Problem<Dim>& pb, const Config& cfg, const RunOptions& opt,
                  const BasisKind& basis, const MappingKind& mapping, const Scheme& scheme);

}  // namespace mpm::driver
