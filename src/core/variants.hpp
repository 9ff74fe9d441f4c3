#pragma once
// Run-time choices resolved once: a config value selects a std::variant alternative by its
// kName; one std::visit then enters fully templated code. An unknown name is an error listing
// the alternatives, never a fallback.
#include <fmt/format.h>
#include <string>
#include <string_view>
#include <variant>

#include "basis/linear.hpp"
#include "core/types.hpp"
#include "mapping/direct.hpp"
#include "scheme/schemes.hpp"

namespace mpm {

// Basis kinds carry the basis template, instantiated with the problem's dimension.
struct LinearKind {
  static constexpr std::string_view kName = "linear";
  template <int Dim>
  using type = LinearBasis<Dim>;
};

using BasisKind = std::variant<LinearKind>;
using MappingKind = std::variant<DirectMapping>;

template <class Variant, std::size_t I = 0>
Variant choose_alternative(std::string_view name, std::string_view key, std::string choices = {}) {
  if constexpr (I < std::variant_size_v<Variant>) {
    using Alt = std::variant_alternative_t<I, Variant>;
    if (name == Alt::kName) return Variant(std::in_place_index<I>);
    if (!choices.empty()) choices += ", ";
    choices += std::string(Alt::kName);
    return choose_alternative<Variant, I + 1>(name, key, std::move(choices));
  } else {
    throw InputError(
        fmt::format("{} = \"{}\" is not available; choose one of: {}", key, name, choices));
  }
}

}  // namespace mpm
