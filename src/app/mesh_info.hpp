#pragma once
// `mpm mesh`: reads a Gmsh mesh (or generates a structured triangulation) the way a run will,
// prints what it holds (vertices, triangles, area, the smallest angle and area, the named
// boundaries a configuration can refer to; a body mesh's parts and volume, in 2D or 3D) and
// optionally writes it as a .vtu with each triangle's area and smallest angle, so a mesh can be
// checked before a run.
#include <iosfwd>
#include <string>
#include <vector>

#include "grid/body_mesh.hpp"
#include "grid/triangle_mesh.hpp"

namespace mpm {

struct MeshQuality {
  double total_area = 0.0;
  double min_area = 0.0, max_area = 0.0;
  double min_angle = 0.0;  // [degrees], over every corner of every triangle
  Index min_angle_cell = -1;
  std::vector<double> area, cell_min_angle;  // per triangle ([m^2], [degrees])
};
MeshQuality mesh_quality(const TriangleMesh& m);

void print_mesh_summary(std::ostream& os, const TriangleMesh& m, const MeshQuality& q);

// A body mesh (body.mesh) as a run reads it: its elements, vertices, volume and bounding box,
// the range of element volumes, the smallest angle (triangles) or dihedral angle (tetrahedra)
// and its element, and each physical group with its elements and volume.
template <int Dim>
void print_body_summary(std::ostream& os, const BodyMesh<Dim>& m);

// The mesh with the per-triangle "area" and "min_angle" as a binary .vtu at `path`.
void write_mesh_vtu(const std::string& path, const TriangleMesh& m, const MeshQuality& q);

}  // namespace mpm
