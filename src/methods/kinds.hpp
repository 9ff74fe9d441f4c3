#pragma once
// Run-time choices resolved once: a config value selects a std::variant alternative by its
// kName; one std::visit then enters fully templated code. An unknown name is an error listing
// the alternatives, never a fallback. Each basis kind declares what the rest of the code asks of
// it (the BasisKindTraits concept below); the questions about "the basis of this run" are
// answered from those declarations, never from a list of kinds.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <concepts>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "basis/ddmpm_settings.hpp"
#include "basis/maxent_settings.hpp"
#include "core/types.hpp"
#include "grid/triangle_mesh.hpp"
#include "mapping/cubic_spline.hpp"
#include "mapping/direct.hpp"
#include "mapping/mls.hpp"
#include "mapping/tls.hpp"
#include "methods/otm_settings.hpp"
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

// dt_crit = factor h / c of the B-splines of degree 1-5 for explicit time integration with lumped
// mass (basis/bspline.cpp).
double bspline_stability_factor(int degree);
// dt_crit = factor h / c of the max-ent basis with these settings, computed as the B-spline
// factors are, from the stiffness and lumped mass of a uniform 1D bar (basis/maxent.cpp).
double maxent_stability_factor(const MaxEntSettings& s);

// The basis kinds. Each carries its basis template (instantiated with the problem's dimension)
// and declares (BasisKindTraits):
// - kName, kDescription: method.basis and `mpm list`; kDegree: the B-spline degree (0: none);
// - supports_dimension(dim), and runs_with<Mapping>(): the mappings it runs with (set-up
//   refuses the other pairs with an input error; their steppers are not compiled);
// - kOnTriangles: it lives on triangles (method.triangles, grid.mesh, particles.per_triangle),
//   kVertexDofs: its DOFs are the vertices of those triangles (a bent roller: a normal per
//   vertex), kOtmNodes: partition of unity and linear completeness on advected nodes
//   (method.solver = "otm", D eq. 4.15-4.16), kUnified: an isoparametric map of the material
//   configuration whose control points reproduce x(X) = X (method.solver = "unified", D 4.5:
//   B-splines; Powell-Sabin splines, D 7.3);
// - stability_factor(): dt_crit = factor h / c with lumped mass on the grid's smallest cell
//   size h (1D bar; the domain-averaged bases take the P1 bound, their gradients being
//   averages of P1's), and boundary_cells(): the cells at each end of the body left out of the
//   interior error norms, where the functions differ from the interior ones.

// P1 (D 2.5): dt <= h / c; a node's function reaches one cell.
struct LinearKind {
  static constexpr std::string_view kName = "linear";
  static constexpr std::string_view kDescription =
      "piecewise-linear (P1) nodal basis, tensor product (D 2.5)";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr int kDegree = 0;
  static constexpr bool kOnTriangles = false, kVertexDofs = false, kOtmNodes = true,
                        kUnified = false;
  template <class Mapping>
  static constexpr bool runs_with() {
    return true;
  }
  double stability_factor() const { return 1.0; }
  int boundary_cells() const { return 1; }
  template <int Dim>
  using type = LinearBasis<Dim>;
  // OTM's basis on the advected nodes.
  void configure_otm(OtmSettings& s, const std::shared_ptr<const TriangleMesh>&) const {
    s.basis = OtmBasis::Linear;
  }
};

// One kind per B-spline degree (method.degree selects it); the degree is a template parameter so
// the stencil size is fixed at compile time. The asymmetric end functions phi_0 .. phi_{p-1} of
// the open knot vector reach p cells into the domain (D Fig. 5.10).
template <int P>
struct BSplineKind {
  static constexpr std::string_view kName = "bspline";
  static constexpr std::string_view kDescription =
      "B-splines of degree method.degree (1-5) from one open uniform knot vector (D 3.1)";
  static constexpr int kDegree = P;
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr bool kOnTriangles = false, kVertexDofs = false, kOtmNodes = false,
                        kUnified = true;
  template <class Mapping>
  static constexpr bool runs_with() {
    return true;
  }
  double stability_factor() const { return bspline_stability_factor(P); }
  int boundary_cells() const { return P; }
  template <int Dim>
  using type = BSplineBasis<Dim, P>;
  // The unified approach's isoparametric map on advected control points.
  void configure_otm(OtmSettings& s, const std::shared_ptr<const TriangleMesh>&) const {
    s.basis = OtmBasis::BSpline;
    s.degree = P;
  }
};

// The kind carries its settings (method.ddmpm_integrals, method.ddmpm_weight), which make_basis
// passes to the basis.
struct DdmpmKind {
  static constexpr std::string_view kName = "ddmpm";
  static constexpr std::string_view kDescription =
      "dual domain MPM: P1 values, smoothed gradients (D 2.6.4)";
  // 1D as in D; 2D and 3D with the weights derived in basis/ddmpm.hpp (method.ddmpm_weight).
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr int kDegree = 0;
  static constexpr bool kOnTriangles = false, kVertexDofs = false, kOtmNodes = false,
                        kUnified = false;
  template <class Mapping>
  static constexpr bool runs_with() {
    return true;
  }
  double stability_factor() const { return 1.0; }
  int boundary_cells() const { return 1; }
  template <int Dim>
  using type = DdmpmBasis<Dim>;
  DdmpmSettings settings;
};

// Domain-averaged bases (D 2.6.4): GIMP with the initial or F-diagonal particle size, and CPDI.
struct UGimpKind {
  static constexpr std::string_view kName = "ugimp";
  static constexpr std::string_view kDescription =
      "uniform GIMP: P1 averaged over the initial particle domain (D 2.6.4, eq. 2.61)";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr int kDegree = 0;
  static constexpr bool kOnTriangles = false, kVertexDofs = false, kOtmNodes = false,
                        kUnified = false;
  template <class Mapping>
  static constexpr bool runs_with() {
    return true;
  }
  double stability_factor() const { return 1.0; }
  int boundary_cells() const { return 1; }
  template <int Dim>
  using type = UGimpBasis<Dim>;
};

struct CpGimpKind {
  static constexpr std::string_view kName = "cpgimp";
  static constexpr std::string_view kDescription =
      "contiguous-particle GIMP: particle domain sized by the diagonal of F (D 2.6.4)";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr int kDegree = 0;
  static constexpr bool kOnTriangles = false, kVertexDofs = false, kOtmNodes = false,
                        kUnified = false;
  template <class Mapping>
  static constexpr bool runs_with() {
    return true;
  }
  double stability_factor() const { return 1.0; }
  int boundary_cells() const { return 1; }
  template <int Dim>
  using type = CpGimpBasis<Dim>;
};

struct CpdiKind {
  static constexpr std::string_view kName = "cpdi";
  static constexpr std::string_view kDescription =
      "CPDI: domain convected by F, P1 interpolated at its corners (D 2.6.4, eq. 2.64)";
  static constexpr bool supports_dimension(int dim) { return dim >= 1 && dim <= 3; }
  static constexpr int kDegree = 0;
  static constexpr bool kOnTriangles = false, kVertexDofs = false, kOtmNodes = false,
                        kUnified = false;
  template <class Mapping>
  static constexpr bool runs_with() {
    return true;
  }
  double stability_factor() const { return 1.0; }
  int boundary_cells() const { return 1; }
  template <int Dim>
  using type = CpdiBasis<Dim>;
};

// CPDI2: quadrilateral domains with tracked corners (2D only; basis/cpdi.hpp).
struct Cpdi2Kind {
  static constexpr std::string_view kName = "cpdi2";
  static constexpr std::string_view kDescription =
      "CPDI2: quadrilateral domains, corners moved with the grid velocity (D 2.6.4; 2D)";
  static constexpr bool supports_dimension(int dim) { return dim == 2; }
  static constexpr int kDegree = 0;
  static constexpr bool kOnTriangles = false, kVertexDofs = false, kOtmNodes = false,
                        kUnified = false;
  template <class Mapping>
  static constexpr bool runs_with() {
    return true;
  }
  double stability_factor() const { return 1.0; }
  int boundary_cells() const { return 1; }
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
  static constexpr int kDegree = 0;
  static constexpr bool kOnTriangles = false, kVertexDofs = false, kOtmNodes = true,
                        kUnified = false;
  // The direct mapping only: with the reconstructions (TLS, MLS, IMLS, cubic spline), whose
  // Gauss points integrate polynomials on each cell while the max-ent functions are not
  // polynomial and span up to six cells, the plate of plate_mms_2d became unstable (TLS:
  // non-finite stress at step 1649; MLS with USF: a mass error of 0.5 at step 1272) where every
  // other basis runs; the cause is not established (docs/verification.md).
  template <class Mapping>
  static constexpr bool runs_with() {
    return std::is_same_v<Mapping, DirectMapping>;
  }
  double stability_factor() const { return maxent_stability_factor(settings); }
  // The cells within d_max zeta of the boundary, where the functions differ from the interior
  // ones (weak Kronecker-delta property).
  int boundary_cells() const { return static_cast<int>(std::ceil(settings.dmax)); }
  template <int Dim>
  using type = MaxEntBasis<Dim>;
  // OTM's basis on the advected nodes, d_i from these settings.
  void configure_otm(OtmSettings& s, const std::shared_ptr<const TriangleMesh>&) const {
    s.basis = OtmBasis::MaxEnt;
    s.maxent = settings;
  }
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
  static constexpr int kDegree = 0;
  static constexpr bool kOnTriangles = true, kVertexDofs = false, kOtmNodes = false,
                        kUnified = true;
  // TLS fits and integrates per triangle (D 6.1.2, 6.3); the other reconstructions (MLS, IMLS,
  // cubic spline) integrate over the grid's rectangular cells.
  template <class Mapping>
  static constexpr bool runs_with() {
    return std::is_same_v<Mapping, DirectMapping> || std::is_same_v<Mapping, TlsMapping>;
  }
  // PS splines are quadratic: the quadratic B-spline's factor on the triangles' length
  // (altitude_factor: on their smallest altitude, a mesh from a file).
  double altitude_factor() const { return bspline_stability_factor(2); }
  double stability_factor() const { return triangle_stability_factor(pattern) * altitude_factor(); }
  int boundary_cells() const { return 1; }
  template <int Dim>
  using type = PowellSabinGridBasis<Dim>;
  // The unified approach's map on the body's triangles: the pattern's on the grid, or the
  // problem's mesh (grid.mesh, which is then the body).
  void configure_otm(OtmSettings& s, const std::shared_ptr<const TriangleMesh>& body_mesh) const {
    s.basis = OtmBasis::PowellSabin;
    s.triangles = pattern;
    s.mesh = body_mesh;
  }
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
  static constexpr int kDegree = 0;
  static constexpr bool kOnTriangles = true, kVertexDofs = true, kOtmNodes = false,
                        kUnified = false;
  template <class Mapping>
  static constexpr bool runs_with() {
    return std::is_same_v<Mapping, DirectMapping> || std::is_same_v<Mapping, TlsMapping>;
  }
  // P1's bound dt <= l / c on the triangles' length l (altitude_factor: on their smallest
  // altitude, a mesh from a file).
  double altitude_factor() const { return 1.0; }
  double stability_factor() const { return triangle_stability_factor(pattern) * altitude_factor(); }
  int boundary_cells() const { return 1; }
  template <int Dim>
  using type = TriangleP1Basis<Dim>;
  TrianglePattern pattern = TrianglePattern::right;
};

// The order is that of `mpm list` and of the choices in error messages (setup/registry.hpp).
using BasisKind =
    std::variant<LinearKind, UGimpKind, CpGimpKind, CpdiKind, Cpdi2Kind, BSplineKind<1>,
                 BSplineKind<2>, BSplineKind<3>, BSplineKind<4>, BSplineKind<5>, DdmpmKind,
                 MaxEntKind, TriangleP1Kind, PowellSabinKind>;

// What the rest of the code asks of a basis kind (see above); a kind of BasisKind that does not
// declare it does not compile. Kinds on triangles carry their pattern and the factor on the
// triangles' smallest altitude.
template <class K>
concept BasisKindTraits = requires(const K& k, int dim) {
  { K::kName } -> std::convertible_to<std::string_view>;
  { K::kDescription } -> std::convertible_to<std::string_view>;
  { K::supports_dimension(dim) } -> std::convertible_to<bool>;
  { K::kDegree } -> std::convertible_to<int>;
  { K::kOnTriangles } -> std::convertible_to<bool>;
  { K::kVertexDofs } -> std::convertible_to<bool>;
  { K::kOtmNodes } -> std::convertible_to<bool>;
  { K::kUnified } -> std::convertible_to<bool>;
  { K::template runs_with<DirectMapping>() } -> std::convertible_to<bool>;
  { k.stability_factor() } -> std::convertible_to<double>;
  { k.boundary_cells() } -> std::convertible_to<int>;
}
&&(!K::kOnTriangles ||
   requires(const K& k) {
     { k.pattern } -> std::convertible_to<TrianglePattern>;
     { k.altitude_factor() } -> std::convertible_to<double>;
   }) &&
    (!K::kVertexDofs || K::kOnTriangles) &&
    (!(K::kOtmNodes || K::kUnified) ||
     requires(const K& k, OtmSettings& s, const std::shared_ptr<const TriangleMesh>& mesh) {
       k.configure_otm(s, mesh);
     });

// Whether a basis kind runs with a mapping (the kind's runs_with; checked by run_settings with
// an input error naming the keys; the steppers of refused pairs are not compiled).
template <class Kind, class Mapping>
constexpr bool supports_mapping() {
  return Kind::template runs_with<Mapping>();
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
DdmpmBasis<Dim> make_basis(const DdmpmKind& kind, const Grid<Dim>& g,
                           const std::shared_ptr<const TriangleMesh>&) {
  return DdmpmBasis<Dim>(g, kind.settings);
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

template <class... Kinds>
constexpr bool kinds_declare_traits(std::variant<Kinds...>*) {
  return (BasisKindTraits<Kinds> && ...);
}
static_assert(kinds_declare_traits(static_cast<BasisKind*>(nullptr)),
              "every basis kind declares the traits of BasisKindTraits");

// The basis of a run, asked through its kind's traits.
inline std::string_view basis_name(const BasisKind& basis) {
  return std::visit([](const auto& k) { return k.kName; }, basis);
}
inline int basis_degree(const BasisKind& basis) {
  return std::visit([](const auto& k) { return k.kDegree; }, basis);
}
inline bool on_triangles(const BasisKind& basis) {
  return std::visit([](const auto& k) { return k.kOnTriangles; }, basis);
}
inline bool otm_nodes(const BasisKind& basis) {
  return std::visit([](const auto& k) { return k.kOtmNodes; }, basis);
}
inline bool unified_dofs(const BasisKind& basis) {
  return std::visit([](const auto& k) { return k.kUnified; }, basis);
}
// dt_crit = factor h / c on the grid's smallest cell size (lumped mass).
inline double stability_factor(const BasisKind& basis) {
  return std::visit([](const auto& k) { return k.stability_factor(); }, basis);
}
// A basis on triangles: the factor on the triangles' smallest altitude (a mesh from a file,
// TriangleMesh::min_altitude); std::logic_error for the others.
inline double altitude_stability_factor(const BasisKind& basis) {
  return std::visit(
      [](const auto& k) -> double {
        if constexpr (std::decay_t<decltype(k)>::kOnTriangles)
          return k.altitude_factor();
        else
          throw std::logic_error("altitude_stability_factor: not a basis on triangles");
      },
      basis);
}
inline int boundary_cells(const BasisKind& basis) {
  return std::visit([](const auto& k) { return k.boundary_cells(); }, basis);
}
// The pattern of a basis on the grid's triangles; none for the others.
inline std::optional<TrianglePattern> triangle_pattern(const BasisKind& basis) {
  return std::visit(
      [](const auto& k) -> std::optional<TrianglePattern> {
        if constexpr (std::decay_t<decltype(k)>::kOnTriangles)
          return k.pattern;
        else
          return std::nullopt;
      },
      basis);
}
// Sets the pattern of a basis on triangles (method.triangles); nothing for the others.
inline void set_triangle_pattern(BasisKind& basis, TrianglePattern pattern) {
  std::visit(
      [pattern](auto& k) {
        if constexpr (std::decay_t<decltype(k)>::kOnTriangles) k.pattern = pattern;
      },
      basis);
}
// The names (method.basis) of the kinds for which `trait(kind)` holds, as "a" or "a" or "b"
// (quoted, for messages), and whether the kind named `name` has it (false for an unknown name).
template <class Trait>
std::string basis_names_where(Trait trait) {
  std::vector<std::string_view> names;
  const auto add = [&](const auto& k) {
    if (trait(k) && std::find(names.begin(), names.end(), k.kName) == names.end())
      names.push_back(k.kName);
  };
  [&]<std::size_t... I>(std::index_sequence<I...>) {
    (add(std::variant_alternative_t<I, BasisKind>{}), ...);
  }
  (std::make_index_sequence<std::variant_size_v<BasisKind>>{});
  std::string out;
  for (std::size_t k = 0; k < names.size(); ++k)
    out += fmt::format("{}\"{}\"", k == 0 ? "" : k + 1 == names.size() ? " or " : ", ", names[k]);
  return out;
}
template <class Trait>
bool basis_named_has(std::string_view name, Trait trait) {
  bool has = false;
  [&]<std::size_t... I>(std::index_sequence<I...>) {
    ((std::variant_alternative_t<I, BasisKind>::kName == name
          ? (has = has || trait(std::variant_alternative_t<I, BasisKind>{}), 0)
          : 0),
     ...);
  }
  (std::make_index_sequence<std::variant_size_v<BasisKind>>{});
  return has;
}

// Whether a basis kind or mapping runs in `dim` dimensions (each declares supports_dimension();
// the driver checks it before instantiating, with an input error naming the key).
template <class T>
constexpr bool supports_dimension(int dim) {
  return T::supports_dimension(dim);
}

// The name of a kind's stepper units (CMakeLists.txt, MPM_BASIS_KIND_UNITS): its kName, with
// the degree after it for the B-splines ("bspline2").
template <class K>
constexpr bool unit_name_is(std::string_view name) {
  if constexpr (K::kDegree > 0)
    return name.size() == K::kName.size() + 1 && name.substr(0, K::kName.size()) == K::kName &&
           name.back() == static_cast<char>('0' + K::kDegree);
  else
    return name == K::kName;
}
// The alternative of BasisKind whose unit name is `unit` (variant_size when none).
constexpr std::size_t basis_kind_index(std::string_view unit) {
  std::size_t found = std::variant_size_v<BasisKind>;
  [&]<std::size_t... I>(std::index_sequence<I...>) {
    ((found == std::variant_size_v<BasisKind> &&
              unit_name_is<std::variant_alternative_t<I, BasisKind>>(unit)
          ? (found = I, 0)
          : 0),
     ...);
  }
  (std::make_index_sequence<std::variant_size_v<BasisKind>>{});
  return found;
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
