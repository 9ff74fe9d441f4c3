#include "io/checkpoint.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <bit>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "core/bytes.hpp"
#include "core/input_file.hpp"
#include "io/output.hpp"

namespace mpm::io {
namespace {

void put(ByteWriter& w, const ParticleArrays& a) {
  w.i64(a.dim);
  w.i64(a.count);
  for (const auto& f : a.reals) w.reals(f);
  w.ints(a.id);
}

ParticleArrays get_particles(ByteReader& r) {
  ParticleArrays a;
  a.dim = r.i64();
  a.count = r.i64();
  for (auto& f : a.reals) f = r.reals();
  a.id = r.ints();
  return a;
}

// A particle field as doubles: Dim or Dim^2 values per particle for vectors and tensors.
template <class T>
void flatten(const std::vector<T>& in, std::vector<double>& out) {
  if constexpr (std::is_same_v<T, double>) {
    out = in;
  } else if constexpr (std::is_integral_v<T>) {
    out.assign(in.begin(), in.end());  // a particle's material index: exact in a double
  } else {
    out.clear();
    out.reserve(in.size() * static_cast<std::size_t>(T::SizeAtCompileTime));
    for (const auto& e : in) out.insert(out.end(), e.data(), e.data() + e.size());
  }
}

// A material's internal variables: their values, row after row (width values per particle).
void flatten(const MaterialState& in, std::vector<double>& out) {
  out = in.values();
}

template <class T>
void unflatten(const std::vector<double>& in, std::vector<T>& out, std::size_t n,
               const std::string& what, const std::string& field) {
  std::size_t k = 1;
  if constexpr (!std::is_same_v<T, double> && !std::is_integral_v<T>)
    k = static_cast<std::size_t>(T::SizeAtCompileTime);
  // (Compared by division: n is read from the file, and n * k may wrap around.)
  if (in.size() % k != 0 || in.size() / k != n)
    throw InputError(
        fmt::format("{}: particle field {} holds {} values, expected {} per particle "
                    "for {} particles",
                    what, field, in.size(), k, n));
  if constexpr (std::is_same_v<T, double>) {
    out = in;
  } else if constexpr (std::is_integral_v<T>) {
    out.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      // (A whole number in T's range: the run checks it against its materials.)
      if (!(in[i] >= static_cast<double>(std::numeric_limits<T>::min()) &&
            in[i] <= static_cast<double>(std::numeric_limits<T>::max()) &&
            in[i] == std::floor(in[i])))
        throw InputError(fmt::format("{}: particle field {} holds {} at particle {}, not an index",
                                     what, field, in[i], i));
      out[i] = static_cast<T>(in[i]);
    }
  } else {
    out.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      std::copy(in.begin() + static_cast<std::ptrdiff_t>(i * k),
                in.begin() + static_cast<std::ptrdiff_t>((i + 1) * k), out[i].data());
  }
}

// A writer for a framed file: room for the header first, and for `payload` bytes after it
// (reserved up front: a piece of a few hundred MB is written without the doubling growth of a
// string, whose peak was twice its size). framed() fills the header (magic, version, payload
// size, payload hash) in place, without copying the payload.
ByteWriter framing(std::size_t payload);
std::string framed(std::string_view magic, ByteWriter& w);
// Bytes the payload encoding of `a` takes (put() below).
std::size_t encoded_size(const ParticleArrays& a) {
  std::size_t n = 3 * 8 + 8 * a.id.size();
  for (const auto& f : a.reals) n += 8 + 8 * f.size();
  return n;
}
// The payload of a framed file, after its header's checks; `kind` ("checkpoint", "checkpoint
// piece") names it in the messages.
std::string_view unframed(std::string_view bytes, std::string_view magic, const std::string& name,
                          std::string_view kind);

}  // namespace

std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t h = 14695981039346656037ull;
  for (char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  return h;
}

const std::vector<std::string>& particle_field_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    const Particles<1> p;
    p.for_each_named_field([&](const char* name, const auto& field) {
      if constexpr (kIsMaterialState<decltype(field)>)
        n.emplace_back(name);
      else if constexpr (!std::is_same_v<typename std::decay_t<decltype(field)>::value_type,
                                         CompactIndex>)
        n.emplace_back(name);
    });
    return n;
  }();
  return names;
}

template <int Dim>
ParticleArrays pack_particles(const Particles<Dim>& p) {
  ParticleArrays a;
  a.dim = Dim;
  a.count = p.size();
  std::size_t k = 0;
  p.for_each_named_field([&](const char*, const auto& field) {
    if constexpr (kIsMaterialState<decltype(field)>) {
      flatten(field, a.reals[k++]);
    } else {
      using T = typename std::decay_t<decltype(field)>::value_type;
      if constexpr (std::is_same_v<T, CompactIndex>)
        a.id.assign(field.begin(), field.end());
      else
        flatten(field, a.reals[k++]);
    }
  });
  return a;
}

template <int Dim>
Particles<Dim> unpack_particles(const ParticleArrays& a, const std::string& what) {
  if (a.dim != Dim || a.count < 0)
    throw InputError(fmt::format("{}: particles of dimension {}, expected {}", what, a.dim, Dim));
  const auto& names = particle_field_names();
  if (a.reals.size() != names.size())
    throw InputError(
        fmt::format("{}: {} particle fields, expected {}", what, a.reals.size(), names.size()));
  const auto n = static_cast<std::size_t>(a.count);
  Particles<Dim> p;
  std::size_t k = 0;
  p.for_each_named_field([&](const char* name, auto& field) {
    if constexpr (kIsMaterialState<decltype(field)>) {
      // Rows of the material's internal variables, named by the run's material when it
      // continues (MaterialState::set_names checks their width).
      auto& values = a.reals[k++];
      if (n == 0 ? !values.empty() : values.size() % n != 0)
        throw InputError(
            fmt::format("{}: particle field {} holds {} values, not a whole number "
                        "per particle for {} particles",
                        what, name, values.size(), n));
      field.set_raw(n, values);
    } else if constexpr (std::is_same_v<typename std::decay_t<decltype(field)>::value_type,
                                        CompactIndex>) {
      // The ids in the stored order: a run re-sorted before the checkpoint continues in that
      // order.
      if (a.id.size() != n)
        throw InputError(fmt::format("{}: particle field {} holds {} values, expected {}", what,
                                     name, a.id.size(), n));
      field.assign(a.id.begin(), a.id.end());
    } else {
      unflatten(a.reals[k++], field, n, what, name);
    }
  });
  return p;
}

template ParticleArrays pack_particles<1>(const Particles<1>&);
template ParticleArrays pack_particles<2>(const Particles<2>&);
template ParticleArrays pack_particles<3>(const Particles<3>&);
template Particles<1> unpack_particles<1>(const ParticleArrays&, const std::string&);
template Particles<2> unpack_particles<2>(const ParticleArrays&, const std::string&);
template Particles<3> unpack_particles<3>(const ParticleArrays&, const std::string&);

FemArrays pack_fem(const Ulfem1D::State& s) {
  FemArrays a;
  a.x = s.x;
  a.v = s.v;
  flatten(s.node_body, a.body);
  a.elements = pack_particles<1>(s.elements);
  a.time = s.time;
  a.time_anchor = s.time_anchor;
  a.last_dt = s.last_dt;
  a.steps = s.steps;
  a.steps_since_anchor = s.steps_since_anchor;
  return a;
}

Ulfem1D::State unpack_fem(const FemArrays& a, const std::string& what) {
  Ulfem1D::State s;
  s.x = a.x;
  s.v = a.v;
  unflatten(a.body, s.node_body, a.body.size(), what, "node body");
  s.elements = unpack_particles<1>(a.elements, what);
  s.time = a.time;
  s.time_anchor = a.time_anchor;
  s.last_dt = a.last_dt;
  s.steps = a.steps;
  s.steps_since_anchor = a.steps_since_anchor;
  return s;
}

std::string encode_checkpoint(const Checkpoint& c) {
  // (The sizes of the large arrays; the rest is small.)
  ByteWriter p = framing(encoded_size(c.particles) +
                         8 * (c.cells.size() + c.basis_state.size() + c.frame_times.size() +
                              c.distribution.size() + c.layer_counts.size()) +
                         (c.fem ? encoded_size(c.fem->elements) +
                                      8 * (c.fem->x.size() + c.fem->v.size() + c.fem->body.size())
                                : 0) +
                         c.config.size() + c.mapping_totals.size() + 64 * c.pieces.size() + 4096);
  p.str(c.config);
  p.str(c.solver);
  p.i64(c.dim);
  p.i64(c.step);
  p.f64(c.time);
  put(p, c.particles);
  p.ints(c.cells);
  p.i64(c.sort_reference);
  p.i64(c.sorts);
  p.f64(c.diag.max_rel_mass_error);
  p.f64(c.diag.max_rel_momentum_error);
  p.i64(c.diag.grid_crossings);
  p.u8(c.fem ? 1 : 0);
  if (c.fem) {
    p.reals(c.fem->x);
    p.reals(c.fem->v);
    p.reals(c.fem->body);
    put(p, c.fem->elements);
    p.f64(c.fem->time);
    p.f64(c.fem->time_anchor);
    p.f64(c.fem->last_dt);
    p.i64(c.fem->steps);
    p.i64(c.fem->steps_since_anchor);
  }
  p.str(c.mapping);
  p.str(c.mapping_totals);
  p.i64(c.frames);
  p.reals(c.frame_times);
  p.reals(c.basis_state);
  p.ints(c.distribution);
  p.ints(c.layer_counts);
  p.u64(c.pieces.size());
  for (const auto& piece : c.pieces) {
    p.str(piece.file);
    p.u64(piece.bytes);
    p.u64(piece.hash);
  }
  p.u64(c.mesh_hash);
  return framed(kCheckpointMagic, p);
}

namespace {

static_assert(kCheckpointMagic.size() == 8 && kPieceMagic.size() == 8 &&
              kCheckpointHeaderBytes == 8 + 4 + 8 + 8);

ByteWriter framing(std::size_t payload) {
  ByteWriter w;
  w.bytes().reserve(kCheckpointHeaderBytes + payload);
  w.bytes().resize(kCheckpointHeaderBytes);
  return w;
}

std::string framed(std::string_view magic, ByteWriter& w) {
  std::string& bytes = w.bytes();
  const std::string_view payload = std::string_view(bytes).substr(kCheckpointHeaderBytes);
  ByteWriter h;
  h.bytes().append(magic);
  h.u32(kCheckpointVersion);
  h.u64(payload.size());
  h.u64(fnv1a64(payload));
  bytes.replace(0, kCheckpointHeaderBytes, h.bytes());
  return std::move(bytes);
}

std::string_view unframed(std::string_view bytes, std::string_view magic, const std::string& name,
                          std::string_view kind) {
  if (bytes.size() < magic.size() && magic.substr(0, bytes.size()) == bytes)
    throw InputError(fmt::format("{} '{}' is truncated: {} bytes", kind, name, bytes.size()));
  if (bytes.size() < magic.size() || bytes.substr(0, magic.size()) != magic) {
    // A piece given where the manifest is expected (mpm run --restart), or the other way round.
    if (magic == kCheckpointMagic && bytes.substr(0, kPieceMagic.size()) == kPieceMagic)
      throw InputError(
          fmt::format("'{}' is one process's piece of a distributed checkpoint; restart from the "
                      "{} next to it",
                      name, kCheckpointFile));
    throw InputError(
        fmt::format("'{}' is not an mpmlab {} (it does not start with \"{}\")", name, kind, magic));
  }
  if (bytes.size() < kCheckpointHeaderBytes)
    throw InputError(fmt::format("{} '{}' is truncated: {} bytes, the header alone is {}", kind,
                                 name, bytes.size(), kCheckpointHeaderBytes));
  ByteReader h(bytes.substr(magic.size(), kCheckpointHeaderBytes - magic.size()), name);
  const std::uint32_t version = h.u32();
  const std::uint64_t size = h.u64();
  const std::uint64_t hash = h.u64();
  if (version != kCheckpointVersion)
    throw InputError(fmt::format("{} '{}' has format version {}; this mpm reads version {} only",
                                 kind, name, version, kCheckpointVersion));
  const std::string_view payload = bytes.substr(kCheckpointHeaderBytes);
  if (payload.size() != size)
    throw InputError(fmt::format(
        "{} '{}' is {}: the header announces {} payload bytes, the file holds {}", kind, name,
        payload.size() < size ? "truncated" : "longer than written", size, payload.size()));
  const std::uint64_t actual = fnv1a64(payload);
  if (actual != hash)
    throw InputError(fmt::format(
        "{} '{}' is corrupted: the payload checksum is {:016x}, the header says {:016x}", kind,
        name, actual, hash));
  return payload;
}

}  // namespace

Checkpoint decode_checkpoint(std::string_view bytes, const std::string& name) {
  ByteReader r(unframed(bytes, kCheckpointMagic, name, "checkpoint"), name);
  Checkpoint c;
  c.config = r.str();
  c.solver = r.str();
  c.dim = r.i64();
  c.step = r.i64();
  c.time = r.f64();
  c.particles = get_particles(r);
  c.cells = r.ints();
  c.sort_reference = r.i64();
  c.sorts = r.i64();
  c.diag.max_rel_mass_error = r.f64();
  c.diag.max_rel_momentum_error = r.f64();
  c.diag.grid_crossings = r.i64();
  if (r.flag()) {
    FemArrays f;
    f.x = r.reals();
    f.v = r.reals();
    f.body = r.reals();
    f.elements = get_particles(r);
    f.time = r.f64();
    f.time_anchor = r.f64();
    f.last_dt = r.f64();
    f.steps = r.i64();
    f.steps_since_anchor = r.i64();
    c.fem = std::move(f);
  }
  c.mapping = r.str();
  c.mapping_totals = r.str();
  c.frames = r.i64();
  c.frame_times = r.reals();
  c.basis_state = r.reals();
  c.distribution = r.ints();
  c.layer_counts = r.ints();
  // (No reserve: the count is read from the file; each entry's bytes must follow.)
  for (std::uint64_t k = 0, n = r.u64(); k < n; ++k) {
    Checkpoint::Piece piece;
    piece.file = r.str();
    piece.bytes = r.u64();
    piece.hash = r.u64();
    c.pieces.push_back(std::move(piece));
  }
  c.mesh_hash = r.u64();
  if (!r.done())
    throw InputError(fmt::format("checkpoint '{}': unexpected bytes after the payload", name));
  return c;
}

std::string encode_piece(const CheckpointPiece& piece) {
  ByteWriter p = framing(3 * 8 + encoded_size(piece.particles) +
                         8 * (2 + piece.cells.size() + piece.basis_state.size()));
  p.i64(piece.step);
  p.i64(piece.rank);
  p.i64(piece.ranks);
  put(p, piece.particles);
  p.ints(piece.cells);
  p.reals(piece.basis_state);
  return framed(kPieceMagic, p);
}

namespace {
// put(w, pack_particles(p)) without the copy.
template <int Dim>
void put_particles(ByteWriter& w, const Particles<Dim>& p) {
  w.i64(Dim);
  w.i64(p.size());
  p.for_each_named_field([&](const char*, const auto& field) {
    if constexpr (kIsMaterialState<decltype(field)>) {
      w.reals(field.values());
      return;
    } else {
      using T = typename std::decay_t<decltype(field)>::value_type;
      if constexpr (std::is_same_v<T, double>) {
        w.reals(field);
      } else if constexpr (std::is_same_v<T, MaterialIndex>) {
        w.u64(field.size());
        for (const auto m : field) w.f64(static_cast<double>(m));  // as flatten(): exact
      } else if constexpr (!std::is_same_v<T, CompactIndex>) {
        constexpr auto k = static_cast<std::size_t>(T::SizeAtCompileTime);
        w.u64(field.size() * k);
        for (const auto& e : field)
          for (std::size_t j = 0; j < k; ++j) w.f64(e.data()[j]);
      }
    }
  });
  w.u64(p.id.size());
  for (const auto id : p.id) w.i64(static_cast<std::int64_t>(id));
}
}  // namespace

template <int Dim>
std::string encode_piece(std::int64_t step, std::int64_t rank, std::int64_t ranks,
                         const Particles<Dim>& particles, std::span<const CompactIndex> cells,
                         const std::vector<double>& basis_state) {
  const auto n = static_cast<std::size_t>(particles.size());
  // (Per particle: the real fields, the material's index as a double, the id and the cell; the
  // counts.)
  ByteWriter p = framing(8 * (5 + particle_field_names().size() + 2) +
                         n * (particles.record_bytes() + 8 + 2 * 8) + 8 * basis_state.size());
  p.i64(step);
  p.i64(rank);
  p.i64(ranks);
  put_particles(p, particles);
  p.u64(cells.size());
  for (const auto c : cells) p.i64(static_cast<std::int64_t>(c));
  p.reals(basis_state);
  return framed(kPieceMagic, p);
}

template std::string encode_piece<1>(std::int64_t, std::int64_t, std::int64_t, const Particles<1>&,
                                     std::span<const CompactIndex>, const std::vector<double>&);
template std::string encode_piece<2>(std::int64_t, std::int64_t, std::int64_t, const Particles<2>&,
                                     std::span<const CompactIndex>, const std::vector<double>&);
template std::string encode_piece<3>(std::int64_t, std::int64_t, std::int64_t, const Particles<3>&,
                                     std::span<const CompactIndex>, const std::vector<double>&);

CheckpointPiece decode_piece(std::string_view bytes, const std::string& name) {
  ByteReader r(unframed(bytes, kPieceMagic, name, "checkpoint piece"), name);
  CheckpointPiece piece;
  piece.step = r.i64();
  piece.rank = r.i64();
  piece.ranks = r.i64();
  piece.particles = get_particles(r);
  piece.cells = r.ints();
  piece.basis_state = r.reals();
  if (!r.done())
    throw InputError(
        fmt::format("checkpoint piece '{}': unexpected bytes after the payload", name));
  return piece;
}

Checkpoint::Piece describe_piece(const std::string& file, std::string_view bytes) {
  if (bytes.size() < kCheckpointHeaderBytes)
    throw std::logic_error("describe_piece: not an encoded piece");
  ByteReader h(bytes.substr(kCheckpointHeaderBytes - 8, 8), file);
  return {file, bytes.size(), h.u64()};
}

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& c) {
  write_file_atomic(path, encode_checkpoint(c));
}

namespace {

std::string read_bytes(const std::filesystem::path& path, std::string_view kind) {
  return read_input_file(path, kind);
}

template <class T>
void append(std::vector<T>& to, const std::vector<T>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

}  // namespace

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  return decode_checkpoint(read_bytes(path, "checkpoint"), path.string());
}

std::vector<std::int64_t> join_pieces(Checkpoint& c, const std::filesystem::path& manifest,
                                      const std::vector<bool>& take) {
  const std::string what = fmt::format("checkpoint '{}'", manifest.string());
  const auto ranks = static_cast<std::int64_t>(c.pieces.size());
  if (take.size() != c.pieces.size())
    throw std::logic_error("join_pieces: one choice per piece expected");
  std::vector<std::int64_t> counts;
  for (std::int64_t r = 0; r < ranks; ++r) {
    if (!take[static_cast<std::size_t>(r)]) continue;
    const Checkpoint::Piece& ref = c.pieces[static_cast<std::size_t>(r)];
    // Only the name this run gives the piece (no other path is opened).
    if (ref.file != checkpoint_piece_name(c.step, static_cast<int>(r)))
      throw InputError(fmt::format("{} names piece {} '{}'; a checkpoint at step {} names it '{}'",
                                   what, r, ref.file, c.step,
                                   checkpoint_piece_name(c.step, static_cast<int>(r))));
    const std::filesystem::path file = manifest.parent_path() / ref.file;
    const std::string bytes = read_bytes(file, "checkpoint piece");
    CheckpointPiece piece = decode_piece(bytes, file.string());  // its header and checksum
    const Checkpoint::Piece found = describe_piece(ref.file, bytes);
    if (found.bytes != ref.bytes || found.hash != ref.hash)
      throw InputError(fmt::format(
          "checkpoint piece '{}' is not the one {} was written with: {} bytes with payload hash "
          "{:016x}, the manifest says {} bytes, {:016x} (a piece of another checkpoint, or "
          "damaged)",
          file.string(), what, found.bytes, found.hash, ref.bytes, ref.hash));
    if (piece.step != c.step || piece.rank != r || piece.ranks != ranks ||
        piece.particles.dim != c.dim)
      throw InputError(fmt::format(
          "checkpoint piece '{}' holds step {} of process {} of {} in {}D; {} expects step {} of "
          "process {} of {} in {}D",
          file.string(), piece.step, piece.rank, piece.ranks, piece.particles.dim, what, c.step, r,
          ranks, c.dim));
    counts.push_back(piece.particles.count);
    // The first piece taken becomes the particles; later ones are appended field by field.
    if (c.particles.count == 0 && c.particles.id.empty()) {
      c.particles = std::move(piece.particles);
    } else {
      for (std::size_t f = 0; f < c.particles.reals.size(); ++f)
        append(c.particles.reals[f], piece.particles.reals[f]);
      append(c.particles.id, piece.particles.id);
      c.particles.count += piece.particles.count;
    }
    append(c.cells, piece.cells);
    append(c.basis_state, piece.basis_state);
  }
  return counts;
}

Checkpoint read_whole_checkpoint(const std::filesystem::path& path) {
  Checkpoint c = read_checkpoint(path);
  if (!c.pieces.empty()) join_pieces(c, path, std::vector<bool>(c.pieces.size(), true));
  return c;
}

namespace {

// A key's value as text for comparison and messages; reals compared by their exact digits.
std::optional<std::string> value_text(const Config& cfg, const KeySpec& k) {
  try {
    switch (k.type) {
      case KeyType::Integer:
        return fmt::format("{}", cfg.get_int(k.name));
      case KeyType::Real:
        return fmt::format("{}", cfg.get_real(k.name));
      case KeyType::Boolean:
        return cfg.get_bool(k.name) ? "true" : "false";
      case KeyType::String:
      case KeyType::Expression:
        return fmt::format("\"{}\"", cfg.get_string(k.name));
      case KeyType::RealVector: {
        std::string text;
        for (double v : cfg.get_reals(k.name))
          text += (text.empty() ? "" : ", ") + fmt::format("{}", v);
        return fmt::format("[{}]", text);
      }
      case KeyType::ExpressionVector: {
        std::string text;
        for (const auto& v : cfg.get_expressions(k.name))
          text += (text.empty() ? "\"" : ", \"") + v + "\"";
        return fmt::format("[{}]", text);
      }
    }
  } catch (const InputError&) {
  }
  return std::nullopt;  // a required key that is missing
}

}  // namespace

std::vector<std::string> hashed_input_keys(const Config& cfg) {
  std::vector<std::string> keys(std::begin(kHashedInputKeys), std::end(kHashedInputKeys));
  for (const std::string& n : cfg.instances("body"))
    for (const char* leaf : {"mesh", "particles"})
      keys.push_back(fmt::format("body.{}.{}", n, leaf));
  return keys;
}

Config restart_config(const Checkpoint& c, const std::string& name, const Config* given,
                      const std::vector<std::string>& overrides) {
  const std::string source = fmt::format("{} (stored configuration)", name);
  const Config stored = Config::parse(c.config, source);
  const Config run = given ? *given : Config::parse(c.config, source, overrides);
  std::vector<std::string> diff;
  // Every key, and every key of each named instance either configuration has ([material.NAME],
  // [body.NAME]: a section's keys, named in full).
  std::vector<KeySpec> keys(schema().begin(), schema().end());
  for (const std::string_view section : {"material", "body"}) {
    std::vector<std::string> names = stored.instances(section);
    for (const std::string& n : run.instances(section))
      if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
    for (const std::string& n : names)
      for (const KeySpec& k : schema())
        if (k.section() == section) {
          KeySpec named = k;
          named.name = fmt::format("{}.{}{}", section, n, k.name.substr(section.size()));
          keys.push_back(std::move(named));
        }
  }
  const std::vector<std::string> hashed = hashed_input_keys(run);
  for (const KeySpec& k : keys) {
    // The outputs, the end, and how the processes cut the grid (parallel.*: the answers are
    // those of one process on any decomposition, to round-off, as on another process count).
    if (k.name.starts_with("output.") || k.name.starts_with("parallel.") || k.name == "time.end")
      continue;
    if (std::find(hashed.begin(), hashed.end(), k.name) != hashed.end()) {
      // The same file, named from another directory (the stored configuration holds its
      // absolute path, a configuration file one relative to itself), is the same file.
      std::error_code ea, eb;
      const auto fa = std::filesystem::absolute(stored.file_path(k.name), ea).lexically_normal();
      const auto fb = std::filesystem::absolute(run.file_path(k.name), eb).lexically_normal();
      if (!ea && !eb && fa == fb) continue;
    }
    const auto a = value_text(stored, k), b = value_text(run, k);
    if (a != b)
      diff.push_back(fmt::format("  {}: checkpoint {}, now {} ({})", k.name, a.value_or("missing"),
                                 b.value_or("missing"), run.where(k.name)));
  }
  std::map<std::string, double> all = stored.constants();
  all.insert(run.constants().begin(), run.constants().end());
  for (const auto& [n, v] : all) {
    const auto a = stored.constants().find(n), b = run.constants().find(n);
    const bool in_a = a != stored.constants().end(), in_b = b != run.constants().end();
    if (in_a && in_b &&
        std::bit_cast<std::uint64_t>(a->second) == std::bit_cast<std::uint64_t>(b->second))
      continue;
    diff.push_back(fmt::format("  constants.{}: checkpoint {}, now {}", n,
                               in_a ? fmt::format("{}", a->second) : "missing",
                               in_b ? fmt::format("{}", b->second) : "missing"));
  }
  if (!diff.empty()) {
    std::string lines;
    for (const auto& d : diff) lines += "\n" + d;
    throw InputError(fmt::format(
        "the configuration differs from the one stored in checkpoint '{}' in {} key(s); a "
        "restart may change only output.*, parallel.* and time.end:{}",
        name, diff.size(), lines));
  }
  return run;
}

}  // namespace mpm::io
