#pragma once
// Triangular meshes from Gmsh files (.msh 4.1 and 2.2, ASCII or binary), read by Gmsh's own
// library (libgmsh-dev): every 3-node triangle (element type 2) becomes a cell; each physical
// group of dimension 1 becomes a named boundary (its name, or its number when unnamed) with its
// 2-node line elements as edges. Only the nodes of the triangles are kept, numbered by ascending
// Gmsh node tag. The mesh must lie in the plane z = 0.
#include <string>

#include "grid/triangle_mesh.hpp"

namespace mpm {

// InputError naming the file for a file that cannot be read, is not a mesh Gmsh can parse, holds
// no 3-node triangles (higher-order or quadrilateral elements are named), or is not planar.
TriangleMesh read_gmsh_mesh(const std::string& path);

}  // namespace mpm
