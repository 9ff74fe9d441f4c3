#pragma once
// Run configuration: a TOML file plus command-line overrides, checked against one declared schema
// (src/setup/keys.cpp). Every user mistake is reported as an InputError that names the file, line
// and column (or the --set argument) and says what would have been valid.
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "setup/expression.hpp"

namespace mpm {

// Expression: a muparser string of x, y, z, t and the constants (see Expression); a number is
// also accepted and stored as its text. RealVector and ExpressionVector: one value per direction
// (or per stress component), written as a TOML array (e.g. ["0", "-9.81"]) or, where one value
// is enough (1D), as a single value; arrays are stored as vectors, single values as scalars.
// The benchmark checks the length against its dimension (Config::where names the line).
enum class KeyType { Integer, Real, Boolean, String, Expression, RealVector, ExpressionVector };

using Value = std::variant<std::int64_t, double, bool, std::string, std::vector<double>,
                           std::vector<std::string>>;

struct KeySpec {
  std::string name;  // dotted: "grid.cells"; no dot for top-level keys ("benchmark")
  KeyType type = KeyType::Real;
  std::string unit;                    // "m", "s", "Pa", "kg/m^3", ...; "" if dimensionless
  std::optional<Value> default_value;  // nullopt = required
  std::optional<double> min, max;      // numeric keys only
  bool min_exclusive = false, max_exclusive = false;
  std::vector<std::string> choices;  // String keys with a fixed set of values
  std::string description;           // one line
  // A key without default that only some runs need (a law's parameter): reported missing when
  // it is read, not whenever a configuration lacks it.
  bool required_when_read = false;

  std::string section() const;  // "grid" for "grid.cells", "" for top-level keys
  bool required() const { return !default_value.has_value(); }
};

// The single declaration of every key (keys.cpp), in declaration order.
const std::vector<KeySpec>& schema();
// nullptr if `name` is not a declared key.
const KeySpec* find_key(std::string_view name);
// What `mpm keys` prints: grouped by section, aligned columns (key, type, unit, default or
// "required", range or choices, description), followed by notes on [constants] and expressions.
void print_schema(std::ostream& os);
// "integer", "real", "boolean", "string", "expression".
std::string_view type_name(KeyType type);

class Config {
 public:
  // Empty configuration: every key at its default (required keys are missing), source "".
  Config() = default;

  // Parse a TOML file, then apply overrides "section.key=value" (from --set) in order. All
  // problems found are reported together, one per line, in a single InputError.
  static Config load(const std::string& path, const std::vector<std::string>& overrides = {});
  static Config parse(std::string_view toml_text, const std::string& source_name,
                      const std::vector<std::string>& overrides = {});

  // Typed access. Unset keys give their default; a required key that is missing throws
  // InputError naming the key. Asking for an undeclared key, or with the wrong accessor for the
  // key's type, is a programming error (std::logic_error).
  std::int64_t get_int(std::string_view key) const;
  double get_real(std::string_view key) const;  // also for Integer keys
  bool get_bool(std::string_view key) const;
  std::string get_string(std::string_view key) const;  // String and Expression keys
  // An Expression key compiled with the [constants] table (already validated when loaded).
  Expression get_expression(std::string_view key) const;
  // RealVector / ExpressionVector keys: every value (a single value gives one). get_real and
  // get_string also read these keys when they hold one value, and otherwise throw InputError
  // naming the key and its line.
  std::vector<double> get_reals(std::string_view key) const;
  std::vector<std::string> get_expressions(std::string_view key) const;

  // The names of the named instances of `section` ([material.NAME]: a material of its own with
  // the keys of [material], read as "material.NAME.density" ...), in alphabetical order.
  std::vector<std::string> instances(std::string_view section) const;
  // Where the instance [section.name] was given first (its table, or a --set of one of its keys).
  std::string instance_where(std::string_view section, std::string_view name) const;

  // Given in the file or by --set / set(). Also accepts "constants.NAME".
  bool is_set(std::string_view key) const;
  // Not given, or given with its default value (a stored config.toml gives every key).
  bool at_default(std::string_view key) const;
  // A String key that names a file (grid.mesh): a relative path is taken from the directory of
  // the configuration file, or from the working directory when the configuration is not a file
  // (a checkpoint's stored configuration, a text parsed in a test).
  std::filesystem::path file_path(std::string_view key) const;
  // "file.toml:12:7", "--set grid.cells=10", or "default"; for later validation messages
  // (e.g. "file.toml:4:9: grid.max must be above grid.min"). Also accepts "constants.NAME".
  std::string where(std::string_view key) const;

  // Same rules as --set ("constants.NAME" included); `origin` replaces FILE:LINE:COL in messages
  // and is what where() returns afterwards. On error the configuration is left unchanged.
  void set(std::string_view key, const std::string& value_text, const std::string& origin);

  const std::map<std::string, double>& constants() const { return constants_; }
  const std::string& source() const { return source_; }

  // The effective configuration: every key (defaults included) and the constants, as valid TOML
  // that parse() accepts and that gives back the same values. Comments give each key's unit,
  // description and where its value came from.
  std::string to_toml() const;

 private:
  struct Stored {
    Value value;
    std::string origin;  // as returned by where()
  };

  const Stored* stored(std::string_view key) const;
  const Value& value_of(const KeySpec& spec) const;

  std::map<std::string, Stored, std::less<>> values_;
  std::map<std::string, double> constants_;
  // Named instances ("material.NAME") and where each was given first.
  std::map<std::string, std::string, std::less<>> instances_;
  std::map<std::string, std::string, std::less<>> constant_origins_;
  std::string source_;

  friend class ConfigBuilder;  // config.cpp: parsing and checking
};

// `mpm run --batch FILE`: several runs in one start of the program, so that a series of short
// distributed runs pays for one mpirun and one MPI_Init (about 0.5 s for 4 processes on a 2-core
// machine, most of a short run). FILE is TOML with one [[run]] table per run:
//   [[run]]
//   config = "examples/vortex_2d.toml"   # required, as CONFIG of `mpm run`
//   out = "runs/vortex_16"               # required, as --out
//   set = ["grid.cells=16"]              # optional, as --set, in order
// Relative paths are taken from the working directory, as on the command line. Each run's
// configuration is loaded (and checked) when its turn comes; read_batch checks the file itself:
// its syntax, the keys and types above, and that no two runs write to one directory.
struct BatchRun {
  std::string config, out;
  std::vector<std::string> sets;
  std::string where;  // "FILE:LINE:COL" of the run's table, for messages
};
std::vector<BatchRun> read_batch(const std::string& path);

}  // namespace mpm
