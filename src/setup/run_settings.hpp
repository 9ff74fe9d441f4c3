#pragma once
// A run's configuration as typed settings, parsed and validated once (run_settings()): the
// driver and the steppers read these, never Config. Keys whose values are used after set-up in
// messages keep where they were set (Config::where: file:line:col or the --set option).
#include <cstdint>
#include <string>
#include <vector>

#include "material/materials.hpp"
#include "methods/kinds.hpp"
#include "parallel/distribution.hpp"
#include "state/simulation.hpp"

namespace mpm {

class Config;

// time.dt, time.end and their whole number of steps; time.allow_unstable.
struct TimeSettings {
  double dt = 0.0;   // [s]
  double end = 0.0;  // [s]
  Index steps = 0;   // end / dt
  bool allow_unstable = false;
  std::string where_dt, where_end;
};

// output.*: what is written into the run's directory, and how often.
struct OutputSettings {
  int frames = 0;              // particle frames besides the initial one
  Index history_every = 1;     // history.csv row every this many steps
  Index checkpoint_every = 0;  // 0: no checkpoints
  bool csv = true, vtk = true;
  bool vtk_binary = true;  // output.vtk_format
};

enum class Solver { Mpm, Ulfem, Otm, Unified };

// method.*: the solver and, for MPM, the basis kind, the mapping (built with its settings from
// method.tls_*, method.mls_*, method.gauss_points: setup/method_settings.hpp), the scheme, the
// mass matrix and re-sorting.
struct MethodSettings {
  Solver solver = Solver::Mpm;
  BasisKind basis;
  MappingKind mapping;
  Scheme scheme;
  MassType mass = MassType::Lumped;
  double mass_tolerance = 1e-10;
  MassSolverSettings mass_solver;  // method.mass_solver and its keys (consistent mass)
  double partial_lumping = 0.0;    // method.partial_lumping (consistent mass; 0: off)
  double conservation_limit = 0.5;
  double local_damping = 0.0;  // method.local_damping (Cundall's alpha; 0: off)
  SortMode sort = SortMode::Auto;
  std::string where_solver, where_basis, where_mapping, where_tls_completion, where_mass;
};

// parallel.*: a run on several processes (RunOptions::comm; parallel/distribution.hpp).
struct ParallelSettings {
  // Move the blocks' boundaries when max particles per process / mean - 1 exceeds this (0:
  // never).
  double rebalance = 0.25;
  BlockShapeRequest blocks;  // parallel.blocks
};

// parallel.blocks of a configuration, parsed (InputError at its line when it is none of the
// decompositions).
BlockShapeRequest blocks_request(const Config& cfg);

// A law's parameter beyond the elastic ones as configured (material.<name>): a real number, or
// one of its choices by name (summary.json's "material" object lists them).
struct MaterialParameterValue {
  std::string name;
  double value = 0.0;
  std::string choice;  // empty for a real number
};

// A material as configured, for summary.json.
struct MaterialSettings {
  std::string name;   // "material" for [material], NAME for [material.NAME]
  std::string model;  // its law's name (TABLE.model)
  ElasticParameters elastic;
  std::vector<MaterialParameterValue> parameters;  // those of its law
};

struct RunSettings {
  TimeSettings time;
  OutputSettings output;
  ParallelSettings parallel;
  MethodSettings method;
  // [material] first, then each [material.NAME] in alphabetical order (the order of the run's
  // materials: setup/material_settings.hpp); the problem holds the laws built from them.
  std::vector<MaterialSettings> materials;
  std::int64_t reference_dofs = 0;  // reference.dofs: the ULFEM reference of benchmarks without
                                    // an exact solution
};

// The settings of `cfg` for a problem of dimension `dim`, checked in the order a run meets them:
// the solver (ULFEM is one-dimensional), the basis, mapping and scheme names, whether they exist
// in `dim`, the time step, then the mapping's own settings. InputError naming the key (file,
// line) and the valid choices.
RunSettings run_settings(const Config& cfg, int dim);

}  // namespace mpm
