#pragma once
// Fundamental types shared by every concept. Dimension is a template parameter everywhere:
// 1D runs today, 2D and 3D reuse the same code paths.
#include <Eigen/Dense>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace mpm {

using Index = std::int64_t;
// Per-particle indices stored for every particle (its stable id, its cell) are 32-bit: 8 bytes
// per particle less in a state of about 300 (the memory target). A run is therefore
// limited to 2^31 - 1 particles and cells; Simulation checks both.
using CompactIndex = std::int32_t;

template <int Dim>
using Vec = Eigen::Matrix<double, Dim, 1>;
template <int Dim>
using Mat = Eigen::Matrix<double, Dim, Dim>;
template <int Dim>
using IVec = std::array<Index, Dim>;

// Compile-time integer power, used for tensor-product stencil sizes (n^Dim).
constexpr int ipow(int base, int exp) {
  return exp == 0 ? 1 : base * ipow(base, exp - 1);
}

// Error raised for invalid user input (configuration, command line). The message is meant for
// the user and is printed without decoration; exit code 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A numerical failure during a run (NaN, particle leaving the grid, ...). Raised outside the
// per-particle loops, after they have recorded what went wrong.
class RunError : public std::runtime_error {
 public:
  RunError(int exit_code, const std::string& what)
      : std::runtime_error(what), exit_code_(exit_code) {}
  int exit_code() const { return exit_code_; }

 private:
  int exit_code_;
};

// Documented exit codes of `mpm` (README, "Exit codes").
namespace exit_code {
inline constexpr int kOk = 0;
inline constexpr int kInternal = 1;
inline constexpr int kInput = 2;
inline constexpr int kNonFinite = 3;
inline constexpr int kLeftGrid = 4;
inline constexpr int kInvertedDeformation = 5;
inline constexpr int kReconstruction = 6;  // a reconstruction mapping cannot fit an element
inline constexpr int kInterrupted = 7;     // SIGINT, SIGTERM or SIGHUP (core/interrupt.hpp)
inline constexpr int kOutput = 8;          // an output could not be written (disk full, ...)
// The particle-to-grid mapping lost or created mass or momentum of order one (above
// method.conservation_limit): the grid no longer represents the particles.
inline constexpr int kConservation = 9;
// A basis could not be evaluated at some point (the max-ent Newton iteration did not converge).
inline constexpr int kBasis = 10;
// An iterative mass solver (method.mass_solver = "cg" or "pmg") did not reach its tolerance.
inline constexpr int kSolver = 11;
// A constitutive law's return mapping found no admissible stress at some particle.
inline constexpr int kReturnMapping = 12;
}  // namespace exit_code

}  // namespace mpm
