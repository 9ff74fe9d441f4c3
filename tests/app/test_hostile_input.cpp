// The command line against hostile or mistaken input, as a probe of many such runs found it:
// files that are not regular files, a mesh file that is a script, outputs onto devices, sizes
// that overflow, keys a benchmark would ignore, loads that are not numbers, one directory under
// two names, a stored configuration that must run again and restart, a history row cut by a
// full disk. Each test fails without the fix it guards.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "../support/shell.hpp"
#include "setup/config.hpp"
#include "setup/gmsh_mesh.hpp"

namespace MPM_UNITY_ID {
namespace {

namespace fs = std::filesystem;

using Result = mpm::test::ShellResult;

// Every command under a time limit: a FIFO must never block (a hang is a failure with exit code
// 124, not a hung suite).
Result shell(const std::string& command, int seconds = 120) {
  return mpm::test::shell(command, seconds);
}

Result mpm(const std::string& args, int seconds = 120) {
  return shell(std::string(MPM_BINARY) + " " + args, seconds);
}

std::string src(const std::string& rel) {
  return std::string(MPM_SOURCE_DIR) + "/" + rel;
}

std::string bytes(const fs::path& f) {
  std::ifstream in(f, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

struct Scratch {
  fs::path dir;
  explicit Scratch(const std::string& name)
      : dir(fs::temp_directory_path() /
            ("mpm_hostile_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Scratch() { fs::remove_all(dir); }
};

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(HostileInput, InputFilesThatAreNotRegularFilesAreRefusedAtOnce) {
  const Scratch s("inputs");
  const auto fifo = s.dir / "run.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string out = " --out " + (s.dir / "o").string();
  for (const std::string& args :
       {"run " + fifo.string() + out, "run --batch " + fifo.string(), "mesh " + fifo.string(),
        "study " + fifo.string() + " --refine grid.cells=5,10" + out}) {
    const auto r = mpm(args, 30);
    EXPECT_EQ(r.code, 2) << args << ": " << r.out;
    EXPECT_TRUE(contains(r.out, "it is a FIFO (named pipe), not a regular file")) << r.out;
  }
  const auto zero = mpm("run /dev/zero", 30);
  EXPECT_EQ(zero.code, 2) << zero.out;
  EXPECT_TRUE(contains(zero.out, "'/dev/zero': it is a character device")) << zero.out;
  // A 3 GiB file (sparse: nothing written) is too large for a configuration, not out of memory.
  const auto big = s.dir / "big.toml";
  std::ofstream(big).close();
  fs::resize_file(big, std::uint64_t{3} << 30);
  const auto large = mpm("run " + big.string(), 30);
  EXPECT_EQ(large.code, 2) << large.out;
  EXPECT_TRUE(contains(large.out, "is too large: 3.0 GiB")) << large.out;
}

// A Gmsh script given as a mesh (mpm mesh, grid.mesh) would run its SystemCall: refused before
// Gmsh sees it, and the command never runs.
TEST(HostileInput, AMeshFileThatIsAScriptIsRefusedAndNeverRuns) {
  const Scratch s("script");
  const auto mark = s.dir / "ran";
  const auto script = s.dir / "grid.msh";
  std::ofstream(script) << "SystemCall \"touch " << mark.string() << "\";\n";
  const auto m = mpm("mesh " + script.string());
  EXPECT_EQ(m.code, 2) << m.out;
  EXPECT_TRUE(contains(m.out, "not a Gmsh mesh file")) << m.out;
  const auto r = mpm("run " + src("examples/plate_triangles_2d.toml") +
                     " -q --set grid.mesh=" + script.string() + " --out " + (s.dir / "o").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_TRUE(contains(r.out, "grid.mesh")) << r.out;
  EXPECT_FALSE(fs::exists(mark));
}

// An output path that is a device is written through, never replaced (as root the rename made
// /dev/null a regular file).
TEST(HostileInput, AnOutputOntoADeviceNeverReplacesIt) {
  const auto r = mpm("mesh " + src("tests/data/meshes/square_v41.msh") + " --vtu /dev/null");
  EXPECT_EQ(r.code, 0) << r.out;
  struct stat st {};
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
}

// A grid whose size overflows (1e308 - (-1e308) = inf) gave "h": null and "ok".
TEST(HostileInput, AGridSizeThatOverflowsIsRefusedInEveryDimension) {
  const Scratch s("overflow");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"examples/custom_bar.toml",
       "--set grid.min=-1e308 --set grid.max=1e308 "
       "--set body.min=0 --set body.max=1"},
      {"examples/custom_plate_2d.toml",
       "--set \"grid.min=[-1e308, 0]\" --set \"grid.max=[1e308, "
       "1]\""},
      {"examples/custom_3d.toml",
       "--set \"grid.min=[-1e308, 0, 0]\" --set \"grid.max=[1e308, 1, "
       "1]\""}};
  for (const auto& [config, sets] : cases) {
    const auto r = mpm("run " + src(config) + " -q " + sets + " --out " + (s.dir / "o").string());
    EXPECT_EQ(r.code, 2) << config << ": " << r.out;
    EXPECT_TRUE(contains(r.out, "grid.max - grid.min")) << r.out;
    EXPECT_TRUE(contains(r.out, "not a finite number of metres")) << r.out;
  }
}

// Keys that only the custom problem reads were ignored in silence by the other benchmarks.
TEST(HostileInput, KeysOfTheCustomProblemAreRefusedElsewhere) {
  const Scratch s("custom_keys");
  for (const auto& [config, set, key] :
       {std::tuple{"examples/vibrating_bar_small.toml", "boundary.left=free", "boundary.left"},
        std::tuple{"examples/vibrating_bar_small.toml", "traction.right=1e3", "traction.right"},
        std::tuple{"examples/plate_mms_2d.toml", "pressure.top=1e3", "pressure.top"},
        std::tuple{"examples/cube_mms_3d.toml", "loading.body_force=[\"0\", \"0\", \"-9.81\"]",
                   "loading.body_force"}}) {
    const auto r = mpm("run " + src(config) + " -q --set \"" + std::string(set) + "\" --out " +
                       (s.dir / "o").string());
    EXPECT_EQ(r.code, 2) << config << " " << set << ": " << r.out;
    EXPECT_TRUE(
        contains(r.out, fmt::format("key '{}' is read by benchmark = \"custom\" only", key)))
        << r.out;
  }
  // The traction bar's own key is not one of them.
  const auto bar =
      mpm("run " + src("examples/traction_bar.toml") +
          " -q --set traction.amplitude=2 --set time.end=2e-4 --out " + (s.dir / "bar").string());
  EXPECT_EQ(bar.code, 0) << bar.out;
}

// Loads that are not numbers stopped with exit code 9 and "-nan" momentum: refused at set-up
// (exit 2) when not finite at t = 0, else the run stops at the step (exit 3), naming the key.
TEST(HostileInput, LoadsThatAreNotFiniteNameTheKey) {
  const Scratch s("loads");
  const std::string base = "run " + src("examples/custom_plate_2d.toml") + " -q --out ";
  const auto now = mpm(base + (s.dir / "a").string() + " --set pressure.top=1/0");
  EXPECT_EQ(now.code, 2) << now.out;
  EXPECT_TRUE(contains(now.out, "the load of key 'pressure.top' is not a finite number at t = 0"))
      << now.out;
  const auto big = mpm(base + (s.dir / "b").string() +
                       " --set \"traction.top=[\\\"1e308*1e308\\\", \\\"0\\\"]\"");
  EXPECT_EQ(big.code, 2) << big.out;
  EXPECT_TRUE(contains(big.out, "'traction.top'")) << big.out;
  const mpm::Config plate = mpm::Config::load(src("examples/custom_plate_2d.toml"));
  const double dt = plate.get_real("time.dt");
  const auto later = mpm(base + (s.dir / "c").string() +
                         fmt::format(" --set \"pressure.top=t > {:.17g} ? 1/0 : 1\" "
                                     "--set time.end={:.17g}",
                                     2.5 * dt, 10 * dt));
  EXPECT_EQ(later.code, 3) << later.out;
  EXPECT_TRUE(contains(later.out, "the load of key 'pressure.top' is not a finite number at t = "))
      << later.out;
}

// Two runs of a batch into one directory under two names (a symbolic link) were not detected.
TEST(HostileInput, BatchRunsIntoOneDirectoryThroughALinkAreRefused) {
  const Scratch s("batch_link");
  fs::create_directories(s.dir / "o");
  fs::create_directory_symlink(s.dir / "o", s.dir / "o_link");
  const std::string cfg = src("examples/vibrating_bar_small.toml");
  std::ofstream(s.dir / "b.toml") << "[[run]]\nconfig = \"" << cfg << "\"\nout = \""
                                  << (s.dir / "o" / "b").string() << "\"\n"
                                  << "[[run]]\nconfig = \"" << cfg << "\"\nout = \""
                                  << (s.dir / "o_link" / "b").string() << "\"\n";
  const auto r = mpm("run --batch " + (s.dir / "b.toml").string() + " -q");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_TRUE(contains(r.out, "as run 1 does")) << r.out;
  EXPECT_FALSE(fs::exists(s.dir / "o" / "b"));
}

// Smaller ones: a long --set argument is not echoed whole; a study value given twice is refused
// (it said the directory was in use by the study's own process).
TEST(HostileInput, LongArgumentsAreCutAndStudyValuesTwiceRefused) {
  const Scratch s("small");
  // (100 kB: one argument of the shell's command line may hold at most 128 KiB on Linux.)
  const std::string huge(100000, '7');
  const auto r = mpm("run " + src("examples/vibrating_bar_small.toml") + " --set grid.cells=x" +
                     huge + " --out " + (s.dir / "o").string());
  EXPECT_EQ(r.code, 2) << r.out.substr(0, 2000);
  EXPECT_LT(r.out.size(), 4000u) << r.out.substr(0, 2000);
  EXPECT_TRUE(contains(r.out, "(100012 characters)")) << r.out.substr(0, 2000);
  const auto twice = mpm("study " + src("examples/vibrating_bar_small.toml") +
                         " --refine grid.cells=5,5 --out " + (s.dir / "st").string());
  EXPECT_EQ(twice.code, 2) << twice.out;
  EXPECT_TRUE(contains(twice.out, "gives the value 5 twice")) << twice.out;
}

// A study over mesh files printed no orders: h was the bounding box's, the same for every mesh.
// A mesh run reports the mesh's own size: its triangles as cells, its longest edge as h.
TEST(HostileInput, AStudyOverMeshFilesHasTheMeshesSizesAndOrders) {
  const Scratch s("mesh_study");
  const std::vector<std::string> meshes = {"meshes/plate_unstructured_8.msh",
                                           "meshes/plate_unstructured_16.msh"};
  const auto r = mpm("study " + src("examples/plate_ps_unstructured_2d.toml") +
                     " --refine grid.mesh=" + meshes[0] + "," + meshes[1] +
                     " --set time.end=2e-4 --set output.frames=0 --out " + (s.dir / "st").string());
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream csv(s.dir / "st" / "study.csv");
  std::string line;
  std::getline(csv, line);  // method,grid.mesh,cells,h,...
  for (const auto& file : meshes) {
    ASSERT_TRUE(std::getline(csv, line));
    const auto m = mpm::read_gmsh_mesh(src("examples/" + file));
    double longest = 0.0;
    for (mpm::Index c = 0; c < m.num_cells(); ++c) {
      const auto& t = m.cell_vertices(c);
      for (std::size_t i = 0; i < 3; ++i)
        longest = std::max(longest, (m.vertex(t[(i + 1) % 3]) - m.vertex(t[i])).norm());
    }
    std::vector<std::string> f;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) f.push_back(cell);
    ASSERT_GE(f.size(), 4u) << line;
    EXPECT_EQ(std::stoll(f[2]), m.num_cells()) << line;
    EXPECT_EQ(std::stod(f[3]), longest) << line;
  }
  // The finer mesh's row of the table has its orders (a number after each error).
  std::ifstream txt(s.dir / "st" / "study.txt");
  std::vector<std::string> rows;
  for (std::string l; std::getline(txt, l);) rows.push_back(l);
  ASSERT_GE(rows.size(), 4u);
  std::stringstream coarse(rows[2]), fine(rows[3]);
  const auto words = [](std::stringstream& in) {
    int n = 0;
    for (std::string w; in >> w;) ++n;
    return n;
  };
  EXPECT_GT(words(fine), words(coarse)) << rows[2] << "\n" << rows[3];
}

// A full disk in the middle of history.csv (here a file-size limit, which mpm meets as EFBIG
// with SIGXFSZ ignored): the message names history.csv and the row, the file keeps whole rows
// only, and the failed summary says so.
TEST(HostileInput, AHistoryRowThatCannotBeWrittenIsNamedAndNotLeftHalf) {
  const Scratch s("history");
  const auto out = s.dir / "o";
  // 80 blocks of 512 bytes (dash) or of 1 KiB (bash): config.toml (about 20 KB, every key with
  // its description) fits, the history of 2000 rows (about 200 KB) does not.
  const auto r = shell("ulimit -f 80; exec " + std::string(MPM_BINARY) + " run " +
                       src("examples/custom_bar.toml") +
                       " -q --set output.csv=false --set output.vtk=false "
                       "--set output.history_every=1 --out " +
                       out.string());
  EXPECT_EQ(r.code, 8) << r.out;
  EXPECT_TRUE(
      contains(r.out, "cannot write '" + (out / "history.csv").string() + "' (write of row "))
      << r.out;
  const std::string history = bytes(out / "history.csv");
  ASSERT_FALSE(history.empty());
  EXPECT_EQ(history.back(), '\n') << "a partial row was left";
  const auto j = nlohmann::json::parse(bytes(out / "summary.json"));
  EXPECT_EQ(j["exit_code"], 8);
  EXPECT_TRUE(contains(j["failure"].get<std::string>(), "history.csv")) << j["failure"];
}

// Every example runs from its own written config.toml to the same bytes, and restarts from a
// checkpoint alone (the stored configuration) to the end of the uninterrupted run; a mesh run's
// checkpoint refuses a mesh file that changed.
TEST(HostileInput, EveryExampleRerunsFromItsConfigAndRestartsFromItsCheckpoint) {
  const Scratch s("roundtrip");
  int n = 0;
  for (const auto& entry : fs::directory_iterator(src("examples"))) {
    if (entry.path().extension() != ".toml") continue;
    const std::string name = entry.path().stem().string();
    const double dt = mpm::Config::load(entry.path().string()).get_real("time.dt");
    const std::string sets = fmt::format(
        " -q --set time.end={:.17g} --set output.checkpoint_every=2 --set output.frames=1 "
        "--set output.vtk=false",
        3 * dt);
    const auto first = s.dir / (name + "_first");
    const auto r = mpm("run " + entry.path().string() + sets + " --out " + first.string());
    ASSERT_EQ(r.code, 0) << name << ": " << r.out;
    // The written configuration runs, from anywhere, to the same bytes.
    const auto again = s.dir / (name + "_again");
    const auto a = shell("cd / && exec " + std::string(MPM_BINARY) + " run " +
                         (first / "config.toml").string() + " -q --out " + again.string());
    ASSERT_EQ(a.code, 0) << name << ": " << a.out;
    EXPECT_EQ(bytes(again / "history.csv"), bytes(first / "history.csv")) << name;
    // The checkpoint alone (step 2), from anywhere, continues to step 3 as the first run did.
    const auto alone = s.dir / (name + "_restart");
    fs::create_directories(alone);
    fs::copy_file(first / "checkpoint.bin", alone / "checkpoint.bin");
    const auto b = shell("cd / && exec " + std::string(MPM_BINARY) + " run --restart " +
                         (alone / "checkpoint.bin").string() + " -q");
    ASSERT_EQ(b.code, 0) << name << ": " << b.out;
    const std::string h1 = bytes(first / "history.csv"), h2 = bytes(alone / "history.csv");
    const auto last_row = [](const std::string& h) {
      const auto end = h.find_last_of('\n', h.size() - 2);
      return h.substr(end + 1);
    };
    EXPECT_EQ(last_row(h2), last_row(h1)) << name;
    ++n;
  }
  EXPECT_EQ(n, 26);  // (every example: a new one is checked too)
  // A mesh run: the mesh file changes after the checkpoint (one more blank line: the same mesh,
  // other bytes), and the restart refuses it.
  const auto dir = s.dir / "mesh";
  fs::create_directories(dir / "meshes");
  fs::copy_file(src("examples/incline_pressure_2d.toml"), dir / "incline.toml");
  fs::copy_file(src("examples/meshes/incline_30.msh"), dir / "meshes" / "incline_30.msh");
  const auto r = mpm("run " + (dir / "incline.toml").string() +
                     " -q --set time.end=7.5e-4 --set output.checkpoint_every=2 --out " +
                     (dir / "o").string());
  ASSERT_EQ(r.code, 0) << r.out;
  std::ofstream(dir / "meshes" / "incline_30.msh", std::ios::app) << "\n";
  const auto refused = mpm("run --restart " + (dir / "o" / "checkpoint.bin").string() + " -q");
  EXPECT_EQ(refused.code, 2) << refused.out;
  EXPECT_TRUE(contains(refused.out, "is not the one checkpoint")) << refused.out;
  // The same for a body's particle file (body.particles), on a grid mesh (grid.mesh): both files
  // are named, and the change of either is refused.
  const auto body = dir / "particles.csv";
  std::ofstream(body) << "x,y,volume\n0.3,0.3,0.01\n0.4,0.35,0.01\n";
  const auto both =
      mpm("run " + (dir / "incline.toml").string() + " -q --set time.end=7.5e-4 " +
          "--set output.checkpoint_every=2 --set body.particles=particles.csv " +
          "--set particles.per_triangle=0 --set boundary.loaded= --set pressure.loaded=0 " +
          "--out " + (dir / "p").string());
  ASSERT_EQ(both.code, 0) << both.out;
  std::ofstream(body, std::ios::app) << "# one more line\n";
  const auto changed = mpm("run --restart " + (dir / "p" / "checkpoint.bin").string() + " -q");
  EXPECT_EQ(changed.code, 2) << changed.out;
  EXPECT_TRUE(contains(changed.out, "are not the ones checkpoint")) << changed.out;
  EXPECT_TRUE(contains(changed.out, "body.particles '")) << changed.out;
}

}  // namespace
}  // namespace MPM_UNITY_ID
