// Bodies from files on a separate background grid (benchmarks/bodies.hpp):
// - the tetrahedron rules: equal volumes, every point inside, linear fields exact, and the
//   degree-2 rule (4 points per tetrahedron) exact for quadratics;
// - a Gmsh body mesh (body.mesh) seeds particles whose volumes sum to the mesh's volume to
//   round-off, the same from MSH 4.1 and 2.2; a body mesh falls freely on a grid it does not
//   fill (2D triangles, 3D tetrahedra);
// - a particle file (body.particles) holding a box body's particles runs bit for bit as the box
//   body, and gives the particles its initial velocity and stress;
// - refusals name the key, the file and the line or element (overlapping elements too).
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "../support/stepper.hpp"
#include "../support/threads.hpp"
#include "benchmarks/benchmarks.hpp"
#include "benchmarks/bodies.hpp"
#include "model/problem.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

std::string mesh_path(const std::string& dir, const std::string& name) {
  return std::string(MPM_SOURCE_DIR) + "/" + dir + "/" + name;
}

// A file of its own under the system's temporary directory, removed at the end.
struct TempFile {
  std::filesystem::path path;
  TempFile(const std::string& name, const std::string& text)
      : path(std::filesystem::temp_directory_path() /
             fmt::format("mpm_bodies_{}_{}", static_cast<long>(::getpid()), name)) {
    std::ofstream(path) << text;
  }
  ~TempFile() { std::filesystem::remove(path); }
};

// A free elastic body on a grid of `cells` cells per direction over [lo, hi]^Dim, without
// boundary conditions, and `body` (the [body] table's lines).
std::string free_body(int dim, double lo, double hi, int cells, const std::string& body,
                      const std::string& extra = "") {
  const std::string v =
      dim == 2 ? fmt::format("[{0}, {0}]", lo) : fmt::format("[{0}, {0}, {0}]", lo);
  const std::string w =
      dim == 2 ? fmt::format("[{0}, {0}]", hi) : fmt::format("[{0}, {0}, {0}]", hi);
  return fmt::format(
      "benchmark = \"custom\"\n[grid]\ndimension = {}\ncells = {}\nmin = {}\nmax = {}\n"
      "[body]\n{}\n[time]\ndt = 1e-4\nend = 1e-3\n[method]\nscheme = \"musl\"\n"
      "basis = \"bspline\"\ndegree = 2\n[material]\nmodel = \"neo_hookean\"\ndensity = 1000.0\n"
      "youngs_modulus = 1e6\npoisson_ratio = 0.3\n[boundary]\nleft = \"free\"\nright = \"free\"\n"
      "bottom = \"free\"\ntop = \"free\"\n{}{}",
      dim, cells, v, w, body, dim == 3 ? "back = \"free\"\nfront = \"free\"\n" : "", extra);
}

TEST(Bodies, TheTetrahedronRulesIntegrateAsTheyClaim) {
  double previous = 0.0;  // the centroid rule's error one refinement coarser
  for (int n : {1, 4, 8, 32, 64}) {
    const auto ref = tetrahedron_seed_reference(n);
    ASSERT_EQ(ref.size(), static_cast<std::size_t>(n));
    Vec<3> mean = Vec<3>::Zero();
    double square = 0.0;
    for (const Vec<3>& p : ref) {
      EXPECT_GT(p.minCoeff(), 0.0) << n;  // inside: every barycentric coordinate positive
      EXPECT_LT(p.sum(), 1.0) << n;
      mean += p / n;
      square += p[0] * p[0] / n;
    }
    // Linear fields: the mean of lambda_i over the tetrahedron is 1/4.
    EXPECT_NEAR((mean - Vec<3>::Constant(0.25)).norm(), 0.0, 1e-15) << n;
    // lambda_1^2: its mean over the tetrahedron is 3! 2! / 5! = 1/10. The rules with 4 points
    // per child (4, 32) are exact; the centroid rules (1, 8, 64) are second order, the error
    // 3/80 of one point falling by about 4 per red refinement (h halved).
    if (n == 4 || n == 32) {
      EXPECT_NEAR(square, 0.1, 1e-15) << n;
    } else {
      EXPECT_LT(square, 0.1) << n;  // (a convex function's mean exceeds its value at the mean)
      if (n > 1) {
        EXPECT_LT(0.1 - square, previous / 3.5) << n;
        EXPECT_GT(0.1 - square, previous / 4.1) << n;
      }
      previous = 0.1 - square;
    }
  }
  for (int n : {0, 2, 3, 12, 16, 100}) {
    const std::string m = test::message_of([&] { tetrahedron_seed_reference(n); });
    EXPECT_NE(m.find("m 8^r"), std::string::npos) << n << ": " << m;
  }
}

TEST(Bodies, AMeshBodyHoldsItsVolumeAndMassToRoundOff) {
  // (Few seedings: under the sanitizers, at -O0, each costs seconds.)
  for (const char* file : {"cube_tets.msh", "cube_tets_v22.msh"})
    for (int per : {1, 8}) {
      if (std::string_view(file) == "cube_tets_v22.msh" && per == 8) continue;  // (compared below)
      const Config cfg = Config::parse(
          free_body(3, -0.5, 1.5, 8,
                    fmt::format("mesh = \"{}\"", mesh_path("tests/data/meshes", file)),
                    fmt::format("[particles]\nper_element = {}\n", per)),
          "mesh_body.toml");
      const auto pb = std::get<Problem<3>>(make_problem(cfg));
      const auto& P = pb.particles;
      ASSERT_EQ(P.size(), 1390 * per) << file;
      double volume = 0.0, mass = 0.0;
      for (std::size_t i = 0; i < P.x.size(); ++i) {
        volume += P.volume[i];
        mass += P.mass[i];
        EXPECT_EQ(P.id[i], static_cast<CompactIndex>(i));
      }
      EXPECT_NEAR(volume, 1.0, 1e-13) << file << " " << per;
      EXPECT_NEAR(mass, 1000.0, 1e-10) << file << " " << per;
    }
  // The two formats seed the same particles.
  auto particles = [](const char* file) {
    return std::get<Problem<3>>(
               make_problem(Config::parse(
                   free_body(3, -0.5, 1.5, 8,
                             fmt::format("mesh = \"{}\"", mesh_path("tests/data/meshes", file)),
                             "[particles]\nper_element = 1\n"),
                   "mesh_body.toml")))
        .particles;
  };
  const auto a = particles("cube_tets.msh"), b = particles("cube_tets_v22.msh");
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.x.size(); ++i) {
    EXPECT_EQ(a.x[i], b.x[i]);
    EXPECT_EQ(a.volume[i], b.volume[i]);
  }
}

// Under gravity alone a body falls as a rigid body: its momentum is M g t to round-off, and every
// particle moves with it, v = g t and x = X + g dt^2 n (n + 1) / 2 (symplectic Euler), to the
// round-off that the nodes at the body's edge, with a small share of mass, amplify (their
// accelerations are force round-off over that mass), whatever part of the grid it covers.
template <int Dim>
void falls_freely(const std::string& text) {
  const test::Threads one(1);
  test::ConfiguredRun<Dim> run(Config::parse(text, "falling.toml"));
  const int steps = 5;
  run.advance(steps);
  const double t = steps * run.dt;
  const auto& P = run.state().particles;
  ASSERT_GT(P.size(), 100);
  Vec<Dim> g = Vec<Dim>::Zero();
  g[Dim - 1] = -10.0;
  double dv = 0.0, dx = 0.0, mass = 0.0;
  Vec<Dim> momentum = Vec<Dim>::Zero();
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    dv = std::max(dv, (P.v[i] - g * t).norm());
    dx = std::max(dx, (P.x[i] - P.x0[i] - g * run.dt * run.dt * steps * (steps + 1) / 2.0).norm());
    momentum += P.mass[i] * P.v[i];
    mass += P.mass[i];
  }
  // Measured (relative to M g t, g t and the positions): 2D 5e-15, 5e-16, 1e-16; 3D (a node
  // can hold 1e-9 of a particle's mass in a quadratic B-spline's corner) 4e-12, 8e-9, 5e-15.
  EXPECT_LT((momentum - mass * g * t).norm(), 1e-11 * mass * g.norm() * t);
  EXPECT_LT(dv, 1e-7 * g.norm() * t);
  EXPECT_LT(dx, 1e-13);
}

TEST(Bodies, MeshBodiesFallFreelyOnAGridTheyDoNotFill) {
  const std::string gravity2 = "[loading]\nbody_force = [\"0\", \"-10\"]\n";
  falls_freely<2>(
      free_body(2, -0.25, 1.25, 12,
                fmt::format("mesh = \"{}\"", mesh_path("examples/meshes", "plate_hole.msh")),
                "[particles]\nper_element = 1\n" + gravity2));
  const std::string gravity3 = "[loading]\nbody_force = [\"0\", \"0\", \"-10\"]\n";
  falls_freely<3>(free_body(
      3, 0.0, 0.5, 10, fmt::format("mesh = \"{}\"", mesh_path("examples/meshes", "sphere.msh")),
      "[particles]\nper_element = 1\n" + gravity3));
}

// The particles of `pb` as a particle file (x_1, ..., volume; 17 digits: the same doubles).
template <int Dim>
std::string as_particle_file(const Particles<Dim>& P, const std::string& extra_header = "",
                             const std::function<std::string(std::size_t)>& extra = {}) {
  std::string t = "# the particles of a box body\n";
  for (int d = 0; d < Dim; ++d) t += fmt::format("x_{},", d + 1);
  t += "volume" + extra_header + "\n";
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    for (int d = 0; d < Dim; ++d) t += fmt::format("{:.17g},", P.x0[i][d]);
    t += fmt::format("{:.17g}", P.volume[i]) + (extra ? extra(i) : "") + "\n";
  }
  return t;
}

template <int Dim>
void particle_file_is_the_box() {
  const test::Threads one(1);
  const std::string box = Dim == 2 ? "min = [0.1, 0.0]\nmax = [0.6, 0.5]\n"
                                   : "min = [0.1, 0.0, 0.2]\nmax = [0.6, 0.5, 0.4]\n";
  const std::string rest = fmt::format(
      "[particles]\nper_cell = 2\n[loading]\nbody_force = {}\n[initial]\nvelocity = {}\n",
      Dim == 2 ? "[\"0\", \"-10\"]" : "[\"0\", \"-10\", \"0\"]",
      Dim == 2 ? "[\"y\", \"-x\"]" : "[\"y\", \"-x\", \"z\"]");
  std::string text = free_body(Dim, 0.0, 1.0, 8, box, rest);
  text.replace(text.find("bottom = \"free\""), 15, "bottom = \"fixed\"");
  const Config box_cfg = Config::parse(text, "box.toml");
  const TempFile csv(
      fmt::format("box{}.csv", Dim),
      as_particle_file<Dim>(std::get<Problem<Dim>>(make_problem(box_cfg)).particles));
  test::ConfiguredRun<Dim> a(box_cfg);
  std::string from_file = text;
  from_file.replace(from_file.find(box), box.size(),
                    fmt::format("particles = \"{}\"\n", csv.path.string()));
  from_file.replace(from_file.find("per_cell = 2\n"), 13, "");
  test::ConfiguredRun<Dim> b(Config::parse(from_file, "file.toml"));
  a.advance(10);
  b.advance(10);
  const auto &P = a.state().particles, &Q = b.state().particles;
  ASSERT_EQ(P.size(), Q.size());
  for (std::size_t i = 0; i < P.x.size(); ++i) {
    ASSERT_EQ(P.x[i], Q.x[i]) << i;
    ASSERT_EQ(P.v[i], Q.v[i]) << i;
    ASSERT_EQ(P.stress[i], Q.stress[i]) << i;
  }
  EXPECT_GT(P.v[0].norm(), 0.0);
}

TEST(Bodies, AParticleFileOfABoxBodysParticlesIsThatBodyBitForBit) {
  particle_file_is_the_box<2>();
  particle_file_is_the_box<3>();
}

TEST(Bodies, AParticleFileGivesTheInitialVelocityAndStress) {
  const std::string csv_text =
      "x, y, volume, vx, vy, stress_11, stress_22, stress_12, stress_zz\n"
      "0.25, 0.25, 0.0625, 1.5, -2, -100, -200, 30, -150\r\n"
      "# a comment between rows\n"
      "\n"
      "0.75, 0.25, 0.0625, +0.5, 0, -110, -210, 0, -160\n";
  const TempFile csv("fields.csv", csv_text);
  std::string text =
      free_body(2, 0.0, 1.0, 4, fmt::format("particles = \"{}\"", csv.path.string()));
  text.replace(text.find("model = \"neo_hookean\""), 21,
               "model = \"mohr_coulomb\"\ncohesion = 1e4\nfriction_angle = 30");
  const auto pb = std::get<Problem<2>>(make_problem(Config::parse(text, "fields.toml")));
  const auto& P = pb.particles;
  ASSERT_EQ(P.size(), 2);
  EXPECT_EQ(P.v[0], Vec<2>(1.5, -2.0));
  EXPECT_EQ(P.v[1], Vec<2>(0.5, 0.0));
  EXPECT_EQ(P.stress[0](0, 1), 30.0);
  EXPECT_EQ(P.stress[0](1, 0), 30.0);
  EXPECT_EQ(P.stress[1](1, 1), -210.0);
  EXPECT_EQ(P.mass[0], 62.5);
  const auto names = P.state.names();
  const auto zz = static_cast<std::size_t>(
      std::find(names.begin(), names.end(), kOutOfPlaneStressName) - names.begin());
  ASSERT_LT(zz, names.size());
  EXPECT_EQ(P.state[0][zz], -150.0);
  EXPECT_EQ(P.state[1][zz], -160.0);
}

TEST(Bodies, RefusalsNameTheKeyTheFileAndWhere) {
  const TempFile good("good.csv", "x_1,x_2,volume\n0.5,0.5,0.01\n");
  const std::string mesh =
      fmt::format("mesh = \"{}\"", mesh_path("examples/meshes", "plate_hole.msh"));
  auto refusal = [](const std::string& text) {
    return test::message_of([&] { make_problem(Config::parse(text, "bad.toml")); });
  };
  auto file_refusal = [&](const std::string& csv_text) {
    const TempFile csv("bad.csv", csv_text);
    return refusal(free_body(2, 0.0, 1.0, 4, fmt::format("particles = \"{}\"", csv.path.string())));
  };
  struct Case {
    std::string message, text;
  };
  const std::vector<Case> cases = {
      // The mesh body reaches beyond the grid [0.2, 1.2]^2.
      {"outside the grid", free_body(2, 0.2, 1.2, 4, mesh)},
      {"body.mesh (at bad.toml", free_body(2, 0.0, 1.0, 4, mesh + "\nparticles = \"x.csv\"")},
      {"body.min is a corner of a box body", free_body(2, -1.0, 2.0, 4, mesh + "\nmin = [0, 0]")},
      {"particles.per_element: 5 particles per triangle",
       free_body(2, -1.0, 2.0, 4, mesh, "[particles]\nper_element = 5\n")},
      {"particles.per_cell seeds the cells of a box body",
       free_body(2, -1.0, 2.0, 4, mesh, "[particles]\nper_cell = 3\n")},
      {"particles.per_element seeds the elements of a body mesh",
       free_body(2, -1.0, 2.0, 4, "min = [0, 0]", "[particles]\nper_element = 3\n")},
      {"traction.top loads a face of the box body",
       free_body(2, -1.0, 2.0, 4, mesh, "[traction]\ntop = [\"0\", \"-1\"]\n")},
      // (A body mesh takes K0 as a box does; this one's law, neo-Hookean, no initial stress.)
      {"initial.geostatic gives an initial stress, which needs an incremental law",
       free_body(2, -1.0, 2.0, 4, mesh,
                 "[loading]\nbody_force = [\"0\", \"-10\"]\n[initial]\ngeostatic = \"k0\"\n"
                 "k0 = 0.5\n")},
      {"method.solver = \"otm\" discretises a box body",
       [&] {
         std::string t = free_body(2, -1.0, 2.0, 4, mesh);
         t.replace(t.find("scheme = \"musl\""), 15, "solver = \"otm\"");
         return t;
       }()},
      {"body.mesh gives a body of a 2D or 3D custom problem",
       "benchmark = \"custom\"\n[grid]\ndimension = 1\ncells = 4\n[body]\n" + mesh +
           "\n[time]\ndt = 1e-4\nend = 1e-3\n[material]\nmodel = \"elastic_1d_small\"\ndensity = "
           "1\n"
           "youngs_modulus = 1\n"},
  };
  for (const Case& c : cases) {
    const std::string m = refusal(c.text);
    EXPECT_NE(m.find(c.message), std::string::npos) << c.message << "\n  got: " << m;
  }
  // Two triangles that overlap: (0, 0), (1, 0), (0, 1) and the same moved by (0.2, 0.2).
  const TempFile overlap("overlap.msh",
                         "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n1 0 0 0\n2 1 0 0\n"
                         "3 0 1 0\n4 0.2 0.2 0\n5 1.2 0.2 0\n6 0.2 1.2 0\n$EndNodes\n"
                         "$Elements\n2\n1 2 2 0 1 1 2 3\n2 2 2 0 1 4 5 6\n$EndElements\n");
  const std::string twice =
      refusal(free_body(2, -1.0, 2.0, 4, fmt::format("mesh = \"{}\"", overlap.path.string())));
  EXPECT_NE(twice.find("elements 1 and 2 of body mesh"), std::string::npos) << twice;
  EXPECT_NE(twice.find("overlap"), std::string::npos) << twice;
  const std::string outside = refusal(free_body(2, 0.2, 1.2, 4, mesh));
  EXPECT_NE(outside.find("plate_hole.msh"), std::string::npos) << outside;
  EXPECT_NE(outside.find("bad.toml:"), std::string::npos) << outside;
  // Particle files: the file, the line and the column.
  struct FileCase {
    std::string message, csv;
  };
  const std::vector<FileCase> files = {
      {"line 2: the particle at (1.5, 0.5) lies outside the grid", "x,y,volume\n1.5,0.5,0.1\n"},
      {"line 1: column \"mass\" is not one mpm reads", "x,y,mass\n0.5,0.5,1\n"},
      {"line 1: the header has no column volume", "x_1,x_2\n0.5,0.5\n"},
      {"line 1: column \"x_1\" gives what another column gives", "x,x_1,y,volume\n"},
      {"line 3, column \"volume\": \"0.1e\" is not a finite number",
       "x,y,volume\n0.5,0.5,0.1\n0.5,0.5,0.1e\n"},
      {"line 2: volume = -0.1 must be positive", "x,y,volume\n0.5,0.5,-0.1\n"},
      {"line 2: 2 fields, and the header names 3 columns", "x,y,volume\n0.5,0.5\n"},
      {"line 2: stress_12 = 1 and stress_21 = 2 differ",
       "x,y,volume,stress_11,stress_12,stress_21,stress_22\n0.5,0.5,0.1,0,1,2,0\n"},
      {"no particles", "x,y,volume\n"},
      {"the header has no column v_2", "x,y,volume,v_1\n"},
  };
  for (const FileCase& c : files) {
    const std::string m = file_refusal(c.csv);
    EXPECT_NE(m.find(c.message), std::string::npos) << c.message << "\n  got: " << m;
    EXPECT_NE(m.find("particle file \""), std::string::npos) << m;
  }
  // An elastic law computes its stress from F: a stress column is refused there.
  const TempFile stressed("stressed.csv",
                          "x,y,volume,stress_11,stress_12,stress_22\n0.5,0.5,0.1,-1,0,0\n");
  const std::string m =
      refusal(free_body(2, 0.0, 1.0, 4, fmt::format("particles = \"{}\"", stressed.path.string())));
  EXPECT_NE(m.find("needs an incremental law"), std::string::npos) << m;
  (void)good;
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
