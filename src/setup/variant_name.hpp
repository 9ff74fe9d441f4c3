#pragma once
// The name of the alternative a method variant holds (BasisKind, MappingKind, Scheme): each
// alternative declares kName (setup/registry.hpp builds the registry from the same names).
#include <string_view>
#include <type_traits>
#include <variant>

namespace mpm {

template <class Variant>
std::string_view name_of(const Variant& v) {
  return std::visit([](const auto& a) { return std::decay_t<decltype(a)>::kName; }, v);
}

}  // namespace mpm
