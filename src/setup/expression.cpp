#include "setup/expression.hpp"

#include <muParser.h>

#include <cmath>
#include <numbers>
#include <string_view>
#include <utility>

#include "core/types.hpp"

namespace mpm {

struct Expression::State {
  mu::Parser parser;
  // Variable storage: mu::Parser::DefineVar keeps these addresses, so this block must not move
  // while the parser lives (it is heap-allocated and owned through a unique_ptr).
  double x = 0, y = 0, z = 0, t = 0;
};

Expression::Expression() : Expression("0", {}) {}

Expression::Expression(const std::string& text, const std::map<std::string, double>& constants)
    : text_(text), constants_(constants) {
  compile();
}

Expression::Expression(const Expression& other) : text_(other.text_), constants_(other.constants_) {
  // Rebuild rather than copy mu::Parser: a copied parser would still point at the other
  // object's variables.
  compile();
}

Expression::Expression(Expression&& other) noexcept = default;

Expression& Expression::operator=(const Expression& other) {
  if (this != &other) {
    Expression copy(other);
    *this = std::move(copy);
  }
  return *this;
}

Expression& Expression::operator=(Expression&& other) noexcept = default;

Expression::~Expression() = default;

void Expression::compile() {
  auto state = std::make_unique<State>();
  mu::Parser& p = state->parser;
  try {
    p.DefineVar("x", &state->x);
    p.DefineVar("y", &state->y);
    p.DefineVar("z", &state->z);
    p.DefineVar("t", &state->t);
    p.DefineConst("pi", std::numbers::pi);
    p.DefineConst("e", std::numbers::e);
    for (const auto& [name, value] : constants_) p.DefineConst(name, value);
    // muparser's '=' assigns to a variable ("x = 5" evaluates to 5 and changes x): an
    // expression is a value, so any '=' that is not part of ==, <=, >= or != is refused.
    for (std::size_t i = 0; i < text_.size(); ++i) {
      if (text_[i] != '=') continue;
      const bool comparison =
          (i > 0 && std::string_view("=<>!").find(text_[i - 1]) != std::string_view::npos) ||
          (i + 1 < text_.size() && text_[i + 1] == '=');
      if (!comparison)
        throw InputError("invalid expression \"" + text_ +
                         "\": an assignment ('=') where a value is expected (compare with ==)");
    }
    p.SetExpr(text_);
    // Eval() parses the whole expression (syntax, unknown names); muparser accepts a
    // comma-separated list of results, which makes no sense for a scalar field.
    p.Eval();
    if (p.GetNumResults() != 1) {
      throw InputError("invalid expression \"" + text_ + "\": expected a single value, got " +
                       std::to_string(p.GetNumResults()) + " comma-separated values");
    }
    const mu::varmap_type& used = p.GetUsedVar();
    uses_position_ = used.count("x") + used.count("y") + used.count("z") > 0;
    uses_time_ = used.count("t") > 0;
  } catch (const mu::Parser::exception_type& e) {
    std::string msg = "invalid expression \"" + text_ + "\": " + e.GetMsg();
    if (e.GetCode() == mu::ecUNASSIGNABLE_TOKEN) {
      // Usually a misspelt or undefined name: say which names exist.
      std::string names = "x, y, z, t, pi, e";
      for (const auto& c : constants_) names += ", " + c.first;
      msg += " (names available: " + names + " and muparser's functions such as sin, exp, sqrt)";
    }
    throw InputError(msg);
  }
  state_ = std::move(state);
}

double Expression::operator()(double x, double y, double z, double t) const {
  State& s = *state_;
  s.x = x;
  s.y = y;
  s.z = z;
  s.t = t;
  return s.parser.Eval();
}

bool Expression::is_reserved_name(const std::string& name) {
  if (name == "x" || name == "y" || name == "z" || name == "t" || name == "pi" || name == "e") {
    return true;
  }
  // Ask muparser for its own built-ins rather than keeping a copy of the list here.
  static const mu::Parser plain;
  return plain.GetFunDef().count(name) > 0 || plain.GetConst().count(name) > 0;
}

}  // namespace mpm
