#pragma once
// Bodies of a custom problem read from files instead of the box [body.min, body.max]: a Gmsh
// body mesh (body.mesh: triangles in 2D, tetrahedra in 3D) seeded element by element with a
// rule of particles.per_element equal-volume points, or a particle file (body.particles: CSV of
// positions, volumes and optional initial fields). Either lies on the run's own background grid
// (the box grid, or in 2D the triangles of grid.mesh), which it need not fill.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/types.hpp"
#include "grid/body_mesh.hpp"

namespace mpm {

class Config;

// The reference points of one triangle for m k^2 equal parts (m = 1, 3 or 6; k^2 similar
// sub-triangles, each split into m, one point at each part's centroid), in the coordinates
// (xi, eta) of the reference triangle (0, 0), (1, 0), (0, 1); InputError for a count not of
// that form. Every point stands for 1 / count of the triangle's area.
std::vector<Vec<2>> triangle_seed_reference(int per_triangle);
// The same for a tetrahedron: m 8^r points (m = 1: the centroid; m = 4: the four points of the
// degree-2 rule, barycentric (a, b, b, b) with a = (5 + 3 sqrt 5) / 20, b = (5 - sqrt 5) / 20)
// in each of the 8^r tetrahedra of r red refinements (Bey 1995: the corners and the octahedron
// cut along one diagonal, eight children of equal volume), in barycentric coordinates
// (lambda_1, lambda_2, lambda_3) of the reference tetrahedron. InputError for another count.
std::vector<Vec<3>> tetrahedron_seed_reference(int per_tetrahedron);
// The counts tetrahedron_seed_reference accepts, "1, 4, 8, 32, 64, 256, 512, ...".
std::string tetrahedron_seed_counts();

// InputError naming `what` when `count` particles' state (share: SeedScope::machine_share) would
// not fit in the machine's memory; checked before anything is allocated.
template <int Dim>
void check_seed_memory(double count, double share, const std::string& what);

// A body from a file: its points in the file's order (element by element, or row by row), each
// with its volume, and the initial fields a particle file gives.
template <int Dim>
class FileBody {
 public:
  // TABLE.mesh or TABLE.particles of `cfg` (TABLE: "body" or a named body "body.NAME";
  // relative paths from the configuration file's directory); nullopt when neither is given.
  // InputError naming the key and the file: both given, a box corner given too, a file that
  // cannot be read, particles.per_element not a count of the element's rule, or (particle files)
  // a malformed row. (Which seeding keys a run's bodies allow: BodySet.)
  static std::optional<FileBody> from_config(const Config& cfg, const std::string& table = "body");

  // "body mesh \"FILE\"" or "particle file \"FILE\"", for messages.
  const std::string& source() const { return source_; }
  // The key that named the file (body.mesh, body.particles, body.NAME.mesh, ...).
  const char* key() const { return key_.c_str(); }
  Index count() const { return count_; }
  // The sum of the points' volumes (a mesh's: its volume to round-off) [m^Dim].
  double volume() const { return volume_; }
  // The smallest box holding the body (a mesh's vertices, a particle file's points).
  const Vec<Dim>& lower() const { return lo_; }
  const Vec<Dim>& upper() const { return hi_; }
  // f(X, volume) for every point in order (its id: its place in that order).
  void for_each(const std::function<void(const Vec<Dim>& X, double volume)>& f) const;
  // InputError naming the key and the first point (a mesh: its element) that lies outside
  // `inside` (the grid, or a mesh grid's triangles): a body must lie on its grid.
  void check_inside(const Config& cfg, const std::function<bool(const Vec<Dim>&)>& inside,
                    const std::string& grid) const;

  // The parts of a body mesh (its physical groups of the body's dimension; none for a particle
  // file), and the part of point `id` (an index into part_names(), -1 for none).
  std::vector<std::string> part_names() const {
    return mesh_ ? mesh_->group_names() : std::vector<std::string>{};
  }
  int part_of(Index id) const {
    return mesh_ ? mesh_->group(id / static_cast<Index>(ref_.size())) : -1;
  }

  // A body mesh's integral along the vertical above X of a weight per part (BodyMesh::
  // integral_above; part -1: an element in no part), e.g. the mass above X per unit area of
  // parts of those densities. std::logic_error for a particle file.
  double integral_above(const Vec<Dim>& X, const std::function<double(int part)>& weight) const;
  bool is_mesh() const { return mesh_ != nullptr; }
  // The element of a body mesh whose inside holds x (BodyMesh::other_element_holding), -1 for
  // none and for a particle file.
  Index element_holding(const Vec<Dim>& x) const {
    return mesh_ ? mesh_->other_element_holding(x, -1) : -1;
  }

  // A particle file's initial fields by point (empty when its columns are not given): the
  // velocity [m/s], the Cauchy stress [Pa], and in 2D the stress normal to the plane [Pa].
  const std::vector<Vec<Dim>>& velocity() const { return velocity_; }
  const std::vector<Mat<Dim>>& stress() const { return stress_; }
  const std::vector<double>& stress_zz() const { return stress_zz_; }

 private:
  std::string source_;
  std::string key_;
  Index count_ = 0;
  double volume_ = 0.0;
  Vec<Dim> lo_, hi_;
  // A body mesh and its rule (reference points, each 1 / ref.size() of an element)...
  std::shared_ptr<const BodyMesh<Dim>> mesh_;
  std::vector<Vec<Dim>> ref_;
  // ... or a particle file's rows.
  std::vector<Vec<Dim>> x_;
  std::vector<double> vol_;
  std::vector<Vec<Dim>> velocity_;
  std::vector<Mat<Dim>> stress_;
  std::vector<double> stress_zz_;
  std::vector<Index> line_;  // each row's line in the file, for messages
  // Reads a particle file's rows (bodies.cpp); whether it had a header.
  bool read_rows(std::string_view text);
};

extern template class FileBody<2>;
extern template class FileBody<3>;

}  // namespace mpm
