// Gmsh meshes through Gmsh's library (setup/gmsh_mesh.hpp): the same mesh in MSH 4.1, 2.2 and
// 4.1 binary, its named and unnamed boundary groups, and the refusals with their reasons
// (tests/data/meshes/README.md says how the files were made); body meshes (read_gmsh_body) of
// tetrahedra in MSH 4.1 and 2.2 with their parts, and their refusals.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "grid/triangle_mesh.hpp"
#include "setup/gmsh_mesh.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

std::string mesh_path(const std::string& name) {
  return std::string(MPM_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

// A directory of its own under the system's temporary directory, removed at the end.
struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name)
      : path(std::filesystem::temp_directory_path() /
             ("mpm_gmsh_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path / name, std::ios::binary) << text;
    return (path / name).string();
  }
};

std::string refusal(const std::string& path) {
  try {
    read_gmsh_mesh(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(GmshMesh, TheSameSquareFromEveryFormat) {
  const auto a = read_gmsh_mesh(mesh_path("square_v41.msh"));
  double area = 0.0;
  for (Index c = 0; c < a.num_cells(); ++c) area += a.cell_volume(c);
  EXPECT_NEAR(area, 1.0, 1e-14);
  EXPECT_GT(a.num_cells(), 20);
  // Euler's formula for a triangulated disc: V - E + F = 1 with 3F = 2E - (boundary edges).
  const auto boundary_edges =
      static_cast<Index>(a.boundary("bottom").edges.size() + a.boundary("right").edges.size() +
                         a.boundary("top_left").edges.size());
  const Index edges = (3 * a.num_cells() + boundary_edges) / 2;
  EXPECT_EQ(a.num_vertices() - edges + a.num_cells(), 1);
  EXPECT_EQ(a.boundary_names(), (std::vector<std::string>{"7", "bottom", "right", "top_left"}));
  for (Index v : a.boundary_vertices("bottom")) EXPECT_EQ(a.vertex(v)[1], 0.0);
  for (Index v : a.boundary_vertices("right")) EXPECT_EQ(a.vertex(v)[0], 1.0);
  for (Index v : a.boundary_vertices("7")) EXPECT_EQ(a.vertex(v)[0], 0.0);  // the unnamed group
  EXPECT_EQ(a.boundary_vertices("bottom").size(), 5u);  // mesh size 0.25 on a unit side
  // "top_left" joins two sides: both corners (0, 1) and (1, 1) and the ends (0, 0), (1, 1).
  EXPECT_EQ(a.boundary_vertices("top_left").size(), 9u);
  for (const std::string other : {"square_v22.msh", "square_v41_binary.msh"}) {
    const auto b = read_gmsh_mesh(mesh_path(other));
    ASSERT_EQ(b.num_vertices(), a.num_vertices()) << other;
    ASSERT_EQ(b.num_cells(), a.num_cells()) << other;
    // ASCII files hold 16 significant digits, binary ones every bit: the same to round-off.
    for (Index v = 0; v < a.num_vertices(); ++v)
      EXPECT_LE((b.vertex(v) - a.vertex(v)).norm(), 1e-15) << other;
    for (Index c = 0; c < a.num_cells(); ++c)
      EXPECT_EQ(b.cell_vertices(c), a.cell_vertices(c)) << other;
    EXPECT_EQ(b.boundary_names(), a.boundary_names()) << other;
    for (const auto& name : a.boundary_names())
      EXPECT_EQ(b.boundary_vertices(name), a.boundary_vertices(name)) << other << " " << name;
  }
  // Point location on the read mesh: the centre lies in some triangle, a point outside in none.
  EXPECT_GE(a.cell_index(Vec<2>(0.5, 0.5)), 0);
  EXPECT_EQ(a.cell_index(Vec<2>(1.01, 0.5)), -1);
}

TEST(GmshMesh, RefusalsNameTheFileAndTheReason) {
  const std::string missing = mesh_path("no_such_mesh.msh");
  EXPECT_EQ(refusal(missing), "cannot open mesh file '" + missing + "': No such file or directory");
  const auto quads = refusal(mesh_path("square_quads.msh"));
  EXPECT_NE(quads.find("no 3-node triangles"), std::string::npos) << quads;
  EXPECT_NE(quads.find("Quadrilateral 4 (Gmsh type 3)"), std::string::npos) << quads;
  const auto order2 = refusal(mesh_path("square_order2.msh"));
  EXPECT_NE(order2.find("Triangle 6 (Gmsh type 9)"), std::string::npos) << order2;
  EXPECT_NE(order2.find("Mesh.ElementOrder = 1"), std::string::npos) << order2;
  // Not a mesh (no $MeshFormat header): refused before Gmsh sees it, naming what it starts with.
  const std::string garbage = mesh_path("../bad_choice.toml");
  const auto bad = refusal(garbage);
  EXPECT_EQ(bad.rfind("mesh file \"" + garbage + "\": not a Gmsh mesh file", 0), 0u) << bad;
  // A header, then what Gmsh's mesh reader cannot parse: Gmsh's message, the file named; the
  // next read still works.
  const TempDir dir("garbage");
  const std::string broken = dir.write("broken.msh",
                                       "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                                       "$Nodes\n1 two three\n$EndNodes\n");
  const auto gmsh = refusal(broken);
  EXPECT_TRUE(gmsh.find("Gmsh could not read it") != std::string::npos ||
              gmsh.find("no 3-node triangles") != std::string::npos)
      << gmsh;
  const auto version = refusal(dir.write("v3.msh", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n"));
  EXPECT_NE(version.find("mpm reads MSH 2.2 and 4.1"), std::string::npos) << version;
  EXPECT_GT(read_gmsh_mesh(mesh_path("square_v22.msh")).num_cells(), 0);
}

// Gmsh reads a file without the $MeshFormat header as a .geo script, whatever its name, and
// merges a file NAME.opt next to the one it opens: either would run a shell command through
// SystemCall. A mesh is data: the script is refused before Gmsh sees it, and the option file
// next to a real mesh is never read (the mesh is opened from a private copy).
TEST(GmshMesh, AMeshFileNeverRunsCode) {
  const TempDir dir("scripts");
  for (const std::string name : {"grid.msh", "grid.txt", "grid.mesh"}) {
    const auto mark = dir.path / ("ran_" + name);
    const std::string script = "SystemCall \"touch " + mark.string() + "\";\n";
    const auto why = refusal(dir.write(name, script));
    EXPECT_NE(why.find("not a Gmsh mesh file"), std::string::npos) << name << ": " << why;
    EXPECT_FALSE(std::filesystem::exists(mark)) << name;
  }
  // A header in front of a script: read as a mesh (which has no triangles), never run.
  {
    const auto mark = dir.path / "ran_after_header";
    const auto why = refusal(dir.write("headed.msh",
                                       "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                                       "SystemCall \"touch " +
                                           mark.string() + "\";\n"));
    EXPECT_FALSE(why.empty());
    EXPECT_FALSE(std::filesystem::exists(mark));
  }
  // A real mesh with an option file beside it: read, and the option file not merged.
  const auto mark = dir.path / "ran_opt";
  std::filesystem::copy_file(mesh_path("square_v22.msh"), dir.path / "square.msh");
  dir.write("square.msh.opt", "SystemCall \"touch " + mark.string() + "\";\n");
  // (The private copy goes under TMPDIR, here a directory of the test's, and is removed.)
  const auto scratch = dir.path / "scratch";
  std::filesystem::create_directories(scratch);
  const char* before = std::getenv("TMPDIR");
  const std::string saved = before != nullptr ? before : "";
  ::setenv("TMPDIR", scratch.c_str(), 1);
  const auto read = read_gmsh_mesh((dir.path / "square.msh").string());
  if (before != nullptr)
    ::setenv("TMPDIR", saved.c_str(), 1);
  else
    ::unsetenv("TMPDIR");
  EXPECT_GT(read.num_cells(), 20);
  EXPECT_FALSE(std::filesystem::exists(mark));
  EXPECT_TRUE(std::filesystem::is_empty(scratch));
}

// What is not a regular file is refused at once: a FIFO would block for ever, a device never end.
TEST(GmshMesh, FifosAndDevicesAreRefused) {
  const TempDir dir("fifo");
  const auto fifo = dir.path / "grid.msh";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto why = refusal(fifo.string());
  EXPECT_NE(why.find("it is a FIFO (named pipe), not a regular file"), std::string::npos) << why;
  const auto dev = refusal("/dev/zero");
  EXPECT_NE(dev.find("it is a character device"), std::string::npos) << dev;
}

// Small MSH 2.2 files: a unit square split along (1, 2)-(3, 4) into two triangles, with extras.
std::string msh22(const std::string& names, const std::string& nodes, const std::string& elements) {
  return "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n" +
         (names.empty() ? std::string() : "$PhysicalNames\n" + names + "$EndPhysicalNames\n") +
         "$Nodes\n" + nodes + "$EndNodes\n$Elements\n" + elements + "$EndElements\n";
}
const std::string kSquareNodes = "4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n";
const std::string kTriangles = "1 2 2 9 9 1 2 3\n2 2 2 9 9 1 3 4\n";

TEST(GmshMesh, MixedElementsTwiceDefinedNodesAndFalseEdgesAreRefused) {
  const TempDir dir("refusals");
  // Triangles and a quadrilateral: refused whole, never read in part.
  const std::string mixed = msh22("", "6\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 2 0 0\n6 2 1 0\n",
                                  "3\n" + kTriangles + "3 3 2 9 9 2 5 6 3\n");
  const auto m = refusal(dir.write("mixed.msh", mixed));
  EXPECT_NE(m.find("mixes 3-node triangles with other surface elements"), std::string::npos) << m;
  EXPECT_NE(m.find("Quadrilateral 4"), std::string::npos) << m;
  // Node 3 defined twice (two coordinates for one id).
  const std::string twice =
      msh22("", "5\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n3 1 2 0\n", "2\n" + kTriangles);
  const auto t = refusal(dir.write("twice.msh", twice));
  EXPECT_NE(t.find("node 3 is defined twice in $Nodes"), std::string::npos) << t;
  // A named line from node 2 to node 4: both are mesh vertices, but no triangle has that edge
  // (the square is split along 1-3), so the line would carry its conditions nowhere.
  const std::string diagonal =
      msh22("1\n1 5 \"cut\"\n", kSquareNodes, "3\n" + kTriangles + "3 1 2 5 5 2 4\n");
  const auto d = refusal(dir.write("diagonal.msh", diagonal));
  EXPECT_NE(d.find("boundary \"cut\" has the edge"), std::string::npos) << d;
  EXPECT_NE(d.find("no edge of a triangle"), std::string::npos) << d;
  // Coordinates whose areas overflow: refused as too large, not as zero area.
  const std::string huge =
      msh22("", "4\n1 -1e308 0 0\n2 1e308 0 0\n3 1e308 1 0\n4 -1e308 1 0\n", "2\n" + kTriangles);
  const auto h = refusal(dir.write("huge.msh", huge));
  EXPECT_NE(h.find("too large for areas in double precision"), std::string::npos) << h;
}

// A physical group named like a side of the bounding box ("x-") would silently replace that
// side in the conditions on sides (boundary.left, ...): refused, naming the group.
TEST(GmshMesh, AGroupNamedLikeABoxSideIsRefused) {
  const TempDir dir("side");
  const std::string named =
      msh22("1\n1 5 \"x-\"\n", kSquareNodes, "3\n" + kTriangles + "3 1 2 5 5 4 1\n");
  const auto path = dir.write("named.msh", named);
  const auto m = read_gmsh_mesh(path);  // (the file alone is a valid mesh)
  try {
    with_box_sides(m);
    ADD_FAILURE() << "a group named x- was accepted";
  } catch (const InputError& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find("physical group \"x-\""), std::string::npos) << why;
    EXPECT_NE(why.find("boundary.left"), std::string::npos) << why;
  }
  // The same line under another name: the sides are added beside it.
  const std::string other =
      msh22("1\n1 5 \"wall\"\n", kSquareNodes, "3\n" + kTriangles + "3 1 2 5 5 4 1\n");
  const auto sided = with_box_sides(read_gmsh_mesh(dir.write("other.msh", other)));
  EXPECT_TRUE(sided.has_boundary("wall"));
  EXPECT_TRUE(sided.has_boundary("x-"));
  EXPECT_TRUE(sided.boundary("wall").outer);
}

TEST(GmshMesh, ABodyOfTetrahedraWithItsPartsFromBothFormats) {
  const BodyMesh<3> a = read_gmsh_body<3>(mesh_path("cube_tets.msh"));
  const BodyMesh<3> b = read_gmsh_body<3>(mesh_path("cube_tets_v22.msh"));
  EXPECT_NEAR(a.volume(), 1.0, 1e-14);
  ASSERT_EQ(a.group_names(), (std::vector<std::string>{"lower", "upper"}));
  double part[2] = {0.0, 0.0};
  for (Index e = 0; e < a.num_elements(); ++e) {
    ASSERT_GE(a.group(e), 0);
    part[a.group(e)] += a.element_volume(e);
    // Each element in its part: "lower" below z = 0.5, "upper" above.
    for (Index v : a.element(e))
      EXPECT_TRUE(a.group(e) == 0 ? a.vertex(v)[2] <= 0.5 + 1e-15 : a.vertex(v)[2] >= 0.5 - 1e-15);
  }
  EXPECT_NEAR(part[0], 0.5, 1e-14);
  EXPECT_NEAR(part[1], 0.5, 1e-14);
  // The same mesh in MSH 2.2: the same vertices, elements and parts.
  ASSERT_EQ(b.num_elements(), a.num_elements());
  ASSERT_EQ(b.num_vertices(), a.num_vertices());
  for (Index v = 0; v < a.num_vertices(); ++v) EXPECT_EQ(a.vertex(v), b.vertex(v));
  for (Index e = 0; e < a.num_elements(); ++e) {
    EXPECT_EQ(a.element(e), b.element(e));
    EXPECT_EQ(a.group(e), b.group(e));
  }
  EXPECT_EQ(gmsh_mesh_dimension(mesh_path("cube_tets.msh")), 3);
  EXPECT_EQ(gmsh_mesh_dimension(mesh_path("square_v41.msh")), 2);
}

TEST(GmshMesh, ABodyOfTrianglesHasItsSurfaceGroupAsItsPart) {
  const BodyMesh<2> m = read_gmsh_body<2>(mesh_path("square_v41.msh"));
  EXPECT_NEAR(m.volume(), 1.0, 1e-14);
  ASSERT_EQ(m.group_names(), std::vector<std::string>{"body"});
  for (Index e = 0; e < m.num_elements(); ++e) EXPECT_EQ(m.group(e), 0);
}

TEST(GmshMesh, BodyRefusalsNameTheFileAndTheElements) {
  auto refused = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string hexes = refused([] { read_gmsh_body<3>(mesh_path("cube_hexes.msh")); });
  EXPECT_NE(hexes.find("cube_hexes.msh"), std::string::npos) << hexes;
  EXPECT_NE(hexes.find("Hexahedron"), std::string::npos) << hexes;
  const std::string flat = refused([] { read_gmsh_body<3>(mesh_path("square_v41.msh")); });
  EXPECT_NE(flat.find("no 4-node tetrahedra"), std::string::npos) << flat;
  EXPECT_NE(flat.find("grid.dimension = 2"), std::string::npos) << flat;
  const std::string solid = refused([] { read_gmsh_body<2>(mesh_path("cube_tets.msh")); });
  EXPECT_NE(solid.find("no 3-node triangles"), std::string::npos) << solid;
  const std::string quads = refused([] { read_gmsh_body<2>(mesh_path("square_quads.msh")); });
  EXPECT_NE(quads.find("Quadrilateral"), std::string::npos) << quads;
  // A script is never a mesh, as for grid.mesh.
  const TempDir dir("body_script");
  const std::string geo = dir.write("body.msh", "Point(1) = {0, 0, 0};\n");
  const std::string script = refused([&] { read_gmsh_body<3>(geo); });
  EXPECT_NE(script.find("$MeshFormat"), std::string::npos) << script;
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
