// Writes an unstructured triangulation of the plate [0, L]^2 (D Fig. 3.6: the plate of
// plate_mms_2d on "an unstructured triangular grid") with Gmsh's library (libgmsh-dev,
// installed by scripts/deps.sh), as examples/meshes/plate_unstructured_*.msh are made:
//   g++ -std=c++20 scripts/plate_mesh.cpp -lgmsh -o plate_mesh
//   ./plate_mesh 0.125 examples/meshes/plate_unstructured_8.msh   # target edge length, file
// The sides are the physical groups "left", "right", "bottom", "top" (mpm names the sides of
// the bounding box "x-", "x+", "y-", "y+" itself); Delaunay (Mesh.Algorithm = 5), linear
// triangles, format 4.1 ASCII, a fixed random seed so that the file is reproducible.
#include <gmsh.h>

#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) {
  if (argc != 3 && argc != 4) {
    std::fprintf(stderr, "usage: plate_mesh EDGE_LENGTH FILE.msh [L]\n");
    return 2;
  }
  const double lc = std::atof(argv[1]);
  const double L = argc == 4 ? std::atof(argv[3]) : 1.0;
  gmsh::initialize();
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::option::setNumber("Mesh.Algorithm", 5);
  gmsh::option::setNumber("Mesh.RandomSeed", 1);
  gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
  gmsh::model::add("plate");
  const int p1 = gmsh::model::geo::addPoint(0, 0, 0, lc),
            p2 = gmsh::model::geo::addPoint(L, 0, 0, lc),
            p3 = gmsh::model::geo::addPoint(L, L, 0, lc),
            p4 = gmsh::model::geo::addPoint(0, L, 0, lc);
  const int bottom = gmsh::model::geo::addLine(p1, p2), right = gmsh::model::geo::addLine(p2, p3),
            top = gmsh::model::geo::addLine(p3, p4), left = gmsh::model::geo::addLine(p4, p1);
  const int loop = gmsh::model::geo::addCurveLoop({bottom, right, top, left});
  const int surface = gmsh::model::geo::addPlaneSurface({loop});
  gmsh::model::geo::synchronize();
  const std::pair<int, const char*> sides[] = {
      {bottom, "bottom"}, {right, "right"}, {top, "top"}, {left, "left"}};
  for (const auto& [tag, name] : sides)
    gmsh::model::setPhysicalName(1, gmsh::model::addPhysicalGroup(1, {tag}), name);
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {surface}), "plate");
  gmsh::model::mesh::generate(2);
  gmsh::write(argv[2]);
  gmsh::finalize();
  return 0;
}
