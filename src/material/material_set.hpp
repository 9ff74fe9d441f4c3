#pragma once
// The materials of a run: one law per material, each particle's chosen by its index
// (Particles::material). A particle's row of internal variables (MaterialState) has the columns
// of every law in the run, each law's names in one contiguous block; laws that declare the same
// names share their block (the plastic laws: material/hencky_plasticity.hpp). A particle's law
// reads and writes its own block; the other columns of its row stay 0. The stages resolve each
// law once and then loop over its particles (for_each_particle): no virtual call, and no variant
// visit, per particle.
#include <algorithm>
#include <cstddef>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "material/materials.hpp"
#include "particles/particles.hpp"

namespace mpm {

class Materials {
 public:
  // The most materials a run holds (MaterialIndex is one byte).
  static constexpr std::size_t kMaxMaterials = 256;
  // The name of the material of the [material] table.
  static constexpr std::string_view kDefaultName = "material";

  Materials() = default;
  // One material, named `name` ([material]'s by default). Implicit: a run of one material is
  // built from its law.
  template <class Law>
  requires std::is_convertible_v<Law, Material> Materials(
      Law law, std::string name = std::string(kDefaultName)) {  // NOLINT
    add(std::move(name), Material(std::move(law)));
  }

  // Appends a material; its index is the count before. std::logic_error beyond kMaxMaterials or
  // for a name already given (set-up refuses both first, naming the keys).
  void add(std::string name, Material law) {
    if (laws_.size() == kMaxMaterials)
      throw std::logic_error("Materials::add: more than 256 materials");
    if (std::find(names_.begin(), names_.end(), name) != names_.end())
      throw std::logic_error("Materials::add: the name " + name + " twice");
    offsets_.push_back(block_of(mpm::state_names(law), std::string(material_name(law))));
    laws_.push_back(std::move(law));
    names_.push_back(std::move(name));
  }

  std::size_t size() const { return laws_.size(); }
  bool empty() const { return laws_.empty(); }
  const Material& operator[](std::size_t k) const { return laws_.at(k); }
  const std::string& name(std::size_t k) const { return names_.at(k); }
  // The index of the material named `name`, or size() when there is none.
  std::size_t find(std::string_view name) const {
    return static_cast<std::size_t>(std::find(names_.begin(), names_.end(), name) - names_.begin());
  }
  // The law of a run of one material: what the problems with an exact solution, OTM and the
  // FEM reference take (set-up refuses several materials there); std::logic_error otherwise.
  const Material& single() const {
    if (laws_.size() != 1)
      throw std::logic_error("Materials::single: a run of " + std::to_string(laws_.size()) +
                             " materials");
    return laws_.front();
  }

  // Every column of the particles' rows of internal variables, the laws' blocks in the order
  // they first appear (Particles::state.set_names).
  std::span<const std::string_view> state_names() const { return columns_; }
  // The first column of material k's block (0 for a law without internal variables).
  std::size_t state_offset(std::size_t k) const { return offsets_.at(k); }
  // Material k's initial density rho0 [kg/m^3] (a particle's mass is rho0 V0).
  double density(std::size_t k) const {
    return std::visit([](const auto& law) { return law.p.density; }, laws_.at(k));
  }
  // The largest elastic wave speed of the materials [m/s]: the explicit stability limit's.
  double max_wave_speed() const {
    double c = 0.0;
    for (const Material& m : laws_) c = std::max(c, wave_speed(m));
    return c;
  }
  // The names of the materials' laws, as "a" or "a, b and c" (each once), for messages.
  std::string law_names() const {
    std::vector<std::string_view> seen;
    for (const Material& m : laws_)
      if (std::find(seen.begin(), seen.end(), material_name(m)) == seen.end())
        seen.push_back(material_name(m));
    std::string out;
    for (std::size_t k = 0; k < seen.size(); ++k)
      out += (k == 0 ? "" : k + 1 == seen.size() ? " and " : ", ") + std::string(seen[k]);
    return out;
  }

  // f(law, k, offset, i) for each particle i in [b, e) of `of` (the particles' material
  // indices), material after material: the law (a value of material k's alternative of
  // Material) is resolved once per material; `offset` is the first column of its block. With one
  // material every particle is its (no test of the index), in order.
  template <class Fn>
  void for_each_particle(const std::vector<MaterialIndex>& of, std::size_t b, std::size_t e,
                         Fn&& f) const {
    for (std::size_t k = 0; k < laws_.size(); ++k) {
      const std::size_t offset = offsets_[k];
      std::visit(
          [&](const auto& law) {
            if (laws_.size() == 1) {
              for (std::size_t i = b; i < e; ++i) f(law, k, offset, i);
            } else {
              for (std::size_t i = b; i < e; ++i)
                if (of[i] == k) f(law, k, offset, i);
            }
          },
          laws_[k]);
    }
  }

 private:
  // The offset of a block of `names` among the columns: where the same names already stand in
  // the same order, else appended. A law whose names clash with another's block in part is a
  // logic_error: laws that share a name share its block (test_material_set.cpp checks every pair
  // of laws).
  std::size_t block_of(std::span<const std::string_view> names, const std::string& law) {
    if (names.empty()) return 0;
    for (std::size_t at = 0; at + names.size() <= columns_.size(); ++at)
      if (std::equal(names.begin(), names.end(),
                     columns_.begin() + static_cast<std::ptrdiff_t>(at)))
        return at;
    for (const std::string_view n : names)
      if (std::find(columns_.begin(), columns_.end(), n) != columns_.end())
        throw std::logic_error("Materials: the law " + law + " declares the internal variable " +
                               std::string(n) + " in another block than an earlier law");
    const std::size_t at = columns_.size();
    columns_.insert(columns_.end(), names.begin(), names.end());
    return at;
  }

  std::vector<Material> laws_;
  std::vector<std::string> names_;
  std::vector<std::size_t> offsets_;
  std::vector<std::string_view> columns_;  // static names of the laws
};

// The particle i's stress update failed (see failed_update, material/materials.hpp): the law's
// residual [Pa], or nullopt.
template <int Dim>
std::optional<double> failed_update(const Materials& m, const Particles<Dim>& P, std::size_t i) {
  const std::size_t k = m.size() == 1 ? 0 : P.material[i];
  const auto row = P.state[i];
  return failed_update<Dim>(m[k], P.stress[i], row.subspan(m.state_offset(k)), P.F[i]);
}

}  // namespace mpm
