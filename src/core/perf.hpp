#pragma once
// `mpm bench`: time per particle-step and memory per particle of the explicit step.
#include <string>

#include "core/types.hpp"

namespace mpm {

struct BenchOptions {
  Index particles = 1000000;
  int per_cell = 4;
  Index steps = 20;
  int repeats = 3;
  std::string scheme = "musl";
  std::string basis = "linear";
  int degree = 2;
  std::string mapping = "direct";
};

struct BenchResult {
  Index particles = 0;
  Index cells = 0;
  Index steps = 0;
  double best_ns_per_particle_step = 0.0;
  double median_ns_per_particle_step = 0.0;
  double bytes_per_particle = 0.0;  // particle state + cached stencils + grid share (linear)
};

// 1D vibrating bar (D Table 3.1 set 2 material) with the given scheme, basis and mapping,
// lumped mass.
BenchResult bench_1d(const BenchOptions& opt);

}  // namespace mpm
