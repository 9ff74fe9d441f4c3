#pragma once
// Run-time choices resolved once: a config value selects a std::variant alternative by its
// kName; one std::visit then enters fully templated code. An unknown name is an error listing
// the alternatives, never a fallback.
#include <fmt/format.h>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>

#include "basis/maxent_settings.hpp"
#include "core/types.hpp"
#include "grid/triangle_mesh.hpp"
#include "mapping/cubic_spline.hpp"
#include "mapping/direct.hpp"
#include "mapping/mls.hpp"
#include "mapping/tls.hpp"
#include "scheme/schemes.hpp"

namespace mpm {

// The basis templates (basis/*.hpp; basis/bases.hpp has them all), only declared here: a kind
// names its basis, and the generated stepper unit of a kind includes that basis's header
// (CMakeLists.txt, MPM_BASIS_KIND_HEADERS), so that an edit to one basis rebuilds only its units.
template <int Dim>
class LinearBasis;
template <int Dim, int Degree>
class BSplineBasis;
template <int Dim>
class UGimpBasis;
template <int Dim>
class TriangleP1Basis;
template <int Dim>
class PowellSabinGridBasis;
template <int Dim>
class CpGimpBasis;
template <int Dim>
class CpdiBasis;
template <int Dim>
class Cpdi2Basis;
template <int Dim>
class DdmpmBasis;
template <int Dim>
class MaxEntBasis;

// Basis kinds carry the basis template, instantiated with the problem's dimension.
struct LinearKind {
  static constexpr std::string_view kName = "linear";
  static constexpr std::string_view kDescription =
      "piecewise-linear (P1) nodal basis, tensor product (D 2.5)";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr int kDegree = 0;  // not a B-spline
  template <int Dim>
  using type = LinearBasis<Dim>;
};

// One kind per B-spline degree (method.degree selects it); the degree is a template parameter so
// the stencil size is fixed at compile time.
// dt_crit = factor h / c of the B-splines of degree 1-5 for explicit time integration with lumped
// mass (basis/bspline.cpp).
double bspline_stability_factor(int degree);

template <int P>
struct BSplineKind {
  static constexpr std::string_view kName = "bspline";
  static constexpr std::string_view kDescription =
      "B-splines of degree method.degree (1-5) from one open uniform knot vector (D 3.1)";
  static constexpr int kDegree = P;
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  template <int Dim>
  using type = BSplineBasis<Dim, P>;
};

struct DdmpmKind {
  static constexpr std::string_view kName = "ddmpm";
  static constexpr std::string_view kDescription =
      "dual domain MPM: P1 values, smoothed gradients (D 2.6.4)";
  // 1D as in D; 2D and 3D with the tensor-product weight alpha derived in basis/ddmpm.hpp.
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr int kDegree = 0;  // not a B-spline
  template <int Dim>
  using type = DdmpmBasis<Dim>;
};

// Domain-averaged bases (D 2.6.4): GIMP with the initial or F-diagonal particle size, and CPDI.
struct UGimpKind {
  static constexpr std::string_view kName = "ugimp";
  static constexpr std::string_view kDescription =
      "uniform GIMP: P1 averaged over the initial particle domain (D 2.6.4, eq. 2.61)";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr int kDegree = 0;  // not a B-spline
  template <int Dim>
  using type = UGimpBasis<Dim>;
};

struct CpGimpKind {
  static constexpr std::string_view kName = "cpgimp";
  static constexpr std::string_view kDescription =
      "contiguous-particle GIMP: particle domain sized by the diagonal of F (D 2.6.4)";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr int kDegree = 0;  // not a B-spline
  template <int Dim>
  using type = CpGimpBasis<Dim>;
};

struct CpdiKind {
  static constexpr std::string_view kName = "cpdi";
  static constexpr std::string_view kDescription =
      "CPDI: domain convected by F, P1 interpolated at its corners (D 2.6.4, eq. 2.64)";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr int kDegree = 0;  // not a B-spline
  template <int Dim>
  using type = CpdiBasis<Dim>;
};

// CPDI2: quadrilateral domains with tracked corners (2D only; basis/cpdi.hpp).
struct Cpdi2Kind {
  static constexpr std::string_view kName = "cpdi2";
  static constexpr std::string_view kDescription =
      "CPDI2: quadrilateral domains, corners moved with the grid velocity (D 2.6.4; 2D)";
  static constexpr bool supports_dimension(int dim) { return dim == 2; }
  static constexpr int kDegree = 0;  // not a B-spline
  template <int Dim>
  using type = Cpdi2Basis<Dim>;
};

// Local max-ent basis on the grid nodes (D 4.3); the kind carries its settings (method.maxent_*),
// which make_basis passes to the basis.
struct MaxEntKind {
  static constexpr std::string_view kName = "maxent";
  static constexpr std::string_view kDescription =
      "local maximum-entropy basis on the grid nodes, cubic-spline prior of radius "
      "method.maxent_dmax cells, Newton for the multipliers (D 4.3)";
  static constexpr bool supports_dimension(int dim) { return dim == 1 || dim == 2; }
  static constexpr int kDegree = 0;  // not a B-spline
  template <int Dim>
  using type = MaxEntBasis<Dim>;
  MaxEntSettings settings;
};
// Quadratic Powell-Sabin splines on a structured triangulation of the grid
// (basis/powell_sabin.hpp; D 3.3, PS-MPM); the kind carries the pattern (method.triangles).
struct PowellSabinKind {
  static constexpr std::string_view kName = "powell_sabin";
  static constexpr std::string_view kDescription =
      "quadratic Powell-Sabin splines (C1, three per vertex) on the grid's cells split into "
      "triangles by method.triangles (D 3.3, PS-MPM; 2D, direct mapping)";
  static constexpr bool supports_dimension(int dim) { return dim == 2; }
  static constexpr int kDegree = 0;  // not a B-spline
  template <int Dim>
  using type = PowellSabinGridBasis<Dim>;
  TrianglePattern pattern = TrianglePattern::right;
};

// P1 on a structured triangulation of the grid (basis/p1_triangle.hpp); the kind carries the
// pattern (method.triangles), which make_basis passes to the basis.
struct TriangleP1Kind {
  static constexpr std::string_view kName = "p1_triangles";
  static constexpr std::string_view kDescription =
      "P1 on triangles: each grid cell split into 2 (method.triangles = \"right\") or 4 "
      "(\"criss_cross\") triangles (D 3.3; 2D, direct mapping)";
  static constexpr bool supports_dimension(int dim) { return dim == 2; }
  static constexpr int kDegree = 0;  // not a B-spline
  template <int Dim>
  using type = TriangleP1Basis<Dim>;
  TrianglePattern pattern = TrianglePattern::right;
};
// dt_crit = factor h / c of the max-ent basis with these settings, computed as the B-spline
// factors are, from the stiffness and lumped mass of a uniform 1D bar (basis/maxent.cpp).
double maxent_stability_factor(const MaxEntSettings& s);

// The order is that of `mpm list` and of the choices in error messages (setup/registry.hpp).
using BasisKind =
    std::variant<LinearKind, UGimpKind, CpGimpKind, CpdiKind, Cpdi2Kind, BSplineKind<1>,
                 BSplineKind<2>, BSplineKind<3>, BSplineKind<4>, BSplineKind<5>, DdmpmKind,
                 MaxEntKind, TriangleP1Kind, PowellSabinKind>;

// Whether a basis kind runs with a mapping (checked by run_settings with an input error naming
// the keys; the steppers of refused pairs are not compiled). Max-ent runs with the direct
// mapping only: with the reconstructions (TLS, MLS, IMLS, cubic spline), whose Gauss points
// integrate polynomials on each cell while the max-ent functions are not polynomial and span up
// to six cells, the plate of plate_mms_2d became unstable (TLS: non-finite stress at step 1649;
// MLS with USF: a mass error of 0.5 at step 1272) where every other basis runs; the cause is not
// established (docs/verification.md).
// P1 and PS splines on triangles run with the direct and the TLS mapping (TLS fits and
// integrates per triangle, D 6.1.2, 6.3); the other reconstructions (MLS, IMLS, cubic spline)
// integrate over the grid's rectangular cells.
template <class Kind, class Mapping>
constexpr bool supports_mapping() {
  if constexpr (std::is_same_v<Kind, MaxEntKind>)
    return std::is_same_v<Mapping, DirectMapping>;
  else if constexpr (std::is_same_v<Kind, TriangleP1Kind> || std::is_same_v<Kind, PowellSabinKind>)
    return std::is_same_v<Mapping, DirectMapping> || std::is_same_v<Mapping, TlsMapping>;
  else
    return true;
}

// The basis of a kind on a grid; a kind with settings passes them on (the more specialised
// overload). `mesh`: the run's triangles from a file (grid.mesh; Problem::mesh), null for a
// structured triangulation of the grid; set-up allows it for the triangle kinds only.
// Instantiated where the basis header is included (the kind's stepper unit).
template <int Dim, class Kind>
typename Kind::template type<Dim> make_basis(const Kind&, const Grid<Dim>& g,
                                             const std::shared_ptr<const TriangleMesh>&) {
  return typename Kind::template type<Dim>(g);
}
template <int Dim>
MaxEntBasis<Dim> make_basis(const MaxEntKind& kind, const Grid<Dim>& g,
                            const std::shared_ptr<const TriangleMesh>&) {
  return MaxEntBasis<Dim>(g, kind.settings);
}
template <int Dim>
TriangleP1Basis<Dim> make_basis(const TriangleP1Kind& kind, const Grid<Dim>& g,
                                const std::shared_ptr<const TriangleMesh>& mesh) {
  return mesh ? TriangleP1Basis<Dim>(mesh) : TriangleP1Basis<Dim>(g, kind.pattern);
}
template <int Dim>
PowellSabinGridBasis<Dim> make_basis(const PowellSabinKind& kind, const Grid<Dim>& g,
                                     const std::shared_ptr<const TriangleMesh>& mesh) {
  return mesh ? PowellSabinGridBasis<Dim>(mesh) : PowellSabinGridBasis<Dim>(g, kind.pattern);
}
using MappingKind =
    std::variant<DirectMapping, CubicSplineMapping, TlsMapping, MlsMapping, ImlsMapping>;

// Whether a basis kind or mapping runs in `dim` dimensions (each declares supports_dimension();
// the driver checks it before instantiating, with an input error naming the key).
template <class T>
constexpr bool supports_dimension(int dim) {
  return T::supports_dimension(dim);
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
