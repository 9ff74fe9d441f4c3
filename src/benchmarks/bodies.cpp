#include "benchmarks/bodies.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include "core/input_file.hpp"
#include "core/strings.hpp"
#include "setup/config.hpp"
#include "setup/gmsh_mesh.hpp"

namespace mpm {

namespace {

// The red refinements of tetrahedron_seed_reference: 1, 8, 64, ... children.
using Tet = std::array<Vec<3>, 4>;
void red_refine(const Tet& t, int levels, std::vector<Tet>& out) {
  if (levels == 0) {
    out.push_back(t);
    return;
  }
  auto mid = [&](std::size_t i, std::size_t j) -> Vec<3> { return 0.5 * (t[i] + t[j]); };
  const Vec<3> x01 = mid(0, 1), x02 = mid(0, 2), x03 = mid(0, 3), x12 = mid(1, 2), x13 = mid(1, 3),
               x23 = mid(2, 3);
  // Bey (1995), Computing 55: four corner tetrahedra and the octahedron cut along x02-x13.
  for (const Tet& c : {Tet{t[0], x01, x02, x03}, Tet{x01, t[1], x12, x13}, Tet{x02, x12, t[2], x23},
                       Tet{x03, x13, x23, t[3]}, Tet{x01, x02, x03, x13}, Tet{x01, x02, x12, x13},
                       Tet{x02, x03, x13, x23}, Tet{x02, x12, x13, x23}})
    red_refine(c, levels - 1, out);
}

// (m, r) with count = m 8^r, m = 1 or 4; (0, 0) for another count.
std::pair<int, int> tetrahedron_pattern(int count) {
  for (int m : {1, 4}) {
    if (count <= 0 || count % m != 0) continue;
    int rest = count / m, r = 0;
    while (rest % 8 == 0) rest /= 8, ++r;
    if (rest == 1) return {m, r};
  }
  return {0, 0};
}

// A field of a particle file: a finite number, the whole field.
double parse_number(std::string_view field, const std::string& where, const std::string& column) {
  field = trim(field);
  double v = 0.0;
  const char* end = field.data() + field.size();
  // (from_chars takes no leading '+', which a CSV writer may put.)
  const char* begin = !field.empty() && field.front() == '+' ? field.data() + 1 : field.data();
  const auto r = std::from_chars(begin, end, v);
  if (field.empty() || r.ec != std::errc() || r.ptr != end || !std::isfinite(v))
    throw InputError(fmt::format("{}, column \"{}\": \"{}\" is not a finite number", where, column,
                                 std::string(field.substr(0, 40))));
  return v;
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t b = 0;
  while (true) {
    const std::size_t e = line.find(',', b);
    out.push_back(line.substr(b, e == std::string_view::npos ? std::string_view::npos : e - b));
    if (e == std::string_view::npos) return out;
    b = e + 1;
  }
}

std::string trimmed(std::string_view s) {
  const auto a = s.find_first_not_of(" \t\"");
  if (a == std::string_view::npos) return {};
  const auto b = s.find_last_not_of(" \t\"");
  return std::string(s.substr(a, b - a + 1));
}

}  // namespace

std::vector<Vec<3>> tetrahedron_seed_reference(int per_tetrahedron) {
  const auto [m, r] = tetrahedron_pattern(per_tetrahedron);
  if (m == 0)
    throw InputError(
        fmt::format("{} particles per tetrahedron is not of the form m 8^r with m = 1 or 4 ({})",
                    per_tetrahedron, tetrahedron_seed_counts()));
  std::vector<Tet> children;
  red_refine(Tet{Vec<3>::Zero(), Vec<3>::UnitX(), Vec<3>::UnitY(), Vec<3>::UnitZ()}, r, children);
  const double a = (5.0 + 3.0 * std::sqrt(5.0)) / 20.0, b = (5.0 - std::sqrt(5.0)) / 20.0;
  std::vector<Vec<3>> ref;
  for (const Tet& t : children) {
    if (m == 1) {
      ref.push_back(0.25 * (t[0] + t[1] + t[2] + t[3]));
      continue;
    }
    for (std::size_t k = 0; k < 4; ++k) {
      Vec<3> p = Vec<3>::Zero();
      for (std::size_t v = 0; v < 4; ++v) p += (v == k ? a : b) * t[v];
      ref.push_back(p);
    }
  }
  return ref;
}

std::string tetrahedron_seed_counts() {
  return "1, 4, 8, 32, 64, 256, 512, ...";
}

// A particle file's rows into x_, vol_, line_ and the initial fields, volume_ summed; InputError
// naming source_ and the line for a malformed one. Whether the file had a header.
template <int Dim>
bool FileBody<Dim>::read_rows(std::string_view text) {
  // The columns: name -> what it holds (kind, component(s)).
  enum Kind { kPosition, kVolume, kVelocity, kStress, kStressZz };
  struct Column {
    Kind kind;
    int i = 0, j = 0;
  };
  std::map<std::string, Column, std::less<>> known;
  for (int d = 0; d < Dim; ++d) {
    known[fmt::format("x_{}", d + 1)] = {kPosition, d};
    known[std::string(1, "xyz"[d])] = {kPosition, d};
    known[fmt::format("v_{}", d + 1)] = {kVelocity, d};
    known[fmt::format("v{}", "xyz"[d])] = {kVelocity, d};
    for (int e = 0; e < Dim; ++e) known[fmt::format("stress_{}{}", d + 1, e + 1)] = {kStress, d, e};
  }
  known["volume"] = {kVolume};
  if constexpr (Dim == 2) known["stress_zz"] = {kStressZz};
  const std::string valid =
      Dim == 2 ? "x_1, x_2 (or x, y), volume; optional: v_1, v_2 (or vx, vy), stress_11, "
                 "stress_12, stress_21, stress_22 (the upper triangle, or all four), stress_zz"
               : "x_1, x_2, x_3 (or x, y, z), volume; optional: v_1, v_2, v_3 (or vx, vy, vz), "
                 "stress_ij for i, j = 1..3 (the upper triangle, or all nine)";
  std::vector<Column> columns;
  std::vector<std::string> names;
  bool has_velocity = false, has_stress = false, has_zz = false;
  std::array<int, Dim> position_given{}, velocity_given{};
  std::array<std::array<int, Dim>, Dim> stress_given{};
  int volume_given = 0;
  std::size_t at = 0;
  Index line_no = 0;
  bool header = true;
  while (at < text.size()) {
    const std::size_t eol = std::min(text.find('\n', at), text.size());
    std::string_view line = text.substr(at, eol - at);
    at = eol + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.find_first_not_of(" \t") == std::string_view::npos || line.front() == '#') continue;
    const std::string where = fmt::format("{}, line {}", source_, line_no);
    const auto fields = split(line);
    if (header) {
      header = false;
      for (const auto& f : fields) {
        const std::string name = trimmed(f);
        const auto it = known.find(name);
        if (it == known.end())
          throw InputError(fmt::format(
              "{}: column \"{}\" is not one mpm reads; the columns of a {}D particle file: {}",
              where, name, Dim, valid));
        if (std::find(names.begin(), names.end(), name) != names.end())
          throw InputError(fmt::format("{}: column \"{}\" is given twice", where, name));
        const Column c = it->second;
        const auto I = static_cast<std::size_t>(c.i), J = static_cast<std::size_t>(c.j);
        int* given = nullptr;  // (stress_zz has no other spelling)
        switch (c.kind) {
          case kPosition:
            given = &position_given[I];
            break;
          case kVelocity:
            given = &velocity_given[I];
            break;
          case kStress:
            given = &stress_given[I][J];
            break;
          case kVolume:
            given = &volume_given;
            break;
          case kStressZz:
            has_zz = true;
            break;
        }
        if (given != nullptr && *given != 0)
          throw InputError(
              fmt::format("{}: column \"{}\" gives what another column gives", where, name));
        if (given != nullptr) *given = 1;
        has_velocity = has_velocity || c.kind == kVelocity;
        has_stress = has_stress || c.kind == kStress;
        names.push_back(name);
        columns.push_back(c);
      }
      std::string missing;
      for (int d = 0; d < Dim; ++d) {
        if (!position_given[static_cast<std::size_t>(d)])
          missing += fmt::format("{}x_{}", missing.empty() ? "" : ", ", d + 1);
        if (has_velocity && !velocity_given[static_cast<std::size_t>(d)])
          missing += fmt::format("{}v_{}", missing.empty() ? "" : ", ", d + 1);
        for (int e = d; e < Dim; ++e)
          if (has_stress &&
              !stress_given[static_cast<std::size_t>(d)][static_cast<std::size_t>(e)] &&
              !stress_given[static_cast<std::size_t>(e)][static_cast<std::size_t>(d)])
            missing += fmt::format("{}stress_{}{}", missing.empty() ? "" : ", ", d + 1, e + 1);
      }
      if (!volume_given) missing += missing.empty() ? "volume" : ", volume";
      if (!missing.empty())
        throw InputError(
            fmt::format("{}: the header has no column {}; the columns of a {}D "
                        "particle file: {}",
                        where, missing, Dim, valid));
      continue;
    }
    if (fields.size() != columns.size())
      throw InputError(fmt::format("{}: {} fields, and the header names {} columns", where,
                                   fields.size(), columns.size()));
    Vec<Dim> x = Vec<Dim>::Zero(), v = Vec<Dim>::Zero();
    Mat<Dim> s = Mat<Dim>::Zero();
    std::array<std::array<bool, Dim>, Dim> set{};
    double vol = 0.0, zz = 0.0;
    for (std::size_t k = 0; k < fields.size(); ++k) {
      const double value = parse_number(fields[k], where, names[k]);
      const Column& c = columns[k];
      switch (c.kind) {
        case kPosition:
          x[c.i] = value;
          break;
        case kVelocity:
          v[c.i] = value;
          break;
        case kVolume:
          vol = value;
          break;
        case kStressZz:
          zz = value;
          break;
        case kStress:
          s(c.i, c.j) = value;
          set[static_cast<std::size_t>(c.i)][static_cast<std::size_t>(c.j)] = true;
          break;
      }
    }
    if (!(vol > 0.0)) throw InputError(fmt::format("{}: volume = {} must be positive", where, vol));
    // A stress given by both its (i, j) and (j, i) columns must be symmetric (to the round-off
    // of a written tensor); one given alone stands for both.
    for (int i = 0; i < Dim; ++i)
      for (int j = i + 1; j < Dim; ++j) {
        const auto I = static_cast<std::size_t>(i), J = static_cast<std::size_t>(j);
        if (set[I][J] && set[J][I]) {
          if (std::abs(s(i, j) - s(j, i)) > 1e-12 * std::max(1.0, s.cwiseAbs().maxCoeff()))
            throw InputError(fmt::format(
                "{}: stress_{}{} = {} and stress_{}{} = {} differ; a Cauchy stress is symmetric",
                where, i + 1, j + 1, s(i, j), j + 1, i + 1, s(j, i)));
          s(i, j) = s(j, i) = 0.5 * (s(i, j) + s(j, i));
        } else if (set[J][I]) {
          s(i, j) = s(j, i);
        } else {
          s(j, i) = s(i, j);
        }
      }
    if (!std::isfinite(volume_ + vol))
      throw InputError(fmt::format("{}: the volumes' sum overflows", where));
    x_.push_back(x);
    vol_.push_back(vol);
    line_.push_back(line_no);
    volume_ += vol;
    if (has_velocity) velocity_.push_back(v);
    if (has_stress) stress_.push_back(s);
    if (has_zz) stress_zz_.push_back(zz);
  }
  return !header;
}

template <int Dim>
std::optional<FileBody<Dim>> FileBody<Dim>::from_config(const Config& cfg,
                                                        const std::string& table) {
  const std::string mesh_key = table + ".mesh", particles_key = table + ".particles";
  const std::string mesh = cfg.get_string(mesh_key);
  const std::string particles = cfg.get_string(particles_key);
  if (mesh.empty() && particles.empty()) return std::nullopt;
  if (!mesh.empty() && !particles.empty())
    throw InputError(fmt::format("{}: {} (at {}) and {} both give the body; give one of them",
                                 cfg.where(particles_key), mesh_key, cfg.where(mesh_key),
                                 particles_key));
  for (const std::string& key : {table + ".min", table + ".max"})
    if (!cfg.at_default(key))
      throw InputError(fmt::format(
          "{}: {} is a corner of a box body, and this run's body comes from {} = \"{}\" (leave "
          "{} out)",
          cfg.where(key), key, mesh.empty() ? particles_key : mesh_key,
          mesh.empty() ? particles : mesh, key));
  FileBody b;
  b.key_ = mesh.empty() ? particles_key : mesh_key;
  const std::filesystem::path path = cfg.file_path(b.key_);
  std::error_code ec;
  const bool from_file = std::filesystem::is_regular_file(cfg.source(), ec);
  const std::string note = path.is_relative() && !from_file
                               ? " (taken from the working directory: the configuration is not a "
                                 "file, as in a restart from a checkpoint alone; give the "
                                 "configuration file too)"
                               : "";
  if (!mesh.empty()) {
    auto per = static_cast<int>(cfg.get_int("particles.per_element"));
    if (per == 0) per = Dim == 2 ? 3 : 4;  // the degree-2 rules
    try {
      if constexpr (Dim == 2)
        b.ref_ = triangle_seed_reference(per);
      else
        b.ref_ = tetrahedron_seed_reference(per);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: particles.per_element: {}",
                                   cfg.where("particles.per_element"), e.what()));
    }
    try {
      b.mesh_ = std::make_shared<const BodyMesh<Dim>>(read_gmsh_body<Dim>(path.string()));
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {}: {}{}", cfg.where(mesh_key), mesh_key, e.what(), note));
    }
    b.source_ = fmt::format("body mesh \"{}\"", path.string());
    // Overlapping elements would count their common volume twice: refused where a particle of
    // one lies inside another (an overlap thinner than the particles' spacing goes unseen).
    {
      const BodyMesh<Dim>& m = *b.mesh_;
      const auto per = static_cast<Index>(b.ref_.size());
      Index k = 0;
      b.for_each([&](const Vec<Dim>& x, double) {
        const Index own = k++ / per;
        if (const Index other = m.other_element_holding(x, own); other >= 0)
          throw InputError(fmt::format(
              "{}: {}: elements {} and {} of {} overlap (a particle of the first lies "
              "inside the second); a body mesh's elements must not overlap (one physical group "
              "meshed twice?)",
              cfg.where(mesh_key), mesh_key, m.tag(own), m.tag(other), b.source_));
      });
    }
    b.count_ = b.mesh_->num_elements() * static_cast<Index>(b.ref_.size());
    b.lo_ = b.mesh_->lower();
    b.hi_ = b.mesh_->upper();
    b.for_each([&](const Vec<Dim>&, double v) { b.volume_ += v; });
    return b;
  }
  b.source_ = fmt::format("particle file \"{}\"", path.string());
  std::string bytes;
  try {
    bytes = read_input_file(path, "particle file");
  } catch (const InputError& e) {
    throw InputError(
        fmt::format("{}: {}: {}{}", cfg.where(particles_key), particles_key, e.what(), note));
  }
  const bool had_header = b.read_rows(bytes);
  if (b.x_.empty())
    throw InputError(fmt::format("{}: {}: no particles (a header{})", cfg.where(particles_key),
                                 b.source_, had_header ? " and no rows" : " is missing too"));
  b.count_ = static_cast<Index>(b.x_.size());
  b.lo_ = b.hi_ = b.x_[0];
  for (const auto& x : b.x_) {
    b.lo_ = b.lo_.cwiseMin(x);
    b.hi_ = b.hi_.cwiseMax(x);
  }
  return b;
}

template <int Dim>
void FileBody<Dim>::for_each(const std::function<void(const Vec<Dim>& X, double volume)>& f) const {
  if (!mesh_) {
    for (std::size_t i = 0; i < x_.size(); ++i) f(x_[i], vol_[i]);
    return;
  }
  const BodyMesh<Dim>& m = *mesh_;
  const double share = 1.0 / static_cast<double>(ref_.size());
  for (Index e = 0; e < m.num_elements(); ++e) {
    const auto& el = m.element(e);
    const Vec<Dim>& x0 = m.vertex(el[0]);
    Mat<Dim> J;
    for (int d = 0; d < Dim; ++d) J.col(d) = m.vertex(el[static_cast<std::size_t>(d) + 1]) - x0;
    const double vol = m.element_volume(e) * share;
    for (const Vec<Dim>& r : ref_) f(x0 + J * r, vol);
  }
}

template <int Dim>
double FileBody<Dim>::integral_above(const Vec<Dim>& X,
                                     const std::function<double(int part)>& weight) const {
  if (!mesh_) throw std::logic_error("FileBody::integral_above: a particle file has no elements");
  const BodyMesh<Dim>& m = *mesh_;
  return m.integral_above(X, [&](Index e) { return weight(m.group(e)); });
}

template <int Dim>
void FileBody<Dim>::check_inside(const Config& cfg,
                                 const std::function<bool(const Vec<Dim>&)>& inside,
                                 const std::string& grid) const {
  auto point = [](const Vec<Dim>& x) {
    return Dim == 2 ? fmt::format("({:.6g}, {:.6g})", x[0], x[1])
                    : fmt::format("({:.6g}, {:.6g}, {:.6g})", x[0], x[1], x[Dim - 1]);
  };
  if (mesh_) {
    const BodyMesh<Dim>& m = *mesh_;
    const auto per = static_cast<Index>(ref_.size());
    Index k = 0;
    for_each([&](const Vec<Dim>& x, double) {
      if (!inside(x))
        throw InputError(fmt::format(
            "{}: element {} of {} has a particle at {}, outside {}; a body lies on its grid "
            "(move the body, or make the grid larger: grid.min, grid.max)",
            cfg.where(key_), m.tag(k / per), source_, point(x), grid));
      ++k;
    });
    return;
  }
  for (std::size_t i = 0; i < x_.size(); ++i)
    if (!inside(x_[i]))
      throw InputError(fmt::format(
          "{}: {}, line {}: the particle at {} lies outside {}; a body lies on its grid (move "
          "the body, or make the grid larger: grid.min, grid.max)",
          cfg.where(key_), source_, line_[i], point(x_[i]), grid));
}

template class FileBody<2>;
template class FileBody<3>;

}  // namespace mpm
