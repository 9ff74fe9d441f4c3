// Tests for the output writers: CSV/VTU/PVD content and the atomic file writer.
#include "io/output.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace mpm::io {
namespace MPM_UNITY_ID {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  std::istringstream in(s);
  while (std::getline(in, cur, sep)) out.push_back(cur);
  return out;
}

std::size_t count_tokens(const std::string& s) {
  std::istringstream in(s);
  std::size_t n = 0;
  std::string tok;
  while (in >> tok) ++n;
  return n;
}

// A minimal XML reader, enough for the files the writers produce: elements with attributes,
// text content, self-closing tags and the <?xml?> declaration. It fails the test on unbalanced
// or mismatched tags.
struct Element {
  std::string name;
  std::map<std::string, std::string> attrs;
  std::string text;  // text directly inside the element
  std::string parent;
};

std::vector<Element> parse_xml(const std::string& xml) {
  std::vector<Element> all;
  std::vector<std::size_t> stack;  // indices into all
  std::size_t pos = 0;
  while (pos < xml.size()) {
    const std::size_t lt = xml.find('<', pos);
    const std::string text =
        xml.substr(pos, lt == std::string::npos ? std::string::npos : lt - pos);
    if (!stack.empty()) {
      all[stack.back()].text += text;
    } else {
      EXPECT_EQ(count_tokens(text), 0u) << "text outside the root element: " << text;
    }
    if (lt == std::string::npos) break;
    const std::size_t gt = xml.find('>', lt);
    if (gt == std::string::npos) {
      ADD_FAILURE() << "unterminated tag";
      break;
    }
    std::string tag = xml.substr(lt + 1, gt - lt - 1);
    pos = gt + 1;
    if (tag.starts_with("?")) {
      EXPECT_TRUE(tag.ends_with("?"));
      continue;
    }
    if (tag.starts_with("/")) {
      if (stack.empty()) {
        ADD_FAILURE() << "closing tag without an open one: " << tag;
        break;
      }
      EXPECT_EQ(tag.substr(1), all[stack.back()].name) << "mismatched closing tag";
      stack.pop_back();
      continue;
    }
    const bool self_closing = tag.ends_with("/");
    if (self_closing) tag.pop_back();
    Element e;
    std::size_t i = tag.find_first_of(" \n");
    e.name = tag.substr(0, i);
    while (i != std::string::npos && i < tag.size()) {
      const std::size_t eq = tag.find('=', i);
      if (eq == std::string::npos) break;
      const std::string key =
          tag.substr(tag.find_first_not_of(" \n", i), eq - tag.find_first_not_of(" \n", i));
      EXPECT_EQ(tag[eq + 1], '"') << "unquoted attribute " << key;
      const std::size_t end = tag.find('"', eq + 2);
      e.attrs[key] = tag.substr(eq + 2, end - eq - 2);
      i = end + 1;
    }
    e.parent = stack.empty() ? "" : all[stack.back()].name;
    EXPECT_TRUE(!stack.empty() || all.empty()) << "more than one root element";
    all.push_back(e);
    if (!self_closing) stack.push_back(all.size() - 1);
  }
  EXPECT_TRUE(stack.empty()) << "unclosed element "
                             << (stack.empty() ? "" : all[stack.back()].name);
  return all;
}

const Element* find_array(const std::vector<Element>& xml, const std::string& name) {
  for (const auto& e : xml) {
    if (e.name == "DataArray" && e.attrs.count("Name") && e.attrs.at("Name") == name) return &e;
  }
  return nullptr;
}

std::vector<double> numbers(const std::string& text) {
  std::vector<double> out;
  std::istringstream in(text);
  std::string tok;
  while (in >> tok) out.push_back(std::stod(tok));
  return out;
}

// Checks the structure shared by every .vtu and returns the point and cell counts.
std::pair<long, long> check_vtu(const std::vector<Element>& xml) {
  EXPECT_FALSE(xml.empty());
  if (xml.empty()) return {-1, -1};
  EXPECT_EQ(xml[0].name, "VTKFile");
  EXPECT_EQ(xml[0].attrs.at("type"), "UnstructuredGrid");
  EXPECT_EQ(xml[0].attrs.at("version"), "0.1");
  EXPECT_EQ(xml[0].attrs.at("byte_order"), "LittleEndian");
  long points = -1, cells = -1;
  for (const auto& e : xml) {
    if (e.name == "Piece") {
      points = std::stol(e.attrs.at("NumberOfPoints"));
      cells = std::stol(e.attrs.at("NumberOfCells"));
    }
  }
  EXPECT_GE(points, 0);
  for (const auto& e : xml) {
    if (e.name != "DataArray") continue;
    const std::string name = e.attrs.count("Name") ? e.attrs.at("Name") : "";
    EXPECT_EQ(e.attrs.at("format"), "ascii") << name;
    const long comps =
        e.attrs.count("NumberOfComponents") ? std::stol(e.attrs.at("NumberOfComponents")) : 1;
    long expected = -1;
    if (e.parent == "PointData" || e.parent == "Points") expected = points * comps;
    if (e.parent == "FieldData") expected = std::stol(e.attrs.at("NumberOfTuples")) * comps;
    if (e.parent == "Cells" && name != "connectivity") expected = cells;
    if (expected >= 0) {
      EXPECT_EQ(static_cast<long>(count_tokens(e.text)), expected) << "DataArray " << name;
    }
  }
  return {points, cells};
}

Particles<1> make_particles_1d() {
  Particles<1> p;
  p.resize(3);
  for (Index i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(i);
    p.x0[k][0] = 0.1 * static_cast<double>(i) + 1.0 / 3.0;
    p.x[k][0] = p.x0[k][0] + 1e-7 * static_cast<double>(i + 1) / 7.0;
    p.v[k][0] = -2.0 / 3.0 * static_cast<double>(i);
    p.mass[k] = 0.1 / 3.0;
    p.volume[k] = 0.1;
    p.F[k](0, 0) = 1.0 + 1e-9 / 3.0;
    p.stress[k](0, 0) = -1234.5678901234567 * static_cast<double>(i);
  }
  return p;
}

Particles<2> make_particles_2d() {
  Particles<2> p;
  p.resize(4);
  for (std::size_t k = 0; k < 4; ++k) {
    const double s = static_cast<double>(k);
    p.x0[k] = Vec<2>(0.25 * s + 0.1, 1.0 / (s + 3.0));
    p.x[k] = p.x0[k] + Vec<2>(1e-3 / 3.0, -2e-4 * s);
    p.v[k] = Vec<2>(0.5 * s, -1.0 / 7.0);
    p.mass[k] = 2.0 / 3.0;
    p.volume[k] = 0.0625;
    p.F[k] << 1.01, 0.02 * s, -0.03, 0.99;
    p.stress[k] << 1e5 * s, 3.3e3, 3.3e3, -2e4 / 3.0;
  }
  return p;
}

// ---- CSV ---------------------------------------------------------------------------------

TEST(OutputCsv, Header1D) {
  const auto p = make_particles_1d();
  const std::string csv = particles_csv(p);
  const auto lines = split(csv, '\n');
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0], "id,x0_1,x_1,u_1,v_1,mass,volume,density,F_11,stress_11");
  EXPECT_TRUE(csv.ends_with("\n"));
}

TEST(OutputCsv, Header2DWithExtra) {
  const auto p = make_particles_2d();
  const std::vector<double> exact{1, 2, 3, 4}, err{0.5, 0.25, 0.125, 0.0625};
  const std::string csv = particles_csv(p, {{"u_exact", &exact}, {"error", &err}});
  const auto lines = split(csv, '\n');
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0],
            "id,x0_1,x0_2,x_1,x_2,u_1,u_2,v_1,v_2,mass,volume,density,F_11,F_12,F_21,F_22,"
            "stress_11,stress_12,stress_21,stress_22,u_exact,error");
  for (std::size_t r = 1; r < lines.size(); ++r) {
    EXPECT_EQ(split(lines[r], ',').size(), 22u) << lines[r];
  }
}

TEST(OutputCsv, ValuesRoundTripExactly2D) {
  const auto p = make_particles_2d();
  const std::vector<double> extra{1.0 / 3.0, -2.0 / 7.0, 1e-300, 6.02214076e23};
  const auto lines = split(particles_csv(p, {{"extra", &extra}}), '\n');
  ASSERT_EQ(lines.size(), 5u);
  for (std::size_t k = 0; k < 4; ++k) {
    const auto f = split(lines[k + 1], ',');
    ASSERT_EQ(f.size(), 21u);
    std::size_t c = 0;
    EXPECT_EQ(std::stol(f[c++]), static_cast<long>(k));
    // u and density are derived (Particles::displacement, density): x - x0 and m / V.
    for (const Vec<2>& vec : {p.x0[k], p.x[k], p.displacement(k), p.v[k]}) {
      for (int d = 0; d < 2; ++d) EXPECT_EQ(std::stod(f[c++]), vec[d]);
    }
    EXPECT_EQ(std::stod(f[c++]), p.mass[k]);
    EXPECT_EQ(std::stod(f[c++]), p.volume[k]);
    EXPECT_EQ(std::stod(f[c++]), p.density(k));
    for (const auto* mat : {&p.F, &p.stress}) {
      for (int r = 0; r < 2; ++r) {
        for (int s = 0; s < 2; ++s) EXPECT_EQ(std::stod(f[c++]), (*mat)[k](r, s));
      }
    }
    EXPECT_EQ(std::stod(f[c++]), extra[k]);
    EXPECT_EQ(c, f.size());
  }
}

TEST(OutputCsv, ValuesRoundTripExactly1D) {
  const auto p = make_particles_1d();
  const auto lines = split(particles_csv(p), '\n');
  for (std::size_t k = 0; k < 3; ++k) {
    const auto f = split(lines[k + 1], ',');
    ASSERT_EQ(f.size(), 10u);
    EXPECT_EQ(std::stod(f[1]), p.x0[k][0]);
    EXPECT_EQ(std::stod(f[2]), p.x[k][0]);
    EXPECT_EQ(std::stod(f[3]), p.displacement(k)[0]);
    EXPECT_EQ(std::stod(f[4]), p.v[k][0]);
    EXPECT_EQ(std::stod(f[7]), p.density(k));
    EXPECT_EQ(std::stod(f[8]), p.F[k](0, 0));
    EXPECT_EQ(std::stod(f[9]), p.stress[k](0, 0));
  }
}

TEST(OutputCsv, EmptyParticleSetGivesHeaderOnly) {
  Particles<1> p;
  const auto lines = split(particles_csv(p), '\n');
  EXPECT_EQ(lines.size(), 1u);
}

TEST(OutputCsv, RejectsBadExtraFields) {
  const auto p = make_particles_1d();
  const std::vector<double> short_field{1.0, 2.0};
  const std::vector<double> ok{1.0, 2.0, 3.0};
  EXPECT_THROW(particles_csv(p, {{"e", &short_field}}), std::invalid_argument);
  EXPECT_THROW(particles_csv(p, {{"e", nullptr}}), std::invalid_argument);
  EXPECT_THROW(particles_csv(p, {{"mass", &ok}}), std::invalid_argument);
  EXPECT_THROW(particles_csv(p, {{"e", &ok}, {"e", &ok}}), std::invalid_argument);
  EXPECT_THROW(particles_vtu(p, 0.0, {{"e", &short_field}}), std::invalid_argument);
}

// ---- particle VTU --------------------------------------------------------------------------

TEST(OutputVtu, Particles1DStructure) {
  const auto p = make_particles_1d();
  const std::vector<double> err{0.1, 0.2, 0.3};
  const auto xml = parse_xml(particles_vtu(p, 0.125, {{"error", &err}}));
  const auto [points, cells] = check_vtu(xml);
  EXPECT_EQ(points, 3);
  EXPECT_EQ(cells, 3);
  for (const char* name : {"id", "x0", "u", "v", "mass", "volume", "density", "F", "stress",
                           "error", "TimeValue", "Points", "connectivity", "offsets", "types"}) {
    EXPECT_NE(find_array(xml, name), nullptr) << name;
  }
  EXPECT_EQ(find_array(xml, "id")->attrs.at("type"), "Int64");
  EXPECT_EQ(find_array(xml, "F")->attrs.at("NumberOfComponents"), "9");
  EXPECT_EQ(find_array(xml, "stress")->attrs.at("NumberOfComponents"), "9");
  EXPECT_EQ(find_array(xml, "v")->attrs.at("NumberOfComponents"), "3");
  EXPECT_EQ(numbers(find_array(xml, "TimeValue")->text), std::vector<double>{0.125});
  EXPECT_EQ(numbers(find_array(xml, "types")->text), std::vector<double>(3, 1.0));  // VTK_VERTEX
  EXPECT_EQ(numbers(find_array(xml, "offsets")->text), (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(numbers(find_array(xml, "connectivity")->text), (std::vector<double>{0, 1, 2}));
  EXPECT_EQ(numbers(find_array(xml, "error")->text), err);
}

TEST(OutputVtu, Particles1DPadding) {
  const auto p = make_particles_1d();
  const auto xml = parse_xml(particles_vtu(p, 0.0));
  const auto pts = numbers(find_array(xml, "Points")->text);
  const auto F = numbers(find_array(xml, "F")->text);
  const auto S = numbers(find_array(xml, "stress")->text);
  ASSERT_EQ(pts.size(), 9u);
  ASSERT_EQ(F.size(), 27u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(pts[3 * k], p.x[k][0]);
    EXPECT_EQ(pts[3 * k + 1], 0.0);
    EXPECT_EQ(pts[3 * k + 2], 0.0);
    const std::vector<double> f(F.begin() + 9 * k, F.begin() + 9 * k + 9);
    EXPECT_EQ(f, (std::vector<double>{p.F[k](0, 0), 0, 0, 0, 1, 0, 0, 0, 1}));
    const std::vector<double> s(S.begin() + 9 * k, S.begin() + 9 * k + 9);
    EXPECT_EQ(s, (std::vector<double>{p.stress[k](0, 0), 0, 0, 0, 0, 0, 0, 0, 0}));
  }
}

TEST(OutputVtu, Particles2DTensorLayout) {
  const auto p = make_particles_2d();
  const auto xml = parse_xml(particles_vtu(p, 1.5));
  const auto [points, cells] = check_vtu(xml);
  EXPECT_EQ(points, 4);
  EXPECT_EQ(cells, 4);
  const auto F = numbers(find_array(xml, "F")->text);
  const auto x0 = numbers(find_array(xml, "x0")->text);
  ASSERT_EQ(F.size(), 36u);
  for (std::size_t k = 0; k < 4; ++k) {
    const auto& m = p.F[k];
    const std::vector<double> f(F.begin() + 9 * k, F.begin() + 9 * k + 9);
    EXPECT_EQ(f, (std::vector<double>{m(0, 0), m(0, 1), 0, m(1, 0), m(1, 1), 0, 0, 0, 1}));
    EXPECT_EQ(x0[3 * k], p.x0[k][0]);
    EXPECT_EQ(x0[3 * k + 1], p.x0[k][1]);
    EXPECT_EQ(x0[3 * k + 2], 0.0);
  }
}

TEST(OutputVtu, EmptyParticleSet) {
  Particles<2> p;
  const auto [points, cells] = check_vtu(parse_xml(particles_vtu(p, 0.0)));
  EXPECT_EQ(points, 0);
  EXPECT_EQ(cells, 0);
}

TEST(OutputVtu, Particles3D) {
  Particles<3> p;
  p.resize(2);
  p.x[1] = Vec<3>(1, 2, 3);
  const auto xml = parse_xml(particles_vtu(p, 0.0));
  const auto [points, cells] = check_vtu(xml);
  EXPECT_EQ(points, 2);
  EXPECT_EQ(cells, 2);
  EXPECT_EQ(numbers(find_array(xml, "Points")->text), (std::vector<double>{0, 0, 0, 1, 2, 3}));
}

// Binary (appended raw) VTU: an independent reader, meshio (python3-meshio, installed by
// scripts/deps.sh), gives back the points and every array of the ASCII file bit for bit, for
// the particles (2D, with an extra field) and the grid.
TEST(OutputVtu, BinaryFramesReadBackByMeshio) {
  const auto dir = fs::temp_directory_path() / ("mpm_vtu_binary_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto p = make_particles_2d();
  const std::vector<double> err{0.5, -1.0 / 3.0, 1e-300, 7.0};
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary) << text;
  };
  write("p_ascii.vtu", particles_vtu(p, 0.25, {{"error", &err}}, false));
  write("p_binary.vtu", particles_vtu(p, 0.25, {{"error", &err}}, true));
  const Grid<2> g(Vec<2>(0.0, -1.0), Vec<2>(2.0, 1.0), IVec<2>{3, 2});
  write("g_ascii.vtu", grid_vtu(g, {}, false));
  write("g_binary.vtu", grid_vtu(g, {}, true));
  // With values that need their 17 digits, binary takes about two thirds of the room (the
  // padding zeros of vectors and tensors take 8 bytes in binary, 1 character in ASCII).
  {
    Particles<2> q;
    q.resize(2000);
    for (std::size_t k = 0; k < 2000; ++k) {
      const double t = 1.0 / (static_cast<double>(k) + 3.0);
      q.x0[k] = Vec<2>(t, 1.0 - t);
      q.v[k] = Vec<2>(t / 7.0, -t / 9.0);
      q.x[k] = q.x0[k] + q.v[k];  // u = v: full-length numbers, as the stored u was
      q.mass[k] = t / 11.0;
      q.volume[k] = t / 13.0;  // density 13/11
      q.F[k] << 1.0 + t / 13.0, t / 17.0, -t / 19.0, 1.0 - t / 23.0;
      q.stress[k] = q.F[k] * 1e5 / 3.0;
    }
    const auto ascii = particles_vtu(q, 0.0, {}, false).size();
    const auto binary = particles_vtu(q, 0.0, {}, true).size();
    EXPECT_LT(static_cast<double>(binary), 0.7 * static_cast<double>(ascii))
        << binary << " against " << ascii << " bytes";
  }
  const std::string script = dir.string() + "/check.py";
  std::ofstream(script) << R"py(
import sys, numpy as np, meshio
d = sys.argv[1]
for stem in ("p", "g"):
    a = meshio.read(f"{d}/{stem}_ascii.vtu")
    b = meshio.read(f"{d}/{stem}_binary.vtu")
    assert a.points.shape == b.points.shape and np.array_equal(a.points, b.points), stem
    assert set(a.point_data) == set(b.point_data), (stem, a.point_data.keys(), b.point_data.keys())
    for k in a.point_data:
        assert np.array_equal(a.point_data[k], b.point_data[k]), (stem, k)
    ca = [(c.type, c.data.tolist()) for c in a.cells]
    cb = [(c.type, c.data.tolist()) for c in b.cells]
    assert ca == cb, stem
    print(stem, len(b.points), sorted(b.point_data))
)py";
  const std::string cmd = "/usr/bin/python3 " + script + " " + dir.string() + " 2>&1";
  FILE* f = popen(cmd.c_str(), "r");
  ASSERT_NE(f, nullptr);
  std::string out;
  std::array<char, 4096> buf{};
  while (std::size_t n = fread(buf.data(), 1, buf.size(), f)) out.append(buf.data(), n);
  const int status = pclose(f);
  EXPECT_EQ(status, 0) << out;
  EXPECT_NE(out.find("p 4 ['F', 'density', 'error', 'id', 'mass', 'stress', 'u', 'v', 'volume', "
                     "'x0']"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("g 12"), std::string::npos) << out;
  fs::remove_all(dir);
}

// VTK's XML reader refuses a connectivity array of several components and then reads no points
// (what ParaView showed for every grid.vtu): one component, whatever the cell. Vectors and
// tensors name their components, which ParaView shows ("stress_XY").
TEST(OutputVtu, OneComponentConnectivityAndNamedComponents) {
  const auto p = make_particles_2d();
  const Grid<2> g(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), IVec<2>{2, 2});
  for (const bool binary : {false, true}) {
    const auto grid = parse_xml(grid_vtu(g, {}, binary));
    EXPECT_EQ(find_array(grid, "connectivity")->attrs.count("NumberOfComponents"), 0u);
    const auto xml = parse_xml(particles_vtu(p, 0.0, {}, binary));
    EXPECT_EQ(find_array(xml, "connectivity")->attrs.count("NumberOfComponents"), 0u);
    const auto& s = find_array(xml, "stress")->attrs;
    const char* tensor[] = {"XX", "XY", "XZ", "YX", "YY", "YZ", "ZX", "ZY", "ZZ"};
    for (int k = 0; k < 9; ++k) EXPECT_EQ(s.at("ComponentName" + std::to_string(k)), tensor[k]);
    const auto& v = find_array(xml, "v")->attrs;
    EXPECT_EQ(v.at("ComponentName0"), "X");
    EXPECT_EQ(v.at("ComponentName2"), "Z");
  }
}

// 2D: the stress normal to the plane (plane strain) in the tensor's zz place, and extra vector
// fields (the exact displacement) as 3-component arrays like u.
TEST(OutputVtu, PlaneStrainZzAndExtraVectors) {
  const auto p = make_particles_2d();
  const std::vector<double> zz{1.5, -2.5, 3.5, 4.5};
  std::vector<Vec<2>> u_exact(4);
  for (std::size_t k = 0; k < 4; ++k) u_exact[k] = Vec<2>(0.25 * k, -1.0 * k);
  const auto xml = parse_xml(particles_vtu(p, 0.0, {}, false, {{"u_exact", &u_exact}}, &zz));
  const auto S = numbers(find_array(xml, "stress")->text);
  const auto U = numbers(find_array(xml, "u_exact")->text);
  EXPECT_EQ(find_array(xml, "u_exact")->attrs.at("NumberOfComponents"), "3");
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(S[9 * k + 8], zz[k]);
    EXPECT_EQ(S[9 * k + 0], p.stress[k](0, 0));
    EXPECT_EQ(S[9 * k + 2], 0.0);
    EXPECT_EQ(U[3 * k], u_exact[k][0]);
    EXPECT_EQ(U[3 * k + 1], u_exact[k][1]);
    EXPECT_EQ(U[3 * k + 2], 0.0);
  }
  EXPECT_THROW(particles_vtu(p, 0.0, {}, false, {{"u", &u_exact}}), std::invalid_argument);
}

TEST(OutputVtu, FieldNamesAreXmlEscaped) {
  const auto p = make_particles_1d();
  const std::vector<double> e{1, 2, 3};
  const std::string vtu = particles_vtu(p, 0.0, {{"a<b & \"c\"", &e}});
  EXPECT_NE(vtu.find("Name=\"a&lt;b &amp; &quot;c&quot;\""), std::string::npos);
  check_vtu(parse_xml(vtu));
}

// ---- grid VTU ------------------------------------------------------------------------------

TEST(OutputGridVtu, Grid1D) {
  const Grid<1> g(Vec<1>(0.0), Vec<1>(1.0), {4});
  const std::vector<double> nodal{0, 1, 2, 3, 4};
  const auto xml = parse_xml(grid_vtu(g, {{"mass", &nodal}}));
  const auto [points, cells] = check_vtu(xml);
  EXPECT_EQ(points, 5);
  EXPECT_EQ(cells, 4);
  EXPECT_EQ(numbers(find_array(xml, "types")->text), std::vector<double>(4, 3.0));  // VTK_LINE
  EXPECT_EQ(numbers(find_array(xml, "connectivity")->text),
            (std::vector<double>{0, 1, 1, 2, 2, 3, 3, 4}));
  EXPECT_EQ(numbers(find_array(xml, "offsets")->text), (std::vector<double>{2, 4, 6, 8}));
  const auto pts = numbers(find_array(xml, "Points")->text);
  ASSERT_EQ(pts.size(), 15u);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_DOUBLE_EQ(pts[3 * i], 0.25 * static_cast<double>(i));
  EXPECT_EQ(numbers(find_array(xml, "mass")->text), nodal);
}

TEST(OutputGridVtu, Grid2D) {
  const Grid<2> g(Vec<2>(0.0, -1.0), Vec<2>(3.0, 1.0), {3, 2});
  const auto xml = parse_xml(grid_vtu(g));
  const auto [points, cells] = check_vtu(xml);
  EXPECT_EQ(points, 12);
  EXPECT_EQ(cells, 6);
  EXPECT_EQ(numbers(find_array(xml, "types")->text), std::vector<double>(6, 9.0));  // VTK_QUAD
  const auto conn = numbers(find_array(xml, "connectivity")->text);
  ASSERT_EQ(conn.size(), 24u);
  // First cell: corners (0,0),(1,0),(1,1),(0,1) counter-clockwise; 4 nodes per row.
  EXPECT_EQ(std::vector<double>(conn.begin(), conn.begin() + 4), (std::vector<double>{0, 1, 5, 4}));
  // Cell (i=0, j=1), the fourth cell (x fastest).
  EXPECT_EQ(std::vector<double>(conn.begin() + 12, conn.begin() + 16),
            (std::vector<double>{4, 5, 9, 8}));
  const auto pts = numbers(find_array(xml, "Points")->text);
  ASSERT_EQ(pts.size(), 36u);
  EXPECT_EQ(pts[3 * 5], 1.0);  // node (1,1)
  EXPECT_EQ(pts[3 * 5 + 1], 0.0);
  EXPECT_EQ(pts[3 * 11], 3.0);  // node (3,2), the upper corner
  EXPECT_EQ(pts[3 * 11 + 1], 1.0);
}

TEST(OutputGridVtu, Grid3D) {
  const Grid<3> g(Vec<3>(0, 0, 0), Vec<3>(1, 1, 1), {2, 2, 2});
  const auto xml = parse_xml(grid_vtu(g));
  const auto [points, cells] = check_vtu(xml);
  EXPECT_EQ(points, 27);
  EXPECT_EQ(cells, 8);
  const auto conn = numbers(find_array(xml, "connectivity")->text);
  ASSERT_EQ(conn.size(), 64u);
  EXPECT_EQ(std::vector<double>(conn.begin(), conn.begin() + 8),
            (std::vector<double>{0, 1, 4, 3, 9, 10, 13, 12}));
  EXPECT_EQ(numbers(find_array(xml, "types")->text), std::vector<double>(8, 12.0));
}

TEST(OutputGridVtu, RejectsWrongNodeFieldSize) {
  const Grid<1> g(Vec<1>(0.0), Vec<1>(1.0), {4});
  const std::vector<double> per_cell{0, 1, 2, 3};
  EXPECT_THROW(grid_vtu(g, {{"m", &per_cell}}), std::invalid_argument);
}

// ---- PVD -----------------------------------------------------------------------------------

TEST(OutputPvd, ListsFramesWithTimes) {
  PvdSeries s;
  EXPECT_EQ(s.size(), 0u);
  s.add(0.0, "particles_000000.vtu");
  s.add(0.1, "particles_000001.vtu");
  s.add(1.0 / 3.0, "frames/particles_000002.vtu");
  EXPECT_EQ(s.size(), 3u);
  const auto xml = parse_xml(s.str());
  ASSERT_FALSE(xml.empty());
  EXPECT_EQ(xml[0].name, "VTKFile");
  EXPECT_EQ(xml[0].attrs.at("type"), "Collection");
  std::vector<std::pair<double, std::string>> got;
  for (const auto& e : xml) {
    if (e.name == "DataSet") {
      EXPECT_EQ(e.parent, "Collection");
      got.emplace_back(std::stod(e.attrs.at("timestep")), e.attrs.at("file"));
    }
  }
  const std::vector<std::pair<double, std::string>> want{
      {0.0, "particles_000000.vtu"},
      {0.1, "particles_000001.vtu"},
      {1.0 / 3.0, "frames/particles_000002.vtu"}};
  EXPECT_EQ(got, want);
}

TEST(OutputPvd, EmptySeriesIsValid) {
  const auto xml = parse_xml(PvdSeries{}.str());
  ASSERT_EQ(xml.size(), 2u);
  EXPECT_EQ(xml[1].name, "Collection");
}

// ---- write_file_atomic ---------------------------------------------------------------------

class AtomicWrite : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("mpm_io_test_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static std::string read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  std::vector<std::string> entries() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir_)) out.push_back(e.path().filename().string());
    return out;
  }

  fs::path dir_;
};

// Temporaries of a process that no longer runs go (issue 16, 5: a killed run left them and the
// next run into the directory kept them); those of live processes, other names and
// subdirectories stay.
TEST_F(AtomicWrite, StaleTemporariesOfDeadProcessesAreRemoved) {
  pid_t dead = 4000000;
  while (dead > 2 && (::kill(dead, 0) == 0 || errno != ESRCH)) --dead;
  const std::string own = std::to_string(::getpid()), gone = std::to_string(dead);
  for (const std::string& name :
       {"summary.json.tmp." + gone, "history.csv.tmp." + gone, "config.toml.tmp." + own,
        std::string("config.toml.tmp.1"), std::string("frame.tmp.12x"), std::string("notes.tmp."),
        std::string("particles_00001.csv")})
    std::ofstream(dir_ / name) << "x";
  fs::create_directories(dir_ / "sub");
  std::ofstream(dir_ / "sub" / ("a.tmp." + gone)) << "x";
  EXPECT_EQ(remove_stale_temporaries(dir_), 2);
  auto left = entries();
  std::sort(left.begin(), left.end());
  // pid 1 (init) is alive or not ours to probe (EPERM): kept either way.
  std::vector<std::string> kept{"config.toml.tmp." + own, "config.toml.tmp.1",
                                "frame.tmp.12x",          "notes.tmp.",
                                "particles_00001.csv",    "sub"};
  std::sort(kept.begin(), kept.end());
  EXPECT_EQ(left, kept);
  EXPECT_TRUE(fs::exists(dir_ / "sub" / ("a.tmp." + gone)));
  EXPECT_EQ(remove_stale_temporaries(dir_ / "missing"), 0);
}

// One run at a time per output directory (issue 16, 4): a second lock, here from the same
// process through another open file, is refused naming the holder's pid; released when the
// first goes. The lock file stays and is not a run's file.
TEST_F(AtomicWrite, DirectoryLockIsExclusiveAndNamesTheHolder) {
  {
    const DirectoryLock first(dir_);
    try {
      const DirectoryLock second(dir_);
      ADD_FAILURE() << "locked twice";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("is in use by another run (pid " +
                                           std::to_string(::getpid()) + ")"),
                std::string::npos)
          << e.what();
    }
  }
  EXPECT_NO_THROW(DirectoryLock{dir_});
  EXPECT_TRUE(fs::exists(dir_ / ".mpm.lock"));
  EXPECT_TRUE(run_files(dir_).empty());
  for (const char* name :
       {"config.toml", "particles_00012.vtu", "particles_00012.csv", "particles_0001.csv",
        "particles_00012.txt", "summary.json.tmp.5", "notes.txt", "checkpoint.bin",
        "checkpoint_s120_p0003.bin", "checkpoint_s120_p03.bin", "checkpoint_sx_p0001.bin",
        "checkpoint_s7_p12345.bin"})
    std::ofstream(dir_ / name) << "x";
  EXPECT_EQ(run_files(dir_),
            (std::vector<std::string>{"checkpoint.bin", "checkpoint_s120_p0003.bin",
                                      "checkpoint_s7_p12345.bin", "config.toml",
                                      "particles_00012.csv", "particles_00012.vtu"}));
  // A distributed checkpoint's pieces (io/checkpoint.hpp): the name of each, and the removal of
  // those a new manifest does not name (nothing else in the directory).
  EXPECT_EQ(checkpoint_piece_name(120, 3), "checkpoint_s120_p0003.bin");
  EXPECT_EQ(checkpoint_piece_name(0, 12345), "checkpoint_s0_p12345.bin");
  for (const char* name : {"checkpoint_s_p0001.bin", "checkpoint_s1_p001.bin",
                           "checkpoint_s1_p0001.bin.tmp.5", "checkpoint_s1-p0001.bin"})
    EXPECT_FALSE(is_checkpoint_piece_name(name)) << name;
  EXPECT_EQ(remove_checkpoint_pieces(dir_, {"checkpoint_s7_p12345.bin"}), 1);
  EXPECT_EQ(run_files(dir_),
            (std::vector<std::string>{"checkpoint.bin", "checkpoint_s7_p12345.bin", "config.toml",
                                      "particles_00012.csv", "particles_00012.vtu"}));
  EXPECT_TRUE(fs::exists(dir_ / "checkpoint_s120_p03.bin"));  // not a piece's name
}

TEST_F(AtomicWrite, CreatesFileWithExactContent) {
  const fs::path p = dir_ / "frame.csv";
  const std::string content = std::string("a,b\n1,2\n") + std::string(1, '\0') + "tail";
  write_file_atomic(p, content);
  EXPECT_EQ(read(p), content);
  EXPECT_EQ(entries(), std::vector<std::string>{"frame.csv"});  // no *.tmp.* left behind
}

TEST_F(AtomicWrite, OverwritesExistingFile) {
  const fs::path p = dir_ / "out.vtu";
  write_file_atomic(p, std::string(100000, 'x'));
  write_file_atomic(p, "short");
  EXPECT_EQ(read(p), "short");
  EXPECT_EQ(entries(), std::vector<std::string>{"out.vtu"});
}

TEST_F(AtomicWrite, EmptyContent) {
  const fs::path p = dir_ / "empty.txt";
  write_file_atomic(p, "");
  EXPECT_TRUE(fs::exists(p));
  EXPECT_EQ(fs::file_size(p), 0u);
}

TEST_F(AtomicWrite, MissingDirectoryThrowsWithPath) {
  const fs::path p = dir_ / "no_such_dir" / "frame.csv";
  try {
    write_file_atomic(p, "data");
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("No such file or directory"), std::string::npos) << msg;
  }
  EXPECT_FALSE(fs::exists(dir_ / "no_such_dir"));  // creates no directories
}

// An output never replaces what is not a regular file: a device is written through (as root
// the rename turned /dev/null into a regular file), a FIFO refused at once (not waited on), a
// symbolic link kept with its target written.
TEST_F(AtomicWrite, WhatIsNotARegularFileIsNeverReplaced) {
  write_file_atomic("/dev/null", "discarded");
  struct stat st {};
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  const fs::path fifo = dir_ / "frame.vtu";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  try {
    write_file_atomic(fifo, "data");
    ADD_FAILURE() << "a FIFO was written";
  } catch (const RunError& e) {
    EXPECT_EQ(e.exit_code(), exit_code::kOutput);
    EXPECT_NE(std::string(e.what()).find("it is a FIFO (named pipe), not a regular file"),
              std::string::npos)
        << e.what();
  }
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  // A link to a regular file: the link stays, the target gets the content.
  std::ofstream(dir_ / "target.txt") << "old";
  fs::create_symlink("target.txt", dir_ / "link.txt");
  write_file_atomic(dir_ / "link.txt", "new");
  EXPECT_TRUE(fs::is_symlink(dir_ / "link.txt"));
  EXPECT_EQ(read(dir_ / "target.txt"), "new");
  // A link to nothing is refused.
  fs::create_symlink("nowhere.txt", dir_ / "dangling.txt");
  EXPECT_THROW(write_file_atomic(dir_ / "dangling.txt", "x"), RunError);
  EXPECT_TRUE(fs::is_symlink(dir_ / "dangling.txt"));
}

TEST_F(AtomicWrite, RenameOntoDirectoryThrowsAndCleansUp) {
  // The target is an existing non-empty directory: the temporary file is written, the rename
  // fails, and the temporary must be removed again.
  const fs::path p = dir_ / "taken";
  fs::create_directories(p / "child");
  EXPECT_THROW(write_file_atomic(p, "data"), std::runtime_error);
  EXPECT_EQ(entries(), std::vector<std::string>{"taken"});
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm::io
