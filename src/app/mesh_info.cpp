#include "app/mesh_info.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <ostream>
#include <string>
#include <vector>

#include "io/output.hpp"

namespace mpm {

MeshQuality mesh_quality(const TriangleMesh& m) {
  MeshQuality q;
  const auto n = static_cast<std::size_t>(m.num_cells());
  q.area.resize(n);
  q.cell_min_angle.resize(n);
  q.min_area = q.min_angle = std::numeric_limits<double>::infinity();
  for (Index c = 0; c < m.num_cells(); ++c) {
    const auto& t = m.cell_vertices(c);
    double smallest = 180.0;
    for (std::size_t i = 0; i < 3; ++i) {
      const Vec<2> a = m.vertex(t[(i + 1) % 3]) - m.vertex(t[i]);
      const Vec<2> b = m.vertex(t[(i + 2) % 3]) - m.vertex(t[i]);
      const double angle = std::atan2(std::abs(a[0] * b[1] - a[1] * b[0]), a.dot(b));
      smallest = std::min(smallest, angle * 180.0 / std::numbers::pi);
    }
    const auto k = static_cast<std::size_t>(c);
    q.area[k] = m.cell_volume(c);
    q.cell_min_angle[k] = smallest;
    q.total_area += q.area[k];
    q.min_area = std::min(q.min_area, q.area[k]);
    q.max_area = std::max(q.max_area, q.area[k]);
    if (smallest < q.min_angle) q.min_angle = smallest, q.min_angle_cell = c;
  }
  return q;
}

void print_mesh_summary(std::ostream& os, const TriangleMesh& m, const MeshQuality& q) {
  os << fmt::format("{}\n", m.source());
  os << fmt::format("  {} vertices, {} triangles, area {:.10g} m^2\n", m.num_vertices(),
                    m.num_cells(), q.total_area);
  os << fmt::format("  bounding box [{:.6g}, {:.6g}] x [{:.6g}, {:.6g}] m\n", m.lower()[0],
                    m.upper()[0], m.lower()[1], m.upper()[1]);
  os << fmt::format("  triangle area {:.4g} to {:.4g} m^2 (ratio {:.3g})\n", q.min_area, q.max_area,
                    q.max_area / q.min_area);
  os << fmt::format("  smallest angle {:.3g} degrees (triangle {})\n", q.min_angle,
                    q.min_angle_cell);
  const auto names = m.boundary_names();
  if (names.empty()) {
    os << "  no named boundaries (Gmsh: physical groups of dimension 1)\n";
    return;
  }
  os << "  boundaries (\"x-\", \"x+\", \"y-\", \"y+\": the boundary edges on the sides of the "
        "bounding box, where the conditions of a run act (boundary.left, right, bottom, top; "
        "the plate's rollers); the others: the file's physical groups of lines (boundary.fixed, "
        "boundary.roller, boundary.loaded):\n";
  for (const auto& name : names) {
    const auto& b = m.boundary(name);
    double length = 0.0;
    for (const auto& e : b.edges) length += (m.vertex(e[1]) - m.vertex(e[0])).norm();
    os << fmt::format("    \"{}\": {} edges, {} vertices, length {:.10g} m\n", name, b.edges.size(),
                      b.vertices.size(), length);
  }
}

template <int Dim>
void print_body_summary(std::ostream& os, const BodyMesh<Dim>& m) {
  const char* kind = Dim == 2 ? "triangles" : "tetrahedra";
  const char* unit = Dim == 2 ? "m^2" : "m^3";
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0, worst = 180.0;
  Index worst_at = 0;
  std::vector<double> group_volume(m.group_names().size() + 1, 0.0);
  std::vector<Index> group_count(m.group_names().size() + 1, 0);
  for (Index e = 0; e < m.num_elements(); ++e) {
    lo = std::min(lo, m.element_volume(e));
    hi = std::max(hi, m.element_volume(e));
    const double a = m.min_angle(e);
    if (a < worst) worst = a, worst_at = e;
    const auto g = static_cast<std::size_t>(m.group(e) + 1);  // 0: in no group
    group_volume[g] += m.element_volume(e);
    ++group_count[g];
  }
  os << fmt::format("as a body (body.mesh, {}D): {} {}, {} vertices, {} {:.10g} {}\n", Dim,
                    m.num_elements(), kind, m.num_vertices(), Dim == 2 ? "area" : "volume",
                    m.volume(), unit);
  std::string box;
  for (int d = 0; d < Dim; ++d)
    box += fmt::format("{}[{:.6g}, {:.6g}]", d == 0 ? "" : " x ", m.lower()[d], m.upper()[d]);
  os << fmt::format("  bounding box {} m\n", box);
  os << fmt::format("  element {} {:.4g} to {:.4g} {} (ratio {:.3g})\n",
                    Dim == 2 ? "area" : "volume", lo, hi, unit, hi / lo);
  os << fmt::format("  smallest {} {:.3g} degrees (element {})\n",
                    Dim == 2 ? "angle" : "dihedral angle", worst, m.tag(worst_at));
  if (m.group_names().empty()) {
    os << fmt::format("  no parts (Gmsh: physical groups of dimension {})\n", Dim);
    return;
  }
  os << fmt::format("  parts (physical groups of dimension {}):\n", Dim);
  for (std::size_t g = 0; g < m.group_names().size(); ++g)
    os << fmt::format("    \"{}\": {} {}, {} {:.10g} {}\n", m.group_names()[g], group_count[g + 1],
                      kind, Dim == 2 ? "area" : "volume", group_volume[g + 1], unit);
  if (group_count[0] > 0)
    os << fmt::format("    in no part: {} {}, {} {:.10g} {}\n", group_count[0], kind,
                      Dim == 2 ? "area" : "volume", group_volume[0], unit);
}
template void print_body_summary<2>(std::ostream&, const BodyMesh<2>&);
template void print_body_summary<3>(std::ostream&, const BodyMesh<3>&);

void write_mesh_vtu(const std::string& path, const TriangleMesh& m, const MeshQuality& q) {
  io::write_file_atomic(
      path, io::triangle_mesh_vtu(m, {}, {{"area", &q.area}, {"min_angle", &q.cell_min_angle}},
                                  /*binary=*/true));
}

}  // namespace mpm
