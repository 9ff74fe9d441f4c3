#include "io/checkpoint.hpp"

#include <fmt/format.h>
#include <bit>
#include <fstream>
#include <iterator>
#include <sstream>
#include <type_traits>

#include "core/bytes.hpp"
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
  } else {
    out.clear();
    out.reserve(in.size() * static_cast<std::size_t>(T::SizeAtCompileTime));
    for (const auto& e : in) out.insert(out.end(), e.data(), e.data() + e.size());
  }
}

template <class T>
void unflatten(const std::vector<double>& in, std::vector<T>& out, std::size_t n,
               const std::string& what, const std::string& field) {
  std::size_t k = 1;
  if constexpr (!std::is_same_v<T, double>) k = static_cast<std::size_t>(T::SizeAtCompileTime);
  // (Compared by division: n is read from the file, and n * k may wrap around.)
  if (in.size() % k != 0 || in.size() / k != n)
    throw InputError(
        fmt::format("{}: particle field {} holds {} values, expected {} per particle "
                    "for {} particles",
                    what, field, in.size(), k, n));
  if constexpr (std::is_same_v<T, double>) {
    out = in;
  } else {
    out.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      std::copy(in.begin() + static_cast<std::ptrdiff_t>(i * k),
                in.begin() + static_cast<std::ptrdiff_t>((i + 1) * k), out[i].data());
  }
}

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
      if constexpr (!std::is_same_v<typename std::decay_t<decltype(field)>::value_type,
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
    using T = typename std::decay_t<decltype(field)>::value_type;
    if constexpr (std::is_same_v<T, CompactIndex>)
      a.id.assign(field.begin(), field.end());
    else
      flatten(field, a.reals[k++]);
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
    using T = typename std::decay_t<decltype(field)>::value_type;
    if constexpr (std::is_same_v<T, CompactIndex>) {
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
  ByteWriter p;
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

  ByteWriter out;
  out.bytes().append(kCheckpointMagic);
  out.u32(kCheckpointVersion);
  out.u64(p.bytes().size());
  out.u64(fnv1a64(p.bytes()));
  out.bytes() += p.bytes();
  return std::move(out.bytes());
}

Checkpoint decode_checkpoint(std::string_view bytes, const std::string& name) {
  if (bytes.size() < kCheckpointMagic.size() && kCheckpointMagic.substr(0, bytes.size()) == bytes)
    throw InputError(fmt::format("checkpoint '{}' is truncated: {} bytes", name, bytes.size()));
  if (bytes.size() < kCheckpointMagic.size() ||
      bytes.substr(0, kCheckpointMagic.size()) != kCheckpointMagic)
    throw InputError(fmt::format("'{}' is not an mpmlab checkpoint (it does not start with \"{}\")",
                                 name, kCheckpointMagic));
  if (bytes.size() < kCheckpointHeaderBytes)
    throw InputError(fmt::format("checkpoint '{}' is truncated: {} bytes, the header alone is {}",
                                 name, bytes.size(), kCheckpointHeaderBytes));
  ByteReader h(
      bytes.substr(kCheckpointMagic.size(), kCheckpointHeaderBytes - kCheckpointMagic.size()),
      name);
  const std::uint32_t version = h.u32();
  const std::uint64_t size = h.u64();
  const std::uint64_t hash = h.u64();
  if (version != kCheckpointVersion)
    throw InputError(
        fmt::format("checkpoint '{}' has format version {}; this mpm reads version {} only", name,
                    version, kCheckpointVersion));
  const std::string_view payload = bytes.substr(kCheckpointHeaderBytes);
  if (payload.size() != size)
    throw InputError(fmt::format(
        "checkpoint '{}' is {}: the header announces {} payload bytes, the file holds {}", name,
        payload.size() < size ? "truncated" : "longer than written", size, payload.size()));
  const std::uint64_t actual = fnv1a64(payload);
  if (actual != hash)
    throw InputError(fmt::format(
        "checkpoint '{}' is corrupted: the payload checksum is {:016x}, the header says {:016x}",
        name, actual, hash));

  ByteReader r(payload, name);
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
  if (!r.done())
    throw InputError(fmt::format("checkpoint '{}': unexpected bytes after the payload", name));
  return c;
}

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& c) {
  write_file_atomic(path, encode_checkpoint(c));
}

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(fmt::format("cannot open checkpoint '{}'", path.string()));
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(fmt::format("cannot read checkpoint '{}'", path.string()));
  return decode_checkpoint(ss.str(), path.string());
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

Config restart_config(const Checkpoint& c, const std::string& name, const Config* given,
                      const std::vector<std::string>& overrides) {
  const std::string source = fmt::format("{} (stored configuration)", name);
  const Config stored = Config::parse(c.config, source);
  const Config run = given ? *given : Config::parse(c.config, source, overrides);
  std::vector<std::string> diff;
  for (const KeySpec& k : schema()) {
    if (k.name.starts_with("output.") || k.name == "time.end") continue;
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
        "restart may change only output.* and time.end:{}",
        name, diff.size(), lines));
  }
  return run;
}

}  // namespace mpm::io
