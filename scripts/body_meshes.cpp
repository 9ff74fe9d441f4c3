// Writes the body meshes of the examples and tests (body.mesh) with Gmsh's library (libgmsh-dev,
// installed by scripts/deps.sh), reproducibly (fixed random seed, Delaunay):
//   g++ -std=c++20 scripts/body_meshes.cpp -lgmsh -o body_meshes && ./body_meshes
// run in the repository's root. It writes
//   examples/meshes/plate_hole.msh   the square [0, 1]^2 with a hole of radius 0.2 at its centre,
//                                    edge length 0.04 (2D, physical surface "plate")
//   examples/meshes/sphere.msh       a sphere of radius 0.1 m centred at (0.25, 0.15, 0.25),
//                                    edge 0.025 m (3D tetrahedra, physical volume "ball")
//   tests/data/meshes/cube_tets.msh  the unit cube, edge 0.5, tetrahedra (MSH 4.1), volume
//                                    groups "lower" (z < 0.5) and "upper"
//   tests/data/meshes/cube_tets_v22.msh  the same in MSH 2.2
//   tests/data/meshes/cube_hexes.msh the unit cube of 2 x 2 x 2 hexahedra (refused as a body)
//   tests/data/meshes/layered_column.msh  the column [0, 0.2] x [0, 1] of structured right
//                                    triangles (h = 0.05), surface groups "lower" (y < 0.5) and
//                                    "upper"
//   examples/meshes/slope_layered.msh  a 6 m high slope of 45 degrees, group "slope", on a 4 m
//                                    thick foundation 20 m long, group "foundation" (edge 0.5 m)
#include <gmsh.h>

#include <string>
#include <vector>

namespace {

void start(const char* name) {
  gmsh::model::add(name);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::option::setNumber("Mesh.Algorithm", 5);
  gmsh::option::setNumber("Mesh.Algorithm3D", 1);
  gmsh::option::setNumber("Mesh.RandomSeed", 1);
  gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
  gmsh::option::setNumber("Mesh.SaveAll", 0);
}

void write(const std::string& file, int dim, double version = 4.1) {
  gmsh::model::mesh::generate(dim);
  gmsh::option::setNumber("Mesh.MshFileVersion", version);
  gmsh::write(file);
  gmsh::model::remove();
}

int polygon(const std::vector<std::pair<double, double>>& pts, double lc) {
  std::vector<int> p, l;
  for (const auto& [x, y] : pts) p.push_back(gmsh::model::geo::addPoint(x, y, 0, lc));
  for (std::size_t i = 0; i < p.size(); ++i)
    l.push_back(gmsh::model::geo::addLine(p[i], p[(i + 1) % p.size()]));
  return gmsh::model::geo::addCurveLoop(l);
}

void plate_hole() {
  start("plate_hole");
  const double lc = 0.04;
  const int outer = polygon({{0, 0}, {1, 0}, {1, 1}, {0, 1}}, lc);
  const int c = gmsh::model::geo::addPoint(0.5, 0.5, 0, lc);
  std::vector<int> q;
  const double pts[4][2] = {{0.7, 0.5}, {0.5, 0.7}, {0.3, 0.5}, {0.5, 0.3}};
  for (const auto& p : pts) q.push_back(gmsh::model::geo::addPoint(p[0], p[1], 0, lc));
  std::vector<int> arcs;
  for (std::size_t i = 0; i < 4; ++i)
    arcs.push_back(gmsh::model::geo::addCircleArc(q[i], c, q[(i + 1) % 4]));
  const int hole = gmsh::model::geo::addCurveLoop(arcs);
  const int s = gmsh::model::geo::addPlaneSurface({outer, hole});
  gmsh::model::geo::synchronize();
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {s}), "plate");
  write("examples/meshes/plate_hole.msh", 2);
}

void sphere() {
  start("sphere");
  gmsh::option::setNumber("Mesh.MeshSizeMax", 0.025);
  const int v = gmsh::model::occ::addSphere(0.25, 0.15, 0.25, 0.1);
  gmsh::model::occ::synchronize();
  gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, {v}), "ball");
  write("examples/meshes/sphere.msh", 3);
}

void cube(const std::string& file, double version, bool hexes) {
  start("cube");
  if (hexes) {
    const int p = gmsh::model::geo::addPoint(0, 0, 0, 0.5);
    const int l = gmsh::model::geo::addLine(p, gmsh::model::geo::addPoint(1, 0, 0, 0.5));
    gmsh::model::geo::mesh::setTransfiniteCurve(l, 3);
    std::vector<std::pair<int, int>> out;
    gmsh::model::geo::extrude({{1, l}}, 0, 1, 0, out, {2}, {}, true);
    std::vector<std::pair<int, int>> out2;
    gmsh::model::geo::extrude({out[1]}, 0, 0, 1, out2, {2}, {}, true);
    gmsh::model::geo::synchronize();
    gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, {out2[1].second}), "cube");
    write(file, 3, version);
    return;
  }
  gmsh::option::setNumber("Mesh.MeshSizeMax", 0.5);
  const int lower = gmsh::model::occ::addBox(0, 0, 0, 1, 1, 0.5);
  const int upper = gmsh::model::occ::addBox(0, 0, 0.5, 1, 1, 0.5);
  std::vector<std::pair<int, int>> out;
  std::vector<std::vector<std::pair<int, int>>> map;
  gmsh::model::occ::fragment({{3, lower}}, {{3, upper}}, out, map);
  gmsh::model::occ::synchronize();
  gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, {map[0][0].second}), "lower");
  gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, {map[1][0].second}), "upper");
  write(file, 3, version);
}

// The column of two layers: transfinite (structured) rectangles cut into two triangles each.
void layered_column() {
  start("layered_column");
  const double h = 0.05;
  const int p0 = gmsh::model::geo::addPoint(0, 0, 0, h),
            p1 = gmsh::model::geo::addPoint(0.2, 0, 0, h);
  const int p2 = gmsh::model::geo::addPoint(0.2, 0.5, 0, h),
            p3 = gmsh::model::geo::addPoint(0, 0.5, 0, h);
  const int p4 = gmsh::model::geo::addPoint(0.2, 1, 0, h),
            p5 = gmsh::model::geo::addPoint(0, 1, 0, h);
  const int bottom = gmsh::model::geo::addLine(p0, p1), right1 = gmsh::model::geo::addLine(p1, p2);
  const int middle = gmsh::model::geo::addLine(p2, p3), left1 = gmsh::model::geo::addLine(p3, p0);
  const int right2 = gmsh::model::geo::addLine(p2, p4), top = gmsh::model::geo::addLine(p4, p5);
  const int left2 = gmsh::model::geo::addLine(p5, p3);
  const int lower = gmsh::model::geo::addPlaneSurface(
      {gmsh::model::geo::addCurveLoop({bottom, right1, middle, left1})});
  const int upper = gmsh::model::geo::addPlaneSurface(
      {gmsh::model::geo::addCurveLoop({-middle, right2, top, left2})});
  for (const int l : {bottom, middle, top}) gmsh::model::geo::mesh::setTransfiniteCurve(l, 5);
  for (const int l : {right1, left1, right2, left2})
    gmsh::model::geo::mesh::setTransfiniteCurve(l, 11);
  for (const int s : {lower, upper}) gmsh::model::geo::mesh::setTransfiniteSurface(s);
  gmsh::model::geo::synchronize();
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {lower}), "lower");
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {upper}), "upper");
  write("tests/data/meshes/layered_column.msh", 2);
}

// A slope of soft soil on a stiffer foundation: two surfaces sharing the line y = 4 m.
void slope_layered() {
  start("slope_layered");
  const double lc = 0.5;
  std::vector<int> p;
  for (const auto& [x, y] : std::vector<std::pair<double, double>>{
           {0, 0}, {20, 0}, {20, 4}, {14, 4}, {0, 4}, {8, 10}, {0, 10}})
    p.push_back(gmsh::model::geo::addPoint(x, y, 0, lc));
  auto line = [&](int a, int b) { return gmsh::model::geo::addLine(p[a], p[b]); };
  const int interface = line(4, 3);  // (0, 4) to (14, 4)
  const int foundation = gmsh::model::geo::addPlaneSurface({gmsh::model::geo::addCurveLoop(
      {line(0, 1), line(1, 2), line(2, 3), -interface, line(4, 0)})});
  const int slope = gmsh::model::geo::addPlaneSurface(
      {gmsh::model::geo::addCurveLoop({interface, line(3, 5), line(5, 6), line(6, 4)})});
  gmsh::model::geo::synchronize();
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {foundation}), "foundation");
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {slope}), "slope");
  write("examples/meshes/slope_layered.msh", 2);
}

}  // namespace

int main() {
  gmsh::initialize();
  plate_hole();
  sphere();
  cube("tests/data/meshes/cube_tets.msh", 4.1, false);
  cube("tests/data/meshes/cube_tets_v22.msh", 2.2, false);
  cube("tests/data/meshes/cube_hexes.msh", 4.1, true);
  layered_column();
  slope_layered();
  gmsh::finalize();
  return 0;
}
