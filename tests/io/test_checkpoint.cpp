// Checkpoint and restart (io/checkpoint.hpp, README "Checkpoints"): a run restarted from the
// checkpoint at step k ends in bit for bit the state of the uninterrupted run, and damaged or
// foreign checkpoint files are refused with an error naming the file.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>

#include "core/bytes.hpp"
#include "driver/run.hpp"
#include "io/checkpoint.hpp"
#include "io/output.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

namespace fs = std::filesystem;

// A fresh directory under the system temporary directory, removed at the end of the test.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    static int counter = 0;
    path_ = fs::temp_directory_path() /
            fmt::format("mpmlab_checkpoint_{}_{}_{}", tag, ::getpid(), counter++);
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string example(const std::string& name) {
  return std::string(MPM_SOURCE_DIR) + "/examples/" + name + ".toml";
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

void spit(const fs::path& p, const std::string& s) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << s;
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  // memcmp with the null data() of an empty vector is undefined even for length 0 (UBSan).
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

void expect_same(const io::ParticleArrays& a, const io::ParticleArrays& b,
                 const std::string& what) {
  EXPECT_EQ(a.dim, b.dim) << what;
  EXPECT_EQ(a.count, b.count) << what;
  ASSERT_EQ(a.reals.size(), io::particle_field_names().size()) << what;
  ASSERT_EQ(b.reals.size(), a.reals.size()) << what;
  for (std::size_t k = 0; k < a.reals.size(); ++k)
    EXPECT_TRUE(same_bytes(a.reals[k], b.reals[k])) << what << " " << io::particle_field_names()[k];
  EXPECT_TRUE(same_bytes(a.id, b.id)) << what << " id";
}

// The complete state at the end of a run: its last checkpoint (written at step `steps`).
void expect_same_state(const io::Checkpoint& a, const io::Checkpoint& b) {
  EXPECT_EQ(a.solver, b.solver);
  EXPECT_EQ(a.step, b.step);
  EXPECT_EQ(std::memcmp(&a.time, &b.time, sizeof(double)), 0);
  expect_same(a.particles, b.particles, "particles");
  EXPECT_TRUE(same_bytes(a.cells, b.cells));
  EXPECT_EQ(std::memcmp(&a.diag.max_rel_mass_error, &b.diag.max_rel_mass_error, sizeof(double)), 0);
  EXPECT_EQ(
      std::memcmp(&a.diag.max_rel_momentum_error, &b.diag.max_rel_momentum_error, sizeof(double)),
      0);
  EXPECT_EQ(a.diag.grid_crossings, b.diag.grid_crossings);
  ASSERT_EQ(a.fem.has_value(), b.fem.has_value());
  if (a.fem) {
    EXPECT_TRUE(same_bytes(a.fem->x, b.fem->x));
    EXPECT_TRUE(same_bytes(a.fem->v, b.fem->v));
    EXPECT_TRUE(same_bytes(a.fem->body, b.fem->body));
    expect_same(a.fem->elements, b.fem->elements, "FEM elements");
    EXPECT_EQ(std::memcmp(&a.fem->time, &b.fem->time, sizeof(double)), 0);
    EXPECT_EQ(a.fem->steps, b.fem->steps);
  }
  EXPECT_EQ(a.mapping, b.mapping);
  EXPECT_EQ(a.mapping_totals, b.mapping_totals);
  EXPECT_TRUE(same_bytes(a.basis_state, b.basis_state));
}

struct Case {
  std::string name;  // example file
  std::vector<std::string> sets;
  int k;  // checkpoint interval; the runs take 3 k steps
};

RunResult run_in(const Config& cfg, const fs::path& dir,
                 std::shared_ptr<const io::Checkpoint> restart = nullptr,
                 const std::string& restart_name = "") {
  RunOptions ro;
  ro.out_dir = dir.string();
  ro.quiet = true;
  ro.restart = std::move(restart);
  ro.restart_name = restart_name;
  return run(cfg, ro);
}

// Uninterrupted: 3k steps with checkpoint_every = k. Interrupted: the same configuration stopped
// at step k (time.end = k dt), then restarted from its checkpoint with time.end = 3k dt.
void check_bitwise_restart(const Case& c) {
  SCOPED_TRACE(c.name);
  TempDir full("full"), part("part"), cont("cont");
  const int n = 3 * c.k;
  auto sets = c.sets;
  sets.insert(sets.end(), {"output.csv=false", "output.vtk=false",
                           fmt::format("output.checkpoint_every={}", c.k)});
  const double dt = Config::load(example(c.name), sets).get_real("time.dt");
  auto with_end = [&](int steps) {
    auto s = sets;
    s.push_back(fmt::format("time.end={}", steps * dt));
    return s;
  };
  const auto r_full = run_in(Config::load(example(c.name), with_end(n)), full.path());
  ASSERT_EQ(r_full.exit_code, 0) << r_full.failure;
  const auto r_part = run_in(Config::load(example(c.name), with_end(c.k)), part.path());
  ASSERT_EQ(r_part.exit_code, 0) << r_part.failure;

  const fs::path file = part.path() / io::kCheckpointFile;
  auto ck = std::make_shared<const io::Checkpoint>(io::read_checkpoint(file));
  ASSERT_EQ(ck->step, c.k);
  const Config cfg =
      io::restart_config(*ck, file.string(), nullptr, {fmt::format("time.end={}", n * dt)});
  const auto r_cont = run_in(cfg, cont.path(), ck, file.string());
  ASSERT_EQ(r_cont.exit_code, 0) << r_cont.failure;
  EXPECT_EQ(r_cont.steps, n);

  const auto a = io::read_checkpoint(full.path() / io::kCheckpointFile);
  const auto b = io::read_checkpoint(cont.path() / io::kCheckpointFile);
  ASSERT_EQ(a.step, n);
  ASSERT_EQ(b.step, n);
  expect_same_state(a, b);
  // The summaries agree too (error norms against the exact or FEM reference solution).
  EXPECT_EQ(r_full.summary["errors"].dump(), r_cont.summary["errors"].dump());
  EXPECT_EQ(r_full.summary["conservation"].dump(), r_cont.summary["conservation"].dump());
  EXPECT_EQ(r_full.summary["grid_crossings"], r_cont.summary["grid_crossings"]);
  for (const char* totals : {"tls", "mls"}) {
    if (r_full.summary.contains(totals)) {
      EXPECT_EQ(r_full.summary[totals], r_cont.summary[totals]);
    }
  }
}

TEST(Checkpoint, RestartIsBitwiseP1DirectMusl) {
  check_bitwise_restart({"vibrating_bar_crossing",
                         {"method.basis=linear", "method.mapping=direct", "method.scheme=musl"},
                         40});
}

TEST(Checkpoint, RestartIsBitwiseBsplineTlsConsistent) {
  check_bitwise_restart(
      {"vibrating_bar_small",
       {"method.basis=bspline", "method.degree=2", "method.mapping=tls", "method.mass=consistent"},
       20});
}

TEST(Checkpoint, RestartIsBitwise2DPlate) {
  // 2D, rollers (per-component Dirichlet) and the per-component consistent-mass solves.
  check_bitwise_restart({"plate_mms_2d", {"grid.cells=4"}, 20});
  check_bitwise_restart(
      {"plate_mms_2d", {"grid.cells=4", "method.mass=consistent", "method.scheme=usavg"}, 20});
  // CPDI2 carries its tracked corners between steps (checkpoint basis state).
  check_bitwise_restart({"plate_mms_2d", {"grid.cells=4", "method.basis=cpdi2"}, 20});
}

TEST(Checkpoint, RestartIsBitwise3DCube) {
  // 3D (issue 20): quadratic B-splines with lumped mass, and uGIMP with consistent mass (three
  // per-component solves of the rollers on the six faces).
  check_bitwise_restart({"cube_mms_3d", {"grid.cells=3"}, 10});
  check_bitwise_restart(
      {"cube_mms_3d",
       {"grid.cells=3", "method.basis=ugimp", "method.mass=consistent", "method.scheme=usf"},
       10});
}

TEST(Checkpoint, RestartIsBitwise2DCustomWithTraction) {
  // Vector keys (arrays) in the stored configuration, expression fields, a face traction.
  check_bitwise_restart({"custom_plate_2d", {"traction.top=[\"1e3*t\", \"-1e3\"]"}, 50});
}

TEST(Checkpoint, RestartIsBitwise3DCustomWithPressure) {
  // 3D custom problem: three-value arrays in the stored configuration, the z faces' keys
  // (boundary.back/front, pressure.front), a face load in 3D.
  check_bitwise_restart({"custom_3d", {"pressure.front=1e4*t"}, 20});
}

TEST(Checkpoint, RestartIsBitwiseLargeBarWithFemReference) {
  check_bitwise_restart({"vibrating_bar_large", {}, 100});
}

TEST(Checkpoint, RestartIsBitwiseOtherSolversAndLoads) {
  check_bitwise_restart({"vibrating_bar_large", {"method.mapping=mls"}, 50});
  check_bitwise_restart({"vibrating_bar_large", {"method.solver=ulfem"}, 50});
  check_bitwise_restart({"vibrating_bar_large", {"method.mapping=cubic_spline"}, 50});
  check_bitwise_restart({"vibrating_bar_large", {"method.basis=ddmpm", "method.scheme=usavg"}, 50});
  check_bitwise_restart({"column_compaction", {"method.basis=cpgimp", "method.scheme=usl"}, 50});
  check_bitwise_restart({"traction_bar", {"method.scheme=usf", "method.basis=cpdi"}, 50});
  // OTM: the advected nodes and the particles' velocities (x_p^s - x_p^{s-1}) / dt.
  check_bitwise_restart(
      {"bar_fixed_ends_otm", {"method.solver=otm", "method.mass=consistent"}, 50});
  check_bitwise_restart({"bar_fixed_ends_otm",
                         {"method.solver=otm", "method.basis=maxent", "method.mass=consistent"},
                         50});
  check_bitwise_restart({"bar_fixed_ends_otm",
                         {"method.solver=unified", "method.basis=bspline", "method.degree=3",
                          "method.mass=consistent"},
                         50});
  check_bitwise_restart({"plate_mms_2d",
                         {"method.solver=unified", "method.basis=bspline", "method.degree=2",
                          "method.mass=consistent", "grid.cells=4"},
                         20});
}

// A valid checkpoint of a short run, written into dir.
fs::path short_checkpoint(const fs::path& dir) {
  const auto r =
      run_in(Config::load(example("vibrating_bar_small"),
                          {"output.csv=false", "output.vtk=false", "output.checkpoint_every=5",
                           "time.end=1e-6", "output.frames=10"}),
             dir);
  EXPECT_EQ(r.exit_code, 0) << r.failure;
  return dir / io::kCheckpointFile;
}

// The InputError message of reading `file`, or "" when it reads.
std::string read_error(const fs::path& file) {
  try {
    io::read_checkpoint(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Checkpoint, HeaderLayoutAndRoundTrip) {
  TempDir dir("layout");
  const auto file = short_checkpoint(dir.path());
  const std::string bytes = slurp(file);
  ASSERT_GT(bytes.size(), io::kCheckpointHeaderBytes);
  EXPECT_EQ(bytes.substr(0, 8), "MPMLABCK");
  EXPECT_EQ(static_cast<unsigned char>(bytes[8]), io::kCheckpointVersion);
  const auto c = io::read_checkpoint(file);
  EXPECT_EQ(c.step, 10);
  EXPECT_EQ(c.solver, "mpm");
  EXPECT_EQ(c.particles.count, 20 * 12);
  EXPECT_NE(c.config.find("checkpoint_every = 5"), std::string::npos);
  EXPECT_EQ(c.frames, 11);  // initial + 10 frames
  EXPECT_EQ(io::encode_checkpoint(c), bytes);
  // FNV-1a 64 test vectors (Fowler, Noll, Vo).
  EXPECT_EQ(io::fnv1a64(""), 0xcbf29ce484222325ull);
  EXPECT_EQ(io::fnv1a64("a"), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(io::fnv1a64("foobar"), 0x85944171f73967e8ull);
}

// A distributed run's checkpoint (io/checkpoint.hpp): a manifest and one piece per process,
// made here by hand from a one-process checkpoint of the bar (20 cells of 12 particles, in id
// order from left to right) cut into three slabs of cell layers [0, 7), [7, 12), [12, 20), as
// three processes would have written it. Joined, the pieces are the whole state; a restart on
// one process from them continues as from the single file, bit for bit; a damaged, foreign or
// misnamed piece is refused, naming it.
TEST(Checkpoint, ADistributedCheckpointsPiecesJoinIntoTheWholeState) {
  TempDir dir("pieces"), split("pieces_split");
  const auto file = short_checkpoint(dir.path());
  const io::Checkpoint whole = io::read_checkpoint(file);
  ASSERT_EQ(whole.particles.count, 240);
  ASSERT_EQ(whole.cells.size(), 240u);
  const std::vector<std::int64_t> cuts{0, 7, 12, 20};
  io::Checkpoint manifest = whole;
  manifest.particles = io::ParticleArrays{};
  manifest.particles.dim = 1;
  manifest.cells.clear();
  manifest.distribution = {3, 3, 0, 7, 12, 20};  // 3 processes, 3 along x, the cuts
  manifest.layer_counts.assign(20, 12);
  std::vector<std::string> bytes(3);
  for (int r = 0; r < 3; ++r) {
    const auto first = static_cast<std::size_t>(12 * cuts[static_cast<std::size_t>(r)]);
    const auto end = static_cast<std::size_t>(12 * cuts[static_cast<std::size_t>(r) + 1]);
    io::CheckpointPiece piece;
    piece.step = whole.step;
    piece.rank = r;
    piece.ranks = 3;
    piece.particles.dim = 1;
    piece.particles.count = static_cast<std::int64_t>(end - first);
    for (std::size_t f = 0; f < whole.particles.reals.size(); ++f) {
      const auto& all = whole.particles.reals[f];
      const std::size_t k = all.size() / 240;  // values per particle
      piece.particles.reals[f].assign(all.begin() + static_cast<std::ptrdiff_t>(k * first),
                                      all.begin() + static_cast<std::ptrdiff_t>(k * end));
    }
    piece.particles.id.assign(whole.particles.id.begin() + static_cast<std::ptrdiff_t>(first),
                              whole.particles.id.begin() + static_cast<std::ptrdiff_t>(end));
    piece.cells.assign(whole.cells.begin() + static_cast<std::ptrdiff_t>(first),
                       whole.cells.begin() + static_cast<std::ptrdiff_t>(end));
    const std::string name = io::checkpoint_piece_name(whole.step, r);
    bytes[static_cast<std::size_t>(r)] = io::encode_piece(piece);
    // What a process writes from its particles: the same bytes.
    const std::vector<CompactIndex> cells(piece.cells.begin(), piece.cells.end());
    EXPECT_EQ(io::encode_piece<1>(whole.step, r, 3, io::unpack_particles<1>(piece.particles, "p"),
                                  cells, {}),
              bytes[static_cast<std::size_t>(r)]);
    spit(split.path() / name, bytes[static_cast<std::size_t>(r)]);
    manifest.pieces.push_back(io::describe_piece(name, bytes[static_cast<std::size_t>(r)]));
    // count, re-sorting reference, sorts, grid crossings (all of them on rank 0)
    manifest.distribution.insert(manifest.distribution.end(),
                                 {piece.particles.count, -1, r == 0 ? whole.sorts : 0,
                                  r == 0 ? whole.diag.grid_crossings : 0});
  }
  const fs::path mfile = split.path() / io::kCheckpointFile;
  io::write_checkpoint(mfile, manifest);
  // The manifest reads back as written, without particles; joined, the pieces are the state.
  const io::Checkpoint m = io::read_checkpoint(mfile);
  EXPECT_EQ(io::encode_checkpoint(m), io::encode_checkpoint(manifest));
  EXPECT_EQ(m.particles.count, 0);
  ASSERT_EQ(m.pieces.size(), 3u);
  EXPECT_EQ(m.pieces[1].file, "checkpoint_s10_p0001.bin");
  EXPECT_EQ(m.pieces[1].bytes, bytes[1].size());
  const io::Checkpoint joined = io::read_whole_checkpoint(mfile);
  expect_same(joined.particles, whole.particles, "joined pieces");
  EXPECT_TRUE(same_bytes(joined.cells, whole.cells));
  // Only the pieces chosen: the middle one.
  io::Checkpoint middle = m;
  EXPECT_EQ(io::join_pieces(middle, mfile, {false, true, false}), (std::vector<std::int64_t>{60}));
  EXPECT_EQ(middle.particles.count, 60);
  EXPECT_EQ(middle.particles.id.front(), 84);

  // A restart on one process from the manifest and from the single file: the same end state.
  TempDir a("pieces_a"), b("pieces_b");
  const auto restart = [&](const fs::path& from, const fs::path& out) {
    auto ck = std::make_shared<const io::Checkpoint>(io::read_checkpoint(from));
    const Config cfg = io::restart_config(*ck, from.string(), nullptr, {"time.end=1.5e-6"});
    const RunResult r = run_in(cfg, out, ck, from.string());
    EXPECT_EQ(r.exit_code, 0) << r.failure;
    return io::read_checkpoint(out / io::kCheckpointFile);
  };
  expect_same_state(restart(mfile, a.path()), restart(file, b.path()));

  // Refused, naming the piece: a flipped byte, a piece of another step (its hash differs from
  // the manifest's), one missing, and a manifest naming another path.
  const auto join_error = [&](const io::Checkpoint& c) {
    try {
      io::Checkpoint copy = c;
      io::join_pieces(copy, mfile, std::vector<bool>(copy.pieces.size(), true));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const fs::path piece1 = split.path() / m.pieces[1].file;
  std::string flipped = bytes[1];
  flipped[flipped.size() / 2] = static_cast<char>(flipped[flipped.size() / 2] ^ 8);
  spit(piece1, flipped);
  std::string msg = join_error(m);
  EXPECT_NE(msg.find(piece1.string() + "' is corrupted"), std::string::npos) << msg;
  io::CheckpointPiece other = io::decode_piece(bytes[1], "piece 1");
  other.step = 5;
  spit(piece1, io::encode_piece(other));
  msg = join_error(m);
  EXPECT_NE(msg.find("is not the one"), std::string::npos) << msg;
  EXPECT_NE(msg.find(piece1.string()), std::string::npos) << msg;
  fs::remove(piece1);
  msg = join_error(m);
  EXPECT_NE(msg.find("cannot open checkpoint piece '" + piece1.string()), std::string::npos) << msg;
  spit(piece1, bytes[1]);
  EXPECT_EQ(join_error(m), "");
  io::Checkpoint elsewhere = m;
  elsewhere.pieces[2].file = "../checkpoint_s10_p0002.bin";
  msg = join_error(elsewhere);
  EXPECT_NE(msg.find("names piece 2 '../checkpoint_s10_p0002.bin'"), std::string::npos) << msg;
  // A piece where the manifest is expected (mpm run --restart PIECE).
  msg = read_error(piece1);
  EXPECT_NE(msg.find("is one process's piece of a distributed checkpoint; restart from the "
                     "checkpoint.bin next to it"),
            std::string::npos)
      << msg;
  // The restarted run into the pieces' directory removes them when it writes its own
  // checkpoint (a single file: one process).
  {
    auto ck = std::make_shared<const io::Checkpoint>(m);
    const Config cfg = io::restart_config(*ck, mfile.string(), nullptr, {"time.end=1.5e-6"});
    EXPECT_EQ(run_in(cfg, split.path(), ck, mfile.string()).exit_code, 0);
    EXPECT_FALSE(fs::exists(piece1));
    EXPECT_TRUE(io::read_checkpoint(mfile).pieces.empty());
  }
}

TEST(Checkpoint, CorruptionTruncationAndOtherVersionsAreRefused) {
  TempDir dir("corrupt");
  const auto file = short_checkpoint(dir.path());
  const std::string good = slurp(file);
  const fs::path bad = dir.path() / "bad.bin";
  auto expect_error = [&](const std::string& content, const std::string& words) {
    spit(bad, content);
    const std::string msg = read_error(bad);
    EXPECT_NE(msg.find(bad.string()), std::string::npos) << msg;
    EXPECT_NE(msg.find(words), std::string::npos) << msg;
  };
  // One bit flipped anywhere in the payload: checksum mismatch.
  for (std::size_t at : {io::kCheckpointHeaderBytes, good.size() / 2, good.size() - 1}) {
    std::string s = good;
    s[at] = static_cast<char>(s[at] ^ 0x10);
    expect_error(s, "corrupted");
  }
  // In the stored checksum itself.
  std::string s = good;
  s[20] = static_cast<char>(s[20] ^ 1);
  expect_error(s, "corrupted");
  // Truncated at several points, header included.
  for (std::size_t n :
       {std::size_t{0}, std::size_t{5}, std::size_t{20}, good.size() / 2, good.size() - 1})
    expect_error(good.substr(0, n), "truncated");
  expect_error(good + "x", "longer");
  // Another format version, another file type.
  s = good;
  s[8] = static_cast<char>(io::kCheckpointVersion + 1);
  expect_error(s, fmt::format("format version {}", io::kCheckpointVersion + 1));
  expect_error("# not a checkpoint\n" + good, "not an mpmlab checkpoint");
  EXPECT_NE(read_error(dir.path() / "missing.bin").find("cannot open"), std::string::npos);
  EXPECT_EQ(read_error(file), "");
}

// The flag before the FEM state is 0 or 1; another byte with a valid checksum is malformed (it
// decoded as "present" and encoded back as 1: a fuzzer finding).
TEST(Checkpoint, AFlagByteOtherThanZeroOrOneIsRefused) {
  TempDir dir("flag");
  const auto file = short_checkpoint(dir.path());
  io::Checkpoint c = io::read_checkpoint(file);
  ASSERT_FALSE(c.fem);
  const std::string good = io::encode_checkpoint(c);
  // The flag follows the diagnostics; find it as the byte that an FEM-less encoding has where
  // one with an (empty) FEM state has 1.
  io::Checkpoint with_fem = c;
  with_fem.fem = io::FemArrays{};
  const std::string other = io::encode_checkpoint(with_fem);
  std::size_t at = io::kCheckpointHeaderBytes;
  while (at < good.size() && good[at] == other[at]) ++at;
  ASSERT_LT(at, good.size());
  ASSERT_EQ(good[at], 0);
  std::string payload = good.substr(io::kCheckpointHeaderBytes);
  payload[at - io::kCheckpointHeaderBytes] = 0x60;
  mpm::ByteWriter w;
  w.bytes().append(io::kCheckpointMagic);
  w.u32(io::kCheckpointVersion);
  w.u64(payload.size());
  w.u64(io::fnv1a64(payload));
  w.bytes().append(payload);
  try {
    (void)io::decode_checkpoint(w.bytes(), "flagged.bin");
    FAIL() << "a flag byte of 0x60 was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("malformed"), std::string::npos) << e.what();
  }
}

TEST(Checkpoint, RestartConfigAllowsOnlyOutputAndEndTime) {
  TempDir dir("config");
  const auto file = short_checkpoint(dir.path());
  const auto c = io::read_checkpoint(file);
  const std::string name = file.string();
  // The stored configuration, with output.* and time.end changed: accepted.
  EXPECT_NO_THROW(io::restart_config(c, name, nullptr,
                                     {"time.end=2e-6", "output.frames=3", "output.vtk=true"}));
  // Other keys: refused, each differing key listed.
  try {
    io::restart_config(c, name, nullptr, {"grid.cells=10", "material.density=1000"});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("grid.cells: checkpoint 20, now 10"), std::string::npos) << msg;
    EXPECT_NE(msg.find("material.density"), std::string::npos) << msg;
    EXPECT_NE(msg.find("2 key(s)"), std::string::npos) << msg;
    EXPECT_NE(msg.find(name), std::string::npos) << msg;
  }
  // A CONFIG file given on the command line: the example itself matches (its time.end and
  // output keys differ), a changed method does not.
  const Config same = Config::load(example("vibrating_bar_small"));
  EXPECT_NO_THROW(io::restart_config(c, name, &same));
  const Config other = Config::load(example("vibrating_bar_small"), {"method.scheme=usl"});
  EXPECT_THROW(io::restart_config(c, name, &other), InputError);
  // A checkpoint beyond the end time.
  auto ck = std::make_shared<const io::Checkpoint>(c);
  EXPECT_THROW(
      run_in(io::restart_config(c, name, nullptr, {"time.end=5e-7"}), dir.path(), ck, name),
      InputError);
  // Restart at the end: nothing to do, the state stays.
  const auto r =
      run_in(io::restart_config(c, name, nullptr, {"time.end=1e-6"}), dir.path(), ck, name);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.steps, 10);
}

// A checkpoint with a valid hash but a state no run of this configuration reaches (issue 16, 9:
// step -5, or a time past time.end, ran with status ok and history.csv going backwards) is
// refused before the first step, naming the checkpoint and what is wrong.
TEST(Checkpoint, InconsistentStatesAreRefused) {
  TempDir dir("inconsistent");
  const auto file = short_checkpoint(dir.path());
  const io::Checkpoint good = io::read_checkpoint(file);
  ASSERT_EQ(good.step, 10);
  const std::vector<std::function<void(io::Checkpoint&)>> crafts = {
      [](io::Checkpoint& c) { c.step = -5; },
      [](io::Checkpoint& c) { c.time = 1.0; },  // past time.end, step 10 unchanged
      [](io::Checkpoint& c) { c.time = std::nextafter(c.time, 1.0); },
      [](io::Checkpoint& c) { c.sorts = -1; },
      [](io::Checkpoint& c) { c.diag.grid_crossings = -3; },
      [](io::Checkpoint& c) { c.cells[7] = 1000000; }};
  for (std::size_t k = 0; k < crafts.size(); ++k) {
    SCOPED_TRACE(k);
    auto c = std::make_shared<io::Checkpoint>(good);
    crafts[k](*c);
    TempDir out("inconsistent_run");
    const auto cfg = io::restart_config(*c, "crafted.bin", nullptr, {"time.end=2e-6"});
    try {
      const RunResult r = run_in(cfg, out.path(), c, "crafted.bin");
      ADD_FAILURE() << "ran with exit code " << r.exit_code;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("checkpoint 'crafted.bin' is not a state of this run"),
                std::string::npos)
          << e.what();
    }
  }
  // The untouched checkpoint restarts.
  TempDir out("consistent_run");
  const auto c = std::make_shared<const io::Checkpoint>(good);
  const auto cfg = io::restart_config(*c, "good.bin", nullptr, {"time.end=2e-6"});
  EXPECT_EQ(run_in(cfg, out.path(), c, "good.bin").exit_code, 0);
}

TEST(Checkpoint, FramesContinueAfterRestart) {
  TempDir dir("frames");
  const auto sets = std::vector<std::string>{"output.checkpoint_every=6", "output.frames=4",
                                             "time.end=1.2e-6", "output.vtk=true"};
  ASSERT_EQ(run_in(Config::load(example("vibrating_bar_small"), sets), dir.path()).exit_code, 0);
  const auto file = dir.path() / io::kCheckpointFile;
  auto ck = std::make_shared<const io::Checkpoint>(io::read_checkpoint(file));
  ASSERT_EQ(ck->step, 12);
  // Frames at steps 0, 3, 6, 9, 12; restart from a checkpoint at step 6 of a longer run.
  TempDir part("frames_part");
  auto s = sets;
  s.push_back("time.end=6e-7");
  s.push_back("output.frames=2");  // frames at 0, 3, 6 of 6 steps
  ASSERT_EQ(run_in(Config::load(example("vibrating_bar_small"), s), part.path()).exit_code, 0);
  const auto pfile = part.path() / io::kCheckpointFile;
  auto pck = std::make_shared<const io::Checkpoint>(io::read_checkpoint(pfile));
  EXPECT_EQ(pck->frames, 3);
  const auto cfg =
      io::restart_config(*pck, pfile.string(), nullptr, {"time.end=1.2e-6", "output.frames=4"});
  ASSERT_EQ(run_in(cfg, part.path(), pck, pfile.string()).exit_code, 0);
  // 9 and 12 continue the numbering; the series lists all five.
  EXPECT_TRUE(fs::exists(part.path() / "particles_00003.csv"));
  EXPECT_TRUE(fs::exists(part.path() / "particles_00004.csv"));
  EXPECT_FALSE(fs::exists(part.path() / "particles_00005.csv"));
  const std::string pvd = slurp(part.path() / "particles.pvd");
  EXPECT_NE(pvd.find("particles_00000.vtu"), std::string::npos);
  EXPECT_NE(pvd.find("particles_00004.vtu"), std::string::npos);
  // history.csv continues: the earlier run's rows before the checkpoint (steps 0 to 5) and the
  // restarted run's (6 to 12) under the header, the file of the uninterrupted run bit for bit.
  const std::string hist = slurp(part.path() / "history.csv");
  EXPECT_EQ(std::count(hist.begin(), hist.end(), '\n'), 1 + 13);
  EXPECT_EQ(hist, slurp(dir.path() / "history.csv"));
  EXPECT_EQ(slurp(part.path() / "particles_00004.csv"), slurp(dir.path() / "particles_00004.csv"));
}

// `mpm run --restart`: the exit code and message of a damaged file, a mismatching CONFIG, and a
// restart without CONFIG into the checkpoint's directory.
struct Shell {
  int code;
  std::string out;
};

Shell sh(const std::string& args) {
  const std::string cmd = std::string(MPM_BINARY) + " " + args + " 2>&1";
  FILE* f = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  while (std::size_t n = fread(buf, 1, sizeof buf, f)) out.append(buf, n);
  const int status = pclose(f);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(Checkpoint, CommandLineRestart) {
  TempDir dir("cli");
  const std::string d = dir.path().string();
  const std::string cfg = example("vibrating_bar_small");
  auto r = sh(fmt::format("run {} -q --out {} --set output.checkpoint_every=10 --set time.end=1e-6",
                          cfg, d));
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string file = (dir.path() / io::kCheckpointFile).string();
  r = sh(fmt::format("run --restart {} -q --set time.end=1.9e-6", file));
  EXPECT_EQ(r.code, 0) << r.out;
  const auto c = io::read_checkpoint(file);  // rewritten at step 10 only: 19 is no multiple
  EXPECT_EQ(c.step, 10);
  EXPECT_TRUE(fs::exists(dir.path() / "summary.json"));
  // CONFIG given: its time.end and outputs may differ, other keys not.
  r = sh(fmt::format("run {} --restart {} -q --out {}/b", cfg, file, d));
  EXPECT_EQ(r.code, 0) << r.out;
  r = sh(fmt::format("run {} --restart {} -q --out {}/c --set grid.cells=10", cfg, file, d));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("grid.cells: checkpoint 20, now 10"), std::string::npos) << r.out;
  // A flipped byte.
  std::string bytes = slurp(file);
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 4);
  spit(dir.path() / "bad.bin", bytes);
  r = sh(fmt::format("run --restart {}/bad.bin -q", d));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("bad.bin' is corrupted"), std::string::npos) << r.out;
  r = sh("run -q");
  EXPECT_EQ(r.code, 2) << r.out;
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
