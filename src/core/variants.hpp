#pragma once
// Run-time choices resolved once: a config value selects a std::variant alternative by its
// kName; one std::visit then enters fully templated code. An unknown name is an error listing
// the alternatives, never a fallback.
#include <fmt/format.h>
#include <string>
#include <string_view>
#include <variant>

#include "basis/bspline.hpp"
#include "basis/cpdi.hpp"
#include "basis/ddmpm.hpp"
#include "basis/gimp.hpp"
#include "basis/linear.hpp"
#include "core/types.hpp"
#include "mapping/cubic_spline.hpp"
#include "mapping/direct.hpp"
#include "mapping/mls.hpp"
#include "mapping/tls.hpp"
#include "scheme/schemes.hpp"

namespace mpm {

// Basis kinds carry the basis template, instantiated with the problem's dimension.
struct LinearKind {
  static constexpr std::string_view kName = "linear";
  template <int Dim>
  using type = LinearBasis<Dim>;
};

// One kind per B-spline degree (method.degree selects it); the degree is a template parameter so
// the stencil size is fixed at compile time.
template <int P>
struct BSplineKind {
  static constexpr std::string_view kName = "bspline";
  static constexpr int kDegree = P;
  template <int Dim>
  using type = BSplineBasis<Dim, P>;
};

struct DdmpmKind {
  static constexpr std::string_view kName = "ddmpm";
  // 1D as in D; 2D with the tensor-product weight alpha derived in basis/ddmpm.hpp.
  static constexpr bool supports_dimension(int dim) { return dim == 1 || dim == 2; }
  template <int Dim>
  using type = DdmpmBasis<Dim>;
};

// Domain-averaged bases (D 2.6.4): GIMP with the initial or F-diagonal particle size, and CPDI.
struct UGimpKind {
  static constexpr std::string_view kName = "ugimp";
  template <int Dim>
  using type = UGimpBasis<Dim>;
};

struct CpGimpKind {
  static constexpr std::string_view kName = "cpgimp";
  template <int Dim>
  using type = CpGimpBasis<Dim>;
};

struct CpdiKind {
  static constexpr std::string_view kName = "cpdi";
  template <int Dim>
  using type = CpdiBasis<Dim>;
};

// CPDI2: quadrilateral domains with tracked corners (2D only; basis/cpdi.hpp).
struct Cpdi2Kind {
  static constexpr std::string_view kName = "cpdi2";
  static constexpr bool supports_dimension(int dim) { return dim == 2; }
  template <int Dim>
  using type = Cpdi2Basis<Dim>;
};

using BasisKind =
    std::variant<LinearKind, UGimpKind, CpGimpKind, CpdiKind, Cpdi2Kind, DdmpmKind, BSplineKind<1>,
                 BSplineKind<2>, BSplineKind<3>, BSplineKind<4>, BSplineKind<5>>;
using MappingKind =
    std::variant<DirectMapping, CubicSplineMapping, TlsMapping, MlsMapping, ImlsMapping>;

// Whether a basis kind or mapping runs in `dim` dimensions: those that are not
// dimension-generic declare supports_dimension(); the run set-up checks it before instantiating.
template <class T>
constexpr bool supports_dimension(int dim) {
  if constexpr (requires { T::supports_dimension(dim); })
    return T::supports_dimension(dim);
  else
    return true;
}

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
