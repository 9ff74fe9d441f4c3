#pragma once
// Gmsh files for tests that run on meshes read from a file (grid.mesh).
#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "grid/triangle_mesh.hpp"

namespace mpm::test {

// `m` as a Gmsh 2.2 ASCII file in the temporary directory: node tags 1.. in vertex order (the
// reader numbers by ascending tag), the triangles in order in one physical surface, and each of
// `lines` as a named physical group of line elements. Returns the path; `keep` triangles only
// when given (the others are left out).
inline std::string write_msh(
    const TriangleMesh& m, const std::string& name, const std::vector<bool>& keep = {},
    const std::map<std::string, std::vector<TriangleMesh::Edge>>& lines = {}) {
  const auto path = std::filesystem::temp_directory_path() /
                    fmt::format("mpm_test_{}_{}.msh", name, static_cast<long>(getpid()));
  std::ofstream f(path);
  f << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
  if (!lines.empty()) {
    f << "$PhysicalNames\n" << lines.size() + 1 << "\n";
    int tag = 1;
    for (const auto& [group, edges] : lines) f << "1 " << ++tag << " \"" << group << "\"\n";
    f << "2 1 \"body\"\n$EndPhysicalNames\n";
  }
  f << "$Nodes\n" << m.num_vertices() << "\n";
  for (Index v = 0; v < m.num_vertices(); ++v)
    f << fmt::format("{} {:.17g} {:.17g} 0\n", v + 1, m.vertex(v)[0], m.vertex(v)[1]);
  std::size_t count = 0;
  for (Index c = 0; c < m.num_cells(); ++c)
    count += keep.empty() || keep[static_cast<std::size_t>(c)] ? 1 : 0;
  for (const auto& [group, edges] : lines) count += edges.size();
  f << "$EndNodes\n$Elements\n" << count << "\n";
  Index k = 0;
  int tag = 1;
  for (const auto& [group, edges] : lines) {
    ++tag;
    for (const auto& e : edges)
      f << fmt::format("{} 1 2 {} {} {} {}\n", ++k, tag, tag, e[0] + 1, e[1] + 1);
  }
  for (Index c = 0; c < m.num_cells(); ++c) {
    if (!keep.empty() && !keep[static_cast<std::size_t>(c)]) continue;
    const auto& t = m.cell_vertices(c);
    f << fmt::format("{} 2 2 1 1 {} {} {}\n", ++k, t[0] + 1, t[1] + 1, t[2] + 1);
  }
  f << "$EndElements\n";
  return path.string();
}

}  // namespace mpm::test
