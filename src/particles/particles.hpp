#pragma once
// Material points as a struct of arrays (one contiguous array per field), D Algorithm 2 input.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/types.hpp"
#include "particles/material_state.hpp"

namespace mpm {

// A particle's material: its index in the run's materials (material/material_set.hpp).
using MaterialIndex = std::uint8_t;

template <class Field>
inline constexpr bool kIsMaterialState = std::is_same_v<std::remove_cvref_t<Field>, MaterialState>;

template <int Dim>
struct Particles {
  std::vector<Vec<Dim>> x;       // current position x_p^s [m]
  std::vector<Vec<Dim>> x0;      // initial (material) position x_p^0 [m]
  std::vector<Vec<Dim>> v;       // velocity v_p [m/s]
  std::vector<double> mass;      // m_p [kg] (per unit area in 1D), constant in time
  std::vector<double> volume;    // V_p [m^Dim]
  std::vector<double> volume0;   // V_p^0 [m^Dim]
  std::vector<Mat<Dim>> F;       // deformation gradient F_p
  std::vector<Mat<Dim>> stress;  // Cauchy stress sigma_p [Pa]
  std::vector<Vec<Dim>> body;    // body force per unit mass b_p [m/s^2], refreshed every step
  // The material's internal variables, a row per particle (none for an elastic law; named by
  // the law's kStateNames: set_names when the run starts).
  MaterialState state;
  // The particle's material, an index in the run's materials (0 in a run of one material).
  std::vector<MaterialIndex> material;
  // Stable id: the particle's index when it was created. Re-sorting (state/sort.hpp) moves the
  // particles in memory; outputs list them in id order and error messages name the id.
  std::vector<CompactIndex> id;

  Index size() const { return static_cast<Index>(x.size()); }
  // Derived, not stored (the memory budget: 32 bytes per particle in 3D): the displacement
  // u_p = x_p - x_p^0 [m] and the density rho_p = m_p / V_p [kg/m^3].
  Vec<Dim> displacement(std::size_t i) const { return x[i] - x0[i]; }
  double density(std::size_t i) const { return mass[i] / volume[i]; }

  void resize(Index n) {
    const auto s = static_cast<std::size_t>(n);
    x.resize(s, Vec<Dim>::Zero());
    x0.resize(s, Vec<Dim>::Zero());
    v.resize(s, Vec<Dim>::Zero());
    mass.resize(s, 0.0);
    volume.resize(s, 0.0);
    volume0.resize(s, 0.0);
    F.resize(s, Mat<Dim>::Identity());
    stress.resize(s, Mat<Dim>::Zero());
    body.resize(s, Vec<Dim>::Zero());
    state.resize(s);
    material.resize(s, 0);
    // New particles get the next ids: the creation order (existing ones keep theirs).
    const std::size_t old = id.size();
    id.resize(s);
    if (s > old)
      std::iota(id.begin() + static_cast<std::ptrdiff_t>(old), id.end(),
                static_cast<CompactIndex>(old));
  }

  // A new particle at rest at x (= x0), with F = I and zero stress, numbered `id_value`: how
  // the set-up seeds a body, numbering its particles in the one process's order whichever of
  // them a process keeps (model/problem.hpp, SeedScope).
  // (Through resize, which gives every field its initial value.)
  void append(const Vec<Dim>& at, double vol, double m, CompactIndex id_value) {
    const std::size_t i = x.size();
    resize(size() + 1);
    x[i] = x0[i] = at;
    volume[i] = volume0[i] = vol;
    mass[i] = m;
    id[i] = id_value;
  }
  void reserve(Index n) {
    for_each_field([&](auto& field) { field.reserve(static_cast<std::size_t>(n)); });
  }
  // Capacity for exactly `headroom` particles more than it holds, in every field (a fresh array
  // where the capacity differs). A process of a distributed run keeps room for particles that
  // arrive from others: growing a full array holds the old and the new one at once (the cached
  // stencils' array growing on the edge slabs of a 4-process plate: 365 MB at their peak against
  // the others' 270), while capacity beyond the particles is never written, so it
  // takes no resident memory. (A restart: the whole checkpoint's particles were written.)
  void keep_room(Index headroom) {
    const std::size_t want = x.size() + static_cast<std::size_t>(headroom);
    for_each_field([&](auto& field) {
      if (field.capacity() == want) return;
      if constexpr (kIsMaterialState<decltype(field)>) {
        field.shrink_capacity_to(want);
      } else {
        std::remove_reference_t<decltype(field)> fresh;
        fresh.reserve(want);
        fresh.assign(field.begin(), field.end());
        field.swap(fresh);
      }
    });
  }

  // Keeps the particles i with keep(*this, i), in order, with their ids: the particles one
  // process owns in a distributed run, or those that stay when others migrate (ids stay those of
  // the whole body).
  template <class Keep>
  void keep_with_ids(Keep&& keep) {
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < x.size(); ++i)
      if (keep(std::as_const(*this), i)) kept.push_back(i);
    for_each_field([&](auto& field) {
      for (std::size_t k = 0; k < kept.size(); ++k) {
        if constexpr (kIsMaterialState<decltype(field)>)
          field.copy_row(k, kept[k]);
        else
          field[k] = field[kept[k]];
      }
      field.resize(kept.size());
    });
  }

  // Keeps the first n particles (the ghost copies appended after a process's own particles
  // are dropped this way: stages::GhostParticles).
  void truncate(Index n) {
    for_each_field([&](auto& field) { field.resize(static_cast<std::size_t>(n)); });
  }

  // Particle i's fields appended to `out` as raw bytes, in the order of for_each_field
  // (record_bytes() of them): migration and gathering between processes of one run, whose
  // machines share the representation.
  void pack(std::size_t i, std::vector<std::byte>& out) const {
    fields(*this, [&](const char*, const auto& field) {
      const std::size_t at = out.size();
      if constexpr (kIsMaterialState<decltype(field)>) {
        out.resize(at + field.row_bytes());
        if (field.width() > 0) std::memcpy(out.data() + at, field.row_data(i), field.row_bytes());
      } else {
        out.resize(at + sizeof(field[i]));
        std::memcpy(out.data() + at, &field[i], sizeof(field[i]));
      }
    });
  }
  // Appends the particles of a buffer written by pack() (by particles of the same material
  // state); returns the bytes read.
  std::size_t unpack_append(std::span<const std::byte> in) {
    const std::size_t n = in.size() / record_bytes();
    std::size_t at = 0;
    for (std::size_t k = 0; k < n; ++k)
      fields(*this, [&](const char*, auto& field) {
        if constexpr (kIsMaterialState<decltype(field)>) {
          field.append_row(in.data() + at);
          at += field.row_bytes();
        } else {
          field.emplace_back();
          // (Eigen's fixed-size vectors and matrices are plain arrays of doubles.)
          std::memcpy(static_cast<void*>(&field.back()), in.data() + at, sizeof(field.back()));
          at += sizeof(field.back());
        }
      });
    return at;
  }

  // Empty particles with this one's material state (its names): what unpack_append fills.
  Particles empty_like() const {
    Particles out;
    out.state.set_names(state.names());
    return out;
  }

  // Whether the particles are in id order (never re-sorted, or sorted back).
  bool in_id_order() const {
    for (std::size_t i = 0; i < id.size(); ++i)
      if (id[i] != static_cast<Index>(i)) return false;
    return true;
  }

  // f(name, field) for every per-particle array, ids last: whatever reorders, copies or stores
  // the particles goes through this one list (re-sorting, checkpoints), so a new field cannot be
  // forgotten. The order is that of the checkpoint payload (io/checkpoint.hpp): a new field
  // changes the checkpoint format.
  template <class Fn>
  void for_each_named_field(Fn&& f) {
    fields(*this, f);
  }
  template <class Fn>
  void for_each_named_field(Fn&& f) const {
    fields(*this, f);
  }
  // f(field), the same list without the names.
  template <class Fn>
  void for_each_field(Fn&& f) {
    fields(*this, [&](const char*, auto& field) { f(field); });
  }

  // Bytes of particle state per particle of a material with `state_width` internal variables
  // (the memory figures and checks): x, x0, v, body; mass, volume, volume0; F, stress; the
  // material state; the material's index; id.
  static constexpr std::size_t bytes_per_particle(std::size_t state_width) {
    return 4 * sizeof(Vec<Dim>) + 3 * sizeof(double) + 2 * sizeof(Mat<Dim>) +
           state_width * sizeof(double) + sizeof(MaterialIndex) + sizeof(CompactIndex);
  }
  // Those of these particles (pack()'s record).
  std::size_t record_bytes() const { return bytes_per_particle(state.width()); }

 private:
  template <class Self, class Fn>
  static void fields(Self& p, Fn&& f) {
    f("x", p.x);
    f("x0", p.x0);
    f("v", p.v);
    f("mass", p.mass);
    f("volume", p.volume);
    f("volume0", p.volume0);
    f("F", p.F);
    f("stress", p.stress);
    f("body", p.body);
    f("state", p.state);
    f("material", p.material);
    f("id", p.id);
  }
};

}  // namespace mpm
