// Writes an unstructured triangulation of a block W x H resting on an incline: the rectangle
// [0, W] x [0, H] turned by ANGLE degrees about the origin, with Gmsh's library (libgmsh-dev,
// installed by scripts/deps.sh), as examples/meshes/incline_30.msh is made:
//   g++ -std=c++20 scripts/incline_mesh.cpp -lgmsh -o incline_mesh
//   ./incline_mesh 30 0.0625 examples/meshes/incline_30.msh   # degrees, edge length, file
//   ./incline_mesh 0 0.0625 examples/meshes/incline_0.msh     # the block not turned
// The sides are the physical groups "base" (on the incline), "top", "left" (uphill end) and
// "right"; Delaunay (Mesh.Algorithm = 5), linear triangles, format 4.1 ASCII, a fixed random
// seed so that the file is reproducible. Used by examples/incline_pressure_2d.toml.
#include <gmsh.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

int main(int argc, char** argv) {
  if (argc != 4 && argc != 6) {
    std::fprintf(stderr, "usage: incline_mesh ANGLE_DEGREES EDGE_LENGTH FILE.msh [W H]\n");
    return 2;
  }
  const double angle = std::atof(argv[1]) * M_PI / 180.0, lc = std::atof(argv[2]);
  const double W = argc == 6 ? std::atof(argv[4]) : 1.0, H = argc == 6 ? std::atof(argv[5]) : 0.5;
  const double c = std::cos(angle), s = std::sin(angle);
  gmsh::initialize();
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::option::setNumber("Mesh.Algorithm", 5);
  gmsh::option::setNumber("Mesh.RandomSeed", 1);
  gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
  gmsh::model::add("incline");
  auto point = [&](double x, double y) {
    return gmsh::model::geo::addPoint(c * x - s * y, s * x + c * y, 0, lc);
  };
  const int p1 = point(0, 0), p2 = point(W, 0), p3 = point(W, H), p4 = point(0, H);
  const int base = gmsh::model::geo::addLine(p1, p2), right = gmsh::model::geo::addLine(p2, p3),
            top = gmsh::model::geo::addLine(p3, p4), left = gmsh::model::geo::addLine(p4, p1);
  const int loop = gmsh::model::geo::addCurveLoop({base, right, top, left});
  const int surface = gmsh::model::geo::addPlaneSurface({loop});
  gmsh::model::geo::synchronize();
  const std::pair<int, const char*> sides[] = {
      {base, "base"}, {right, "right"}, {top, "top"}, {left, "left"}};
  for (const auto& [tag, name] : sides)
    gmsh::model::setPhysicalName(1, gmsh::model::addPhysicalGroup(1, {tag}), name);
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {surface}), "block");
  gmsh::model::mesh::generate(2);
  gmsh::write(argv[3]);
  gmsh::finalize();
  return 0;
}
