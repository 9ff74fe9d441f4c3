// libFuzzer target for the configuration loader and expressions (scripts/fuzz.sh runs it).
//
// An input is a TOML configuration given to Config::parse. Invalid input must be reported as an
// InputError; any other exception, a crash or a sanitizer report is a bug. A configuration that
// loads has every expression-valued key compiled and evaluated, and its to_toml() must load again
// with the same values. Inputs starting with '!' go to Expression directly instead (the rest of
// the input is the expression text, with a few constants defined).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <string>
#include <string_view>

#include "core/types.hpp"
#include "setup/config.hpp"
#include "setup/expression.hpp"

namespace {

[[noreturn]] void bug(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_config: %s: %s\n", what, detail.c_str());
  std::abort();
}

void evaluate(const mpm::Expression& e) {
  const double points[] = {0.0, -1.0, 0.5, 1e300, -1e-300, NAN};
  double sum = 0;
  for (double x : points) sum += e(x, x, x, -x);
  (void)sum;  // any value (NaN, Inf) is fine; only crashes and non-InputError throws are bugs
}

void fuzz_expression(std::string_view text) {
  static const std::map<std::string, double> constants{{"L", 2.0}, {"v0", 0.1}, {"c_1", -3.5}};
  try {
    const mpm::Expression e{std::string(text), constants};
    evaluate(e);
    mpm::Expression copy = e;  // copies rebuild the parser
    evaluate(copy);
  } catch (const mpm::InputError&) {
  }
}

void fuzz_config(std::string_view text) {
  mpm::Config cfg;
  try {
    cfg = mpm::Config::parse(text, "<fuzz>");
  } catch (const mpm::InputError&) {
    return;
  }
  for (const mpm::KeySpec& spec : mpm::schema()) {
    if (spec.type == mpm::KeyType::Expression) evaluate(cfg.get_expression(spec.name));
    if (spec.type == mpm::KeyType::ExpressionVector)
      for (const std::string& text : cfg.get_expressions(spec.name))
        evaluate(mpm::Expression(text, cfg.constants()));
    (void)cfg.where(spec.name);
  }
  // The written-back configuration must load again and give the same values.
  const std::string written = cfg.to_toml();
  mpm::Config again;
  try {
    again = mpm::Config::parse(written, "<fuzz:to_toml>");
  } catch (const mpm::InputError& e) {
    bug("to_toml() output does not load", std::string(e.what()) + "\n" + written);
  }
  for (const mpm::KeySpec& spec : mpm::schema()) {
    // A key required only by what reads it (a law's parameter), not given: no value on either
    // side, and none written back.
    if (spec.required_when_read && spec.required() && !cfg.is_set(spec.name)) {
      if (again.is_set(spec.name)) bug("to_toml() writes a key that was not given", spec.name);
      continue;
    }
    bool same = true;
    switch (spec.type) {
      case mpm::KeyType::Integer:
        same = cfg.get_int(spec.name) == again.get_int(spec.name);
        break;
      case mpm::KeyType::Real:
        same = cfg.get_real(spec.name) == again.get_real(spec.name);
        break;
      case mpm::KeyType::Boolean:
        same = cfg.get_bool(spec.name) == again.get_bool(spec.name);
        break;
      case mpm::KeyType::String:
      case mpm::KeyType::Expression:
        same = cfg.get_string(spec.name) == again.get_string(spec.name);
        break;
      case mpm::KeyType::RealVector:
        same = cfg.get_reals(spec.name) == again.get_reals(spec.name);
        break;
      case mpm::KeyType::ExpressionVector:
        same = cfg.get_expressions(spec.name) == again.get_expressions(spec.name);
        break;
    }
    if (!same) bug("to_toml() changes a value", spec.name + "\n" + written);
  }
  if (cfg.constants() != again.constants()) bug("to_toml() changes the constants", written);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    if (!text.empty() && text.front() == '!') {
      fuzz_expression(text.substr(1));
    } else {
      fuzz_config(text);
    }
  } catch (const mpm::InputError& e) {
    bug("InputError escaped where none was expected", e.what());
  } catch (const std::exception& e) {
    bug("exception other than mpm::InputError", e.what());
  } catch (...) {
    bug("exception other than mpm::InputError", "(not a std::exception)");
  }
  return 0;
}
