#pragma once
// Wall time per stage of the explicit step, for `mpm bench --stages`: where a step's time goes
// (the basis, the particle-to-grid sums, the grid solves, the grid-to-particle updates and the
// material laws among them). The stages add their time to RunState::clock when it is set, which
// only a one-thread run does: the laws are timed inside the particle loop, one block at a time.
#include <array>
#include <chrono>
#include <cstddef>
#include <string_view>

namespace mpm {

enum class Stage : int {
  kBasis,        // stages::evaluate_basis: the checks and the cached stencils
  kToGrid,       // the particle-to-grid sums with their checks and exchanges (MUSL's velocity
                 // update with its momentum sum)
  kGrid,         // the grid's solves: accelerations, velocities, the Euler-Cromer update
  kToParticles,  // the grid-to-particle updates, the material laws included
  kMaterial,     // the material laws alone (F, V, the stress: stages::deform_particles)
  kCount
};

inline constexpr std::array<std::string_view, static_cast<std::size_t>(Stage::kCount)> kStageNames{
    "basis", "particles to grid", "grid", "grid to particles", "material"};

struct StageClock {
  std::array<double, static_cast<std::size_t>(Stage::kCount)> seconds{};  // [s] per stage
  double& operator[](Stage s) { return seconds[static_cast<std::size_t>(s)]; }
  double operator[](Stage s) const { return seconds[static_cast<std::size_t>(s)]; }
};

// Adds the wall time of its scope to stage s of *clock; nothing when clock is null.
class StageTimer {
 public:
  StageTimer(StageClock* clock, Stage s) : clock_(clock), stage_(s) {
    if (clock_ != nullptr) start_ = std::chrono::steady_clock::now();
  }
  ~StageTimer() {
    if (clock_ != nullptr)
      (*clock_)[stage_] +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

 private:
  StageClock* clock_;
  Stage stage_;
  std::chrono::steady_clock::time_point start_{};
};

}  // namespace mpm
