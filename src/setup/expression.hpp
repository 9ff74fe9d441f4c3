#pragma once
// A user-supplied scalar expression of position and time, e.g. "v0*sin(pi*x/L)", evaluated with
// muparser. Used for initial fields, body forces and any other config key of type Expression.
#include <map>
#include <memory>
#include <string>

namespace mpm {

// Wraps mu::Parser. Variables: x, y, z (position, m) and t (time, s). Constants: pi, e and the
// user constants of the [constants] table. Functions: muparser's built-ins (sin, cos, tan, asin,
// acos, atan, sinh, cosh, tanh, exp, ln, log, log10, log2, sqrt, abs, sign, rint, min, max, sum,
// avg) and the operators + - * / ^, comparisons, && || and the ternary ?:.
//
// NOT thread-safe: evaluation writes the variables into storage shared by one parser, so give
// each thread its own copy. Copies are independent (the parser is rebuilt, since mu::Parser keeps
// raw pointers to the variables).
class Expression {
 public:
  // The constant expression "0".
  Expression();
  // Compiles `text`; throws InputError("invalid expression \"TEXT\": <muparser message>").
  Expression(const std::string& text, const std::map<std::string, double>& constants);
  Expression(const Expression& other);
  Expression(Expression&& other) noexcept;
  Expression& operator=(const Expression& other);
  Expression& operator=(Expression&& other) noexcept;
  ~Expression();

  double operator()(double x, double y = 0, double z = 0, double t = 0) const;

  bool uses_position() const { return uses_position_; }  // x, y or z appears
  bool uses_time() const { return uses_time_; }          // t appears
  bool is_constant() const { return !uses_position_ && !uses_time_; }
  const std::string& text() const { return text_; }
  const std::map<std::string, double>& constants() const { return constants_; }

  // Names that cannot be user constants: the variables, pi and e, and muparser's built-in
  // functions and constants (a constant of that name would be shadowed or rejected).
  static bool is_reserved_name(const std::string& name);

 private:
  struct State;  // mu::Parser plus the variable storage it points to; on the heap so that a
                 // move keeps those pointers valid.
  void compile();

  std::string text_;
  std::map<std::string, double> constants_;
  std::unique_ptr<State> state_;
  bool uses_position_ = false;
  bool uses_time_ = false;
};

}  // namespace mpm
