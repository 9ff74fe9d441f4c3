#include "io/checkpoint.hpp"

#include <fmt/format.h>
#include <bit>
#include <fstream>
#include <iterator>
#include <sstream>

#include "io/output.hpp"

namespace mpm::io {
namespace {

// Little-endian byte writer and reader of the checkpoint payload.
class Writer {
 public:
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int k = 0; k < 4; ++k) u8(static_cast<std::uint8_t>(v >> (8 * k)));
  }
  void u64(std::uint64_t v) {
    for (int k = 0; k < 8; ++k) u8(static_cast<std::uint8_t>(v >> (8 * k)));
  }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
  void str(std::string_view s) {
    u64(s.size());
    out_.append(s);
  }
  void reals(const std::vector<double>& v) {
    u64(v.size());
    for (double x : v) f64(x);
  }
  void ints(const std::vector<std::int64_t>& v) {
    u64(v.size());
    for (auto x : v) i64(x);
  }
  std::string& bytes() { return out_; }

 private:
  std::string out_;
};

class Reader {
 public:
  Reader(std::string_view in, const std::string& name) : in_(in), name_(name) {}
  std::uint8_t u8() {
    need(1);
    return static_cast<std::uint8_t>(in_[pos_++]);
  }
  std::uint32_t u32() {
    std::uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v |= static_cast<std::uint32_t>(u8()) << (8 * k);
    return v;
  }
  std::uint64_t u64() {
    std::uint64_t v = 0;
    for (int k = 0; k < 8; ++k) v |= static_cast<std::uint64_t>(u8()) << (8 * k);
    return v;
  }
  std::int64_t i64() { return static_cast<std::int64_t>(u64()); }
  double f64() { return std::bit_cast<double>(u64()); }
  std::string str() {
    const auto n = count(1);
    std::string s(in_.substr(pos_, n));
    pos_ += n;
    return s;
  }
  std::vector<double> reals() {
    std::vector<double> v(count(8));
    for (double& x : v) x = f64();
    return v;
  }
  std::vector<std::int64_t> ints() {
    std::vector<std::int64_t> v(count(8));
    for (auto& x : v) x = i64();
    return v;
  }
  bool done() const { return pos_ == in_.size(); }

 private:
  // A length prefix whose elements of `size` bytes must still fit into the input.
  std::size_t count(std::size_t size) {
    const std::uint64_t n = u64();
    if (n > (in_.size() - pos_) / size) fail();
    return static_cast<std::size_t>(n);
  }
  void need(std::size_t n) {
    if (in_.size() - pos_ < n) fail();
  }
  [[noreturn]] void fail() const {
    throw InputError(fmt::format(
        "checkpoint '{}': the payload ends early or is malformed (at byte {} of {}); it was "
        "written by an incompatible mpm",
        name_, pos_, in_.size()));
  }

  std::string_view in_;
  std::string name_;
  std::size_t pos_ = 0;
};

void put(Writer& w, const ParticleArrays& a) {
  w.i64(a.dim);
  w.i64(a.count);
  for (const auto* f : {&a.x, &a.x0, &a.u, &a.v, &a.mass, &a.volume, &a.volume0, &a.density, &a.F,
                        &a.stress, &a.body})
    w.reals(*f);
  w.ints(a.id);
}

ParticleArrays get_particles(Reader& r) {
  ParticleArrays a;
  a.dim = r.i64();
  a.count = r.i64();
  for (auto* f : {&a.x, &a.x0, &a.u, &a.v, &a.mass, &a.volume, &a.volume0, &a.density, &a.F,
                  &a.stress, &a.body})
    *f = r.reals();
  a.id = r.ints();
  return a;
}

template <class T>
void flatten(const std::vector<T>& in, std::vector<double>& out) {
  out.clear();
  out.reserve(in.size() * static_cast<std::size_t>(T::SizeAtCompileTime));
  for (const auto& e : in) out.insert(out.end(), e.data(), e.data() + e.size());
}

template <class T>
void unflatten(const std::vector<double>& in, std::vector<T>& out, std::size_t n,
               const std::string& what, const char* field) {
  constexpr auto k = static_cast<std::size_t>(T::SizeAtCompileTime);
  if (in.size() != n * k)
    throw InputError(fmt::format("{}: particle field {} holds {} values, expected {}", what, field,
                                 in.size(), n * k));
  out.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    std::copy(in.begin() + static_cast<std::ptrdiff_t>(i * k),
              in.begin() + static_cast<std::ptrdiff_t>((i + 1) * k), out[i].data());
}

void scalars(const std::vector<double>& in, std::vector<double>& out, std::size_t n,
             const std::string& what, const char* field) {
  if (in.size() != n)
    throw InputError(fmt::format("{}: particle field {} holds {} values, expected {}", what, field,
                                 in.size(), n));
  out = in;
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

template <int Dim>
ParticleArrays pack_particles(const Particles<Dim>& p) {
  ParticleArrays a;
  a.dim = Dim;
  a.count = p.size();
  flatten(p.x, a.x);
  flatten(p.x0, a.x0);
  flatten(p.u, a.u);
  flatten(p.v, a.v);
  a.mass = p.mass;
  a.volume = p.volume;
  a.volume0 = p.volume0;
  a.density = p.density;
  flatten(p.F, a.F);
  flatten(p.stress, a.stress);
  flatten(p.body, a.body);
  a.id.assign(p.id.begin(), p.id.end());
  return a;
}

template <int Dim>
Particles<Dim> unpack_particles(const ParticleArrays& a, const std::string& what) {
  if (a.dim != Dim || a.count < 0)
    throw InputError(fmt::format("{}: particles of dimension {}, expected {}", what, a.dim, Dim));
  const auto n = static_cast<std::size_t>(a.count);
  Particles<Dim> p;
  unflatten(a.x, p.x, n, what, "x");
  unflatten(a.x0, p.x0, n, what, "x0");
  unflatten(a.u, p.u, n, what, "u");
  unflatten(a.v, p.v, n, what, "v");
  scalars(a.mass, p.mass, n, what, "mass");
  scalars(a.volume, p.volume, n, what, "volume");
  scalars(a.volume0, p.volume0, n, what, "volume0");
  scalars(a.density, p.density, n, what, "density");
  unflatten(a.F, p.F, n, what, "F");
  unflatten(a.stress, p.stress, n, what, "stress");
  unflatten(a.body, p.body, n, what, "body");
  // The ids in the stored order: a run re-sorted before the checkpoint continues in that order.
  if (a.id.size() != n)
    throw InputError(
        fmt::format("{}: particle field id holds {} values, expected {}", what, a.id.size(), n));
  p.id.assign(a.id.begin(), a.id.end());
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
  Writer p;
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

  Writer out;
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
  Reader h(bytes.substr(kCheckpointMagic.size(), kCheckpointHeaderBytes - kCheckpointMagic.size()),
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

  Reader r(payload, name);
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
  if (r.u8()) {
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
        return "\"" + cfg.get_string(k.name) + "\"";
      case KeyType::RealVector: {
        std::string text;
        for (double v : cfg.get_reals(k.name))
          text += (text.empty() ? "" : ", ") + fmt::format("{}", v);
        return "[" + text + "]";
      }
      case KeyType::ExpressionVector: {
        std::string text;
        for (const auto& v : cfg.get_expressions(k.name))
          text += (text.empty() ? "\"" : ", \"") + v + "\"";
        return "[" + text + "]";
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

std::string encode_totals(const TlsReport& t) {
  Writer w;
  for (Index v :
       {t.elements, t.active, t.full, t.reduced, t.with_virtual, t.with_neighbours, t.failed,
        t.outside, static_cast<Index>(t.min_terms), t.failed_element, t.failed_points})
    w.i64(v);
  w.f64(t.max_condition);
  w.f64(t.failed_condition);
  return std::move(w.bytes());
}

void decode_totals(std::string_view bytes, TlsReport& t) {
  Reader r(bytes, "TLS totals");
  for (Index* v : {&t.elements, &t.active, &t.full, &t.reduced, &t.with_virtual, &t.with_neighbours,
                   &t.failed, &t.outside})
    *v = r.i64();
  t.min_terms = static_cast<int>(r.i64());
  t.failed_element = r.i64();
  t.failed_points = r.i64();
  t.max_condition = r.f64();
  t.failed_condition = r.f64();
}

std::string encode_totals(const MlsReport& t) {
  Writer w;
  for (Index v : {t.points, t.empty, t.ill_conditioned, t.singular, t.reduced, t.widened}) w.i64(v);
  w.f64(t.max_condition);
  w.f64(t.worst_x);
  w.f64(t.worst_y);
  return std::move(w.bytes());
}

void decode_totals(std::string_view bytes, MlsReport& t) {
  Reader r(bytes, "MLS totals");
  for (Index* v : {&t.points, &t.empty, &t.ill_conditioned, &t.singular, &t.reduced, &t.widened})
    *v = r.i64();
  t.max_condition = r.f64();
  t.worst_x = r.f64();
  t.worst_y = r.f64();
}

}  // namespace mpm::io
