#pragma once
// Triangular meshes from Gmsh files (.msh 4.1 and 2.2, ASCII or binary), read by Gmsh's own
// library (libgmsh-dev): every 3-node triangle (element type 2) becomes a cell; each physical
// group of dimension 1 becomes a named boundary (its name, or its number when unnamed) with its
// 2-node line elements as edges. Only the nodes of the triangles are kept, numbered by ascending
// Gmsh node tag. The mesh must lie in the plane z = 0.
#include <string>

#include "grid/body_mesh.hpp"
#include "grid/triangle_mesh.hpp"

namespace mpm {

// InputError naming the file for a file that cannot be read, is not a mesh Gmsh can parse, holds
// no 3-node triangles (higher-order or quadrilateral elements are named), or is not planar.
TriangleMesh read_gmsh_mesh(const std::string& path);

// A body mesh (body.mesh): every 3-node triangle (Dim 2, in the plane z = 0) or 4-node
// tetrahedron (Dim 3, Gmsh type 4) of the file, numbered by ascending Gmsh node tag as above,
// each in the physical group of dimension Dim that holds it (its name, or its number when
// unnamed). InputError naming the file for what read_gmsh_mesh refuses, for other elements of
// the body's dimension (quadrilaterals, hexahedra, prisms, second-order elements: named), for
// no element at all, and for an element in two groups.
template <int Dim>
BodyMesh<Dim> read_gmsh_body(const std::string& path);

// 3 when the file holds elements of dimension 3 (tetrahedra, hexahedra, ...), else 2 (for
// `mpm mesh`, which reports either).
int gmsh_mesh_dimension(const std::string& path);

}  // namespace mpm
