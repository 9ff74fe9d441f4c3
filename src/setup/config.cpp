#include "setup/config.hpp"

#include <fmt/format.h>

#include <toml++/toml.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "core/input_file.hpp"
#include "core/strings.hpp"
#include "core/types.hpp"

namespace mpm {

// ---------------------------------------------------------------------------------------------
// Formatting helpers
// ---------------------------------------------------------------------------------------------
namespace {

// Shortest text that reads back to the same double ("0.1", "1e-10", "-1").
std::string real_text(double v) {
  return fmt::format("{}", v);
}

// A TOML float literal: like real_text but always recognisably a float ("1.0", not "1").
std::string toml_float(double v) {
  std::string s = real_text(v);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // 'n': inf, nan
  return s;
}

// A TOML basic string, quoted and escaped.
std::string quote(std::string_view s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\b':
        out += "\\b";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\f':
        out += "\\f";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
          out += fmt::format("\\u{:04X}", static_cast<unsigned>(static_cast<unsigned char>(c)));
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

// Text safe inside a TOML comment (no line breaks or other control characters).
std::string comment_text(std::string s) {
  for (char& c : s) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  }
  return s;
}

std::string join(const std::vector<std::string>& items, std::string_view sep) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += sep;
    out += items[i];
  }
  return out;
}

// A --set argument's key or value without the blanks around it (line ends included).
std::string_view trim_blanks(std::string_view s) {
  return trim(s, " \t\r\n");
}

// What a TOML node holds, for "got ..." in type errors.
std::string describe(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string: {
      // (A long one by its start: a message is read, not scrolled.)
      const std::string& text = node.as_string()->get();
      if (text.size() <= 160) return "a string (" + quote(text) + ")";
      std::size_t cut = 120;
      while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
      return fmt::format("a string of {} characters ({}...)", text.size(),
                         quote(text.substr(0, cut)));
    }
    case toml::node_type::integer:
      return "an integer (" + std::to_string(node.as_integer()->get()) + ")";
    case toml::node_type::floating_point:
      return "a floating-point number (" + toml_float(node.as_floating_point()->get()) + ")";
    case toml::node_type::boolean:
      return std::string("a boolean (") + (node.as_boolean()->get() ? "true" : "false") + ")";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::table:
      return "a table";
    case toml::node_type::date:
      return "a date";
    case toml::node_type::time:
      return "a time";
    case toml::node_type::date_time:
      return "a date-time";
    case toml::node_type::none:
      break;
  }
  return "nothing";
}

std::string expected(KeyType type) {
  switch (type) {
    case KeyType::Integer:
      return "an integer";
    case KeyType::Real:
      return "a number";
    case KeyType::Boolean:
      return "a boolean (true or false)";
    case KeyType::String:
      return "a string";
    case KeyType::Expression:
      return "an expression (a string or a number)";
    case KeyType::RealVector:
      return "a number or an array of numbers (one per direction)";
    case KeyType::ExpressionVector:
      return "an expression or an array of expressions (one per component)";
  }
  return "?";
}

std::string value_text(const Value& v) {
  return std::visit(
      [](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, std::int64_t>) {
          return std::to_string(x);
        } else if constexpr (std::is_same_v<T, double>) {
          return toml_float(x);
        } else if constexpr (std::is_same_v<T, bool>) {
          return x ? "true" : "false";
        } else if constexpr (std::is_same_v<T, std::string>) {
          return quote(x);
        } else {
          std::vector<std::string> items;
          for (const auto& item : x) {
            if constexpr (std::is_same_v<std::decay_t<decltype(item)>, double>)
              items.push_back(toml_float(item));
            else
              items.push_back(quote(item));
          }
          return "[" + join(items, ", ") + "]";
        }
      },
      v);
}

bool in_range(const KeySpec& s, double v) {
  if (s.min && (s.min_exclusive ? !(v > *s.min) : !(v >= *s.min))) return false;
  if (s.max && (s.max_exclusive ? !(v < *s.max) : !(v <= *s.max))) return false;
  return true;
}

// "> 0", ">= 1", "<= 2", "[1, 5]", "(-1, 0.5)"; "" if unbounded.
std::string range_text(const KeySpec& s) {
  if (s.min && s.max) {
    return fmt::format("{}{}, {}{}", s.min_exclusive ? '(' : '[', real_text(*s.min),
                       real_text(*s.max), s.max_exclusive ? ')' : ']');
  }
  if (s.min) return (s.min_exclusive ? "> " : ">= ") + real_text(*s.min);
  if (s.max) return (s.max_exclusive ? "< " : "<= ") + real_text(*s.max);
  return "";
}

// Optimal-string-alignment distance (Levenshtein plus adjacent transpositions), so that
// "grdi" -> "grid" counts as one typo; limit + 1 when it exceeds limit. The distance is at least
// the difference of the lengths, so a key of a megabyte costs one comparison, not a table of
// its length times the candidate's.
std::size_t edit_distance(std::string_view a, std::string_view b, std::size_t limit) {
  const std::size_t n = a.size(), m = b.size();
  if ((n > m ? n - m : m - n) > limit) return limit + 1;
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return std::min(d[n][m], limit + 1);
}

// How many typos still count as "close": one for short words, up to three for long names.
std::size_t typo_budget(std::string_view word) {
  return word.size() < 4 ? 1 : (word.size() < 12 ? 2 : 3);
}

// The closest candidate within the typo budget, if any.
std::optional<std::string> closest(std::string_view word, const std::vector<std::string>& cands) {
  std::optional<std::string> best;
  std::size_t best_d = typo_budget(word) + 1;
  for (const std::string& c : cands) {
    const std::size_t d = edit_distance(word, c, best_d - 1);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

const std::string kConstants = "constants";

// Is `prefix` a section (or sub-section) of the schema, i.e. some key starts with "prefix."?
bool is_section(std::string_view prefix) {
  if (prefix.empty()) return true;  // the root
  if (prefix == kConstants) return true;
  return std::any_of(schema().begin(), schema().end(), [&](const KeySpec& k) {
    return k.name.size() > prefix.size() && k.name.starts_with(prefix) &&
           k.name[prefix.size()] == '.';
  });
}

// "; valid keys in [grid]: cells, max, min" for the innermost known section enclosing `name`,
// or the top-level keys and sections when there is none.
std::string valid_list(std::string_view name) {
  std::string parent(is_section(name) ? name : std::string_view{});
  if (parent.empty()) {
    // Innermost known section above `name`.
    std::string_view p = name;
    while (true) {
      const auto dot = p.rfind('.');
      if (dot == std::string_view::npos) break;
      p = p.substr(0, dot);
      if (is_section(p)) {
        parent = p;
        break;
      }
    }
  }
  std::set<std::string> keys, sections;
  const std::string prefix = parent.empty() ? "" : parent + ".";
  for (const KeySpec& k : schema()) {
    if (!k.name.starts_with(prefix)) continue;
    const std::string rest = k.name.substr(prefix.size());
    const auto dot = rest.find('.');
    if (dot == std::string::npos) {
      keys.insert(rest);
    } else {
      sections.insert(rest.substr(0, dot));
    }
  }
  if (parent.empty()) sections.insert(kConstants);
  const std::vector<std::string> key_list(keys.begin(), keys.end());
  const std::vector<std::string> section_list(sections.begin(), sections.end());
  if (parent.empty()) {
    return "; valid top-level keys: " + join(key_list, ", ") +
           "; valid sections: " + join(section_list, ", ");
  }
  std::string out = "; valid keys in [" + parent + "]: " + join(key_list, ", ");
  if (!section_list.empty()) out += "; sub-sections: " + join(section_list, ", ");
  return out;
}

// " (did you mean 'grid.cells'?)" or "".
std::string suggestion(std::string_view name) {
  std::vector<std::string> names;
  for (const KeySpec& k : schema()) names.push_back(k.name);
  if (auto best = closest(name, names)) return " (did you mean '" + *best + "'?)";

  // Right key, wrong or missing section ("grid.dt", "cells"): match on the last component.
  const auto dot = name.rfind('.');
  const std::string_view leaf = dot == std::string_view::npos ? name : name.substr(dot + 1);
  std::vector<std::string> same_leaf;
  for (const std::string& n : names) {
    const auto d = n.rfind('.');
    if ((d == std::string::npos ? std::string_view(n) : std::string_view(n).substr(d + 1)) ==
        leaf) {
      same_leaf.push_back(n);
    }
  }
  if (same_leaf.size() == 1) return " (did you mean '" + same_leaf.front() + "'?)";

  // A misspelt section: "constant.L", "[grdi]".
  const std::string_view first = name.substr(0, name.find('.'));
  if (!is_section(first)) {
    std::set<std::string> sections{kConstants};
    for (const KeySpec& k : schema()) {
      if (!k.section().empty()) sections.insert(k.section());
    }
    if (auto best = closest(first, {sections.begin(), sections.end()})) {
      return " (did you mean [" + *best + "]?)";
    }
  }
  return "";
}

// At most kShown characters of a name or value in a message, and how long it was.
constexpr std::size_t kShown = 200;
// "" for a text that is shown whole, else "... (N characters)" after its first kShown.
std::string cut_note(std::string_view s) {
  return s.size() <= kShown ? "" : "... (" + std::to_string(s.size()) + " characters)";
}
std::string shown(std::string_view s) {
  return std::string(s.substr(0, kShown)) + cut_note(s);
}

bool instance_name(std::string_view section, std::string_view name);

std::string unknown_key_message(std::string_view name) {
  // A key of a named instance ([material.NAME]) is suggested among its section's keys.
  const auto first = name.find('.');
  const auto second = first == std::string_view::npos ? first : name.find('.', first + 1);
  if (second != std::string_view::npos &&
      instance_name(name.substr(0, first), name.substr(first + 1, second - first - 1))) {
    const std::string as_section =
        std::string(name.substr(0, first)) + std::string(name.substr(second));
    std::string hint = suggestion(as_section);
    if (const auto at = hint.find("'" + std::string(name.substr(0, first)) + ".");
        at != std::string::npos)
      hint.insert(at + first + 2, std::string(name.substr(first + 1, second - first)));
    return "unknown key '" + shown(name) + "'" + hint + valid_list(name.substr(0, first));
  }
  return "unknown key '" + shown(name) + "'" + suggestion(name) + valid_list(name);
}

bool is_identifier(std::string_view s) {
  if (s.empty()) return false;
  auto alpha = [](char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; };
  if (!alpha(s.front())) return false;
  return std::all_of(s.begin(), s.end(),
                     [&](char c) { return alpha(c) || (c >= '0' && c <= '9'); });
}

// Sections that also hold named instances: [material.NAME] is a material of its own, with the
// keys of [material] (material/material_set.hpp: the run's materials; the bodies name theirs),
// and [body.NAME] a body besides [body], with its keys (benchmarks/body_set.hpp).
constexpr std::array<std::string_view, 2> kInstanced = {"material", "body"};

// Whether NAME of "SECTION.NAME" names an instance of SECTION: an identifier, not the section's
// own name, and neither a key nor a sub-section of it.
bool instance_name(std::string_view section, std::string_view name) {
  if (std::find(kInstanced.begin(), kInstanced.end(), section) == kInstanced.end()) return false;
  const std::string full = std::string(section) + "." + std::string(name);
  return is_identifier(name) && name != section && find_key(full) == nullptr && !is_section(full);
}

// The instance "SECTION.NAME" and the key of SECTION of a key "SECTION.NAME.KEY", if it is one.
std::optional<std::pair<std::string, std::string>> split_instance_key(std::string_view key) {
  const auto first = key.find('.');
  if (first == std::string_view::npos) return std::nullopt;
  const auto second = key.find('.', first + 1);
  if (second == std::string_view::npos) return std::nullopt;
  const std::string_view section = key.substr(0, first);
  if (!instance_name(section, key.substr(first + 1, second - first - 1))) return std::nullopt;
  return std::pair{std::string(key.substr(0, second)),
                   std::string(section) + std::string(key.substr(second))};
}

// The spec of "SECTION.KEY" named as `key` = "SECTION.NAME.KEY" of an instance, if it is one.
std::optional<KeySpec> instance_spec(std::string_view key) {
  const auto split = split_instance_key(key);
  if (!split) return std::nullopt;
  const KeySpec* spec = find_key(split->second);
  if (spec == nullptr) return std::nullopt;
  KeySpec out = *spec;
  out.name = std::string(key);
  return out;
}

std::string location(const std::string& file, const toml::source_region& r) {
  if (r.begin.line == 0) return file;
  return fmt::format("{}:{}:{}", file, r.begin.line, r.begin.column);
}

// toml++ parses dotted keys, table headers, inline tables and arrays recursively: a file nesting
// them some ten thousand levels deep overflowed the stack (a crash with no message). A
// configuration nests a few levels, so more than kMaxNesting is refused before parsing: key
// components (dots in a key or a header) and open brackets and braces, outside strings and
// comments. Returns the 1-based line of the first excess, 0 if none.
constexpr int kMaxNesting = 64;

int excessive_nesting_line(std::string_view text) {
  int line = 1, depth = 0, dots = 0;
  std::vector<char> open;  // the open brackets and braces, innermost last
  bool key = true;         // at a key: line start at depth 0, a header, after '{' or ',' in '{'
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      if (open.empty()) key = true, dots = 0;
    } else if (c == '#') {
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
    } else if (c == '"' || c == '\'') {
      // A string: basic ("..." with escapes) or literal ('...'), either possibly multi-line
      // (three quotes).
      const bool triple = text.substr(i, 3) == std::string(3, c);
      const std::string_view close = triple ? text.substr(i, 3) : text.substr(i, 1);
      i += close.size();
      while (i < text.size() && text.substr(i, close.size()) != close) {
        if (text[i] == '\n') ++line;
        if (c == '"' && text[i] == '\\') ++i;
        ++i;
      }
      i += close.size() - 1;
    } else if (c == '[' || c == '{') {
      open.push_back(c);
      depth = static_cast<int>(open.size());
      if (depth > kMaxNesting) return line;
      key = c == '{' || (c == '[' && open.size() <= 2 && key);  // a header keeps the key state
      dots = 0;
    } else if (c == ']' || c == '}') {
      if (!open.empty()) open.pop_back();
      key = false;
    } else if (c == ',' && !open.empty() && open.back() == '{') {
      key = true;
      dots = 0;
    } else if (c == '=') {
      key = false;
    } else if (c == '.' && key) {
      if (++dots >= kMaxNesting) return line;
    }
  }
  return 0;
}

void check_nesting(std::string_view text, const std::string& where) {
  if (const int line = excessive_nesting_line(text))
    throw InputError(fmt::format(
        "{}:{}: keys, tables or arrays nested more than {} levels deep; a configuration "
        "needs a few",
        shown(where), line, kMaxNesting));
}

// A --set value: TOML if it parses as one ("40", "1e-5", "true", "\"usl\""), else the bare text
// ("usl", "0.1*sin(pi*x)"). Returned as the single entry "v" of a table that owns it.
toml::table parse_value_text(const std::string& text, const std::string& origin) {
  check_nesting(text, origin);
  try {
    toml::table t = toml::parse("v = " + text);
    if (t.size() == 1 && t.contains("v")) return t;
  } catch (const toml::parse_error&) {
    // Not a TOML value: fall through to the bare string.
  }
  toml::table t;
  t.insert("v", text);
  return t;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Schema access
// ---------------------------------------------------------------------------------------------

std::string KeySpec::section() const {
  const auto dot = name.find('.');
  return dot == std::string::npos ? "" : name.substr(0, dot);
}

const KeySpec* find_key(std::string_view name) {
  for (const KeySpec& k : schema()) {
    if (k.name == name) return &k;
  }
  return nullptr;
}

std::string_view type_name(KeyType type) {
  switch (type) {
    case KeyType::Integer:
      return "integer";
    case KeyType::Real:
      return "real";
    case KeyType::Boolean:
      return "boolean";
    case KeyType::String:
      return "string";
    case KeyType::Expression:
      return "expression";
    case KeyType::RealVector:
      return "real[]";
    case KeyType::ExpressionVector:
      return "expression[]";
  }
  return "?";
}

void print_schema(std::ostream& os) {
  // Long choice lists wrap inside their column so the descriptions stay readable.
  constexpr std::size_t kAllowedWidth = 36;
  struct Row {
    std::string section;
    std::vector<std::string> cols;     // key, type, unit, default
    std::vector<std::string> allowed;  // one entry per printed line
    std::string description;
  };
  std::vector<Row> rows;
  for (const KeySpec& k : schema()) {
    Row r;
    r.section = k.section();
    r.cols = {k.name, std::string(type_name(k.type)), k.unit.empty() ? "-" : k.unit,
              k.default_value ? value_text(*k.default_value) : "required"};
    if (!k.choices.empty()) {
      std::string line;
      for (std::size_t i = 0; i < k.choices.size(); ++i) {
        const std::string item = k.choices[i] + (i + 1 < k.choices.size() ? "," : "");
        if (!line.empty() && line.size() + 1 + item.size() > kAllowedWidth) {
          r.allowed.push_back(line);
          line.clear();
        }
        line += (line.empty() ? "" : " ") + item;
      }
      r.allowed.push_back(line);
    } else {
      const std::string range = range_text(k);
      r.allowed.push_back(range.empty() ? "-" : range);
    }
    r.description = k.description;
    rows.push_back(std::move(r));
  }

  const std::vector<std::string> header = {"KEY", "TYPE", "UNIT", "DEFAULT", "ALLOWED"};
  std::vector<std::size_t> width(5);
  for (std::size_t c = 0; c < 4; ++c) width[c] = header[c].size();
  width[4] = header[4].size();
  for (const Row& r : rows) {
    for (std::size_t c = 0; c < 4; ++c) width[c] = std::max(width[c], r.cols[c].size());
    for (const std::string& a : r.allowed) width[4] = std::max(width[4], a.size());
  }
  auto print_line = [&](const std::vector<std::string>& cells, const std::string& last) {
    std::string line;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      line += cells[c];
      line += std::string(width[c] - cells[c].size() + 2, ' ');
    }
    line += last;
    line.erase(line.find_last_not_of(' ') + 1);  // no trailing blanks
    os << line << '\n';
  };

  print_line(header, "DESCRIPTION");
  std::string current = "\x01";  // no section printed yet
  for (const Row& r : rows) {
    if (r.section != current) {
      current = r.section;
      os << '\n' << (current.empty() ? std::string("(top level)") : "[" + current + "]") << '\n';
    }
    std::vector<std::string> cells = r.cols;
    cells.push_back(r.allowed.front());
    print_line(cells, r.description);
    for (std::size_t i = 1; i < r.allowed.size(); ++i) {
      print_line({"", "", "", "", r.allowed[i]}, "");
    }
  }
  os << "\n[constants]\n"
        "  User constants, NAME = number (e.g. L = 2.0), usable in every expression key. NAME is\n"
        "  an identifier other than x, y, z, t, pi, e and muparser's built-in names.\n"
        "\n[material.NAME]\n"
        "  A named material with the keys of [material] (e.g. [material.clay] model = ...),\n"
        "  for the bodies and mesh parts that name it (body.material, body.part_materials);\n"
        "  NAME is an identifier. The others take [material].\n"
        "\nExpressions use muparser syntax: variables x, y, z (position, m) and t (time, s),\n"
        "constants pi, e and the [constants]; functions sin, cos, tan, exp, ln, log10, sqrt,\n"
        "abs, sign, min, max, ...; operators + - * / ^ and the ternary c ? a : b.\n"
        "Example: velocity = \"v0*sin(pi*x/L)\". A plain number is accepted as well.\n"
        "\nAny key can be overridden on the command line: --set SECTION.KEY=VALUE, e.g.\n"
        "--set grid.cells=40 --set method.scheme=usl --set constants.L=2\n";
}

// ---------------------------------------------------------------------------------------------
// Parsing and checking
// ---------------------------------------------------------------------------------------------

// Fills a Config from TOML and overrides, collecting every problem (sorted by position) before
// throwing, so that the user can fix them all in one go.
class ConfigBuilder {
 public:
  explicit ConfigBuilder(Config& cfg) : cfg_(cfg) {}

  void from_table(const toml::table& table, const std::string& prefix) {
    for (auto&& [k, node] : table) {
      const std::string name =
          prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
      if (name == kConstants) {
        constants_table(node);
      } else if (const KeySpec* spec = find_key(name)) {
        assign(*spec, node, at(node.source()), position(node.source()));
      } else if (const auto instance = instance_spec(name)) {
        note_instance(split_instance_key(name)->first, at(node.source()));
        assign(*instance, node, at(node.source()), position(node.source()));
      } else if (const toml::table* sub = node.as_table();
                 sub && instance_name(prefix, std::string_view(k.str()))) {
        // [material.NAME]: a named material with the keys of [material].
        note_instance(name, at(k.source()));
        from_table(*sub, name);
      } else if (is_section(name)) {
        if (const toml::table* sub = node.as_table()) {
          from_table(*sub, name);
        } else {
          error(node.source(), "key '" + name + "' is a section, not a value; write it as [" +
                                   name + "]" + valid_list(name));
        }
      } else if (const toml::table* sub = node.as_table(); sub && !prefix.empty()) {
        error(k.source(), unknown_key_message(name));
      } else if (sub && !sub->empty()) {
        // Unknown section: report each key in it, with a suggestion for the whole name.
        for (auto&& entry : *sub) {
          const toml::key& child = entry.first;
          error(child.source(), unknown_key_message(name + "." + std::string(child.str())));
        }
      } else if (sub) {
        error(k.source(), "unknown section [" + name + "]" + suggestion(name) + valid_list(name));
      } else {
        error(k.source(), unknown_key_message(name));
      }
    }
  }

  void override_arg(const std::string& arg) {
    // The argument names itself in messages (and in where()); a long one only by its start.
    std::string shown = arg;
    if (arg.size() > 160) {
      std::size_t cut = 120;
      while (cut > 0 && (static_cast<unsigned char>(arg[cut]) & 0xC0) == 0x80) --cut;  // UTF-8
      shown = fmt::format("{}... ({} characters)", arg.substr(0, cut), arg.size());
    }
    const std::string origin = "--set " + shown;
    const auto eq = arg.find('=');
    if (eq == std::string::npos) {
      error_at(origin, kOverride, "expected KEY=VALUE (e.g. --set grid.cells=40), got no '='");
      return;
    }
    apply(trim_blanks(std::string_view(arg).substr(0, eq)),
          std::string(trim_blanks(std::string_view(arg).substr(eq + 1))), origin);
  }

  // One value from the command line or set(): `origin` stands in for FILE:LINE:COL.
  void apply(std::string_view key, const std::string& value, const std::string& origin) {
    const toml::table holder = parse_value_text(value, origin);
    const toml::node& node = *holder.get("v");
    if (key.starts_with(kConstants + ".")) {
      constant(key.substr(kConstants.size() + 1), node, origin, origin, kOverride);
    } else if (const KeySpec* spec = find_key(key)) {
      assign(*spec, node, origin, kOverride);
    } else if (const auto instance = instance_spec(key)) {
      note_instance(split_instance_key(key)->first, origin);
      assign(*instance, node, origin, kOverride);
    } else if (key == kConstants) {
      error_at(origin, kOverride, "set one constant at a time: constants.NAME=VALUE");
    } else {
      error_at(origin, kOverride, unknown_key_message(key));
    }
  }

  // Checks that need every value: expressions (they see the final constants) and, for a whole
  // configuration, the required keys. Throws the collected errors.
  void finish(bool check_required) {
    for (auto it = cfg_.values_.begin(); it != cfg_.values_.end(); ++it) {
      // (Defaults are valid expressions: only the given values are compiled.)
      const std::optional<KeySpec> instance =
          find_key(it->first) ? std::nullopt : instance_spec(it->first);
      const KeySpec* found = instance ? &*instance : find_key(it->first);
      if (found == nullptr) continue;
      const KeySpec& spec = *found;
      if (spec.type != KeyType::Expression && spec.type != KeyType::ExpressionVector) continue;
      std::vector<std::string> texts;
      if (const auto* list = std::get_if<std::vector<std::string>>(&it->second.value))
        texts = *list;
      else
        texts.push_back(std::get<std::string>(it->second.value));
      for (std::size_t k = 0; k < texts.size(); ++k) {
        try {
          Expression(texts[k], cfg_.constants_);
        } catch (const InputError& e) {
          const std::string which =
              texts.size() > 1 ? fmt::format(" (value {} of {})", k + 1, texts.size()) : "";
          error_at(it->second.origin, order_of(spec.name),
                   "key '" + spec.name + "'" + which + ": " + e.what());
        }
      }
    }
    if (check_required && errors_.empty()) {
      for (const KeySpec& spec : schema()) {
        if (spec.required() && !spec.required_when_read && !cfg_.values_.contains(spec.name)) {
          error_at(cfg_.source_, kRequired, missing_message(spec));
        }
      }
      // Each named instance has its section's required keys.
      for (const auto& [instance, origin] : cfg_.instances_) {
        const std::string section = instance.substr(0, instance.find('.'));
        for (const KeySpec& spec : schema()) {
          if (spec.section() != section || !spec.required() || spec.required_when_read) continue;
          KeySpec named = spec;
          named.name = instance + spec.name.substr(section.size());
          if (!cfg_.values_.contains(named.name))
            error_at(origin, kRequired, missing_message(named) + " (in [" + instance + "])");
        }
      }
    }
    if (errors_.empty()) return;
    std::stable_sort(errors_.begin(), errors_.end(),
                     [](const Error& a, const Error& b) { return a.order < b.order; });
    std::vector<std::string> lines;
    for (const Error& e : errors_) lines.push_back(e.text);
    throw InputError(join(lines, "\n"));
  }

  static std::string missing_message(const KeySpec& spec) {
    std::string what = spec.description;
    if (!spec.unit.empty()) what += " [" + spec.unit + "]";
    std::string msg = "required key '" + spec.name + "' (" + what + ") is missing";
    if (!spec.choices.empty()) msg += "; choose one of: " + join(spec.choices, ", ");
    return msg;
  }

 private:
  using Order = std::tuple<std::uint64_t, std::uint64_t>;  // (line, column), for sorting
  static constexpr std::uint64_t kLast = std::numeric_limits<std::uint64_t>::max();
  static constexpr Order kOverride{kLast - 1, 0};  // after everything from the file
  static constexpr Order kRequired{kLast, 0};

  struct Error {
    Order order;
    std::string text;
  };

  std::string at(const toml::source_region& r) const { return location(cfg_.source_, r); }

  // A named instance ("material.NAME") met first at `origin`.
  void note_instance(const std::string& instance, const std::string& origin) {
    cfg_.instances_.emplace(instance, origin);
  }

  // Sort position of a stored value: its place in the file, or after the file for --set.
  Order order_of(const std::string& key) const {
    const auto it = positions_.find(key);
    return it == positions_.end() ? kOverride : it->second;
  }

  static Order position(const toml::source_region& r) { return {r.begin.line, r.begin.column}; }

  void error(const toml::source_region& r, const std::string& msg) {
    errors_.push_back({position(r), at(r) + ": " + msg});
  }
  void error_at(const std::string& origin, Order order, const std::string& msg) {
    errors_.push_back({order, (origin.empty() ? "" : origin + ": ") + msg});
  }

  // Stores one value; `order` is its position in the file, or kOverride.
  void assign(const KeySpec& spec, const toml::node& node, const std::string& origin, Order order) {
    std::string problem;
    std::optional<Value> v = convert(spec, node, problem);
    if (!v) {
      error_at(origin, order, problem);
      return;
    }
    cfg_.values_[spec.name] = Config::Stored{std::move(*v), origin};
    positions_[spec.name] = order;
  }

  // The typed, checked value, or nullopt with `problem` set.
  static std::optional<Value> convert(const KeySpec& spec, const toml::node& node,
                                      std::string& problem) {
    const std::string key = "key '" + spec.name + "'";
    auto wrong_type = [&]() -> std::optional<Value> {
      problem = key + " expects " + expected(spec.type) + ", got " + describe(node);
      if (!spec.choices.empty()) problem += "; choose one of: " + join(spec.choices, ", ");
      return std::nullopt;
    };
    auto out_of_range = [&](const std::string& shown) -> std::optional<Value> {
      const std::string range = range_text(spec);
      problem = key + " = " + shown + " is out of range: must be " +
                (spec.min && spec.max ? "in " + range : range);
      return std::nullopt;
    };
    switch (spec.type) {
      case KeyType::Integer: {
        if (!node.is_integer()) return wrong_type();
        const std::int64_t v = node.as_integer()->get();
        if (!in_range(spec, static_cast<double>(v))) return out_of_range(std::to_string(v));
        return Value(v);
      }
      case KeyType::Real: {
        double v;
        if (node.is_integer()) {
          v = static_cast<double>(node.as_integer()->get());
        } else if (node.is_floating_point()) {
          v = node.as_floating_point()->get();
        } else {
          return wrong_type();
        }
        if (!std::isfinite(v)) {
          problem = key + " = " + real_text(v) + " is not a finite number";
          return std::nullopt;
        }
        if (!in_range(spec, v)) return out_of_range(real_text(v));
        return Value(v);
      }
      case KeyType::Boolean:
        if (!node.is_boolean()) return wrong_type();
        return Value(node.as_boolean()->get());
      case KeyType::String: {
        if (!node.is_string()) return wrong_type();
        std::string v = node.as_string()->get();
        if (!spec.choices.empty() &&
            std::find(spec.choices.begin(), spec.choices.end(), v) == spec.choices.end()) {
          problem = key + " = " + quote(std::string_view(v).substr(0, kShown)) + cut_note(v) +
                    " is not valid; choose one of: " + join(spec.choices, ", ");
          if (auto best = closest(v, spec.choices))
            problem += " (did you mean " + quote(*best) + "?)";
          return std::nullopt;
        }
        return Value(std::move(v));
      }
      case KeyType::Expression:
        // Compiled in finish(), once all constants are known.
        if (node.is_string()) return Value(node.as_string()->get());
        if (node.is_integer()) return Value(std::to_string(node.as_integer()->get()));
        if (node.is_floating_point() && std::isfinite(node.as_floating_point()->get())) {
          return Value(real_text(node.as_floating_point()->get()));
        }
        return wrong_type();
      case KeyType::RealVector:
      case KeyType::ExpressionVector: {
        const toml::array* array = node.as_array();
        if (!array) {
          // A single value: checked as the scalar type, stored as a scalar.
          KeySpec scalar = spec;
          scalar.type = spec.type == KeyType::RealVector ? KeyType::Real : KeyType::Expression;
          auto v = convert(scalar, node, problem);
          // A value of the wrong type: say that an array would also do.
          if (!v && problem.starts_with(key + " expects ")) return wrong_type();
          return v;
        }
        if (array->empty() || array->size() > 6) {
          problem = key + " expects " + expected(spec.type) + ": 1 to 6 values, got " +
                    std::to_string(array->size());
          return std::nullopt;
        }
        KeySpec element = spec;
        element.type = spec.type == KeyType::RealVector ? KeyType::Real : KeyType::Expression;
        std::vector<double> reals;
        std::vector<std::string> texts;
        for (std::size_t k = 0; k < array->size(); ++k) {
          std::string element_problem;
          auto v = convert(element, *array->get(k), element_problem);
          if (!v) {
            problem = fmt::format("{} (value {} of {})", element_problem, k + 1, array->size());
            return std::nullopt;
          }
          if (auto* r = std::get_if<double>(&*v)) reals.push_back(*r);
          if (auto* t = std::get_if<std::string>(&*v)) texts.push_back(std::move(*t));
        }
        if (spec.type == KeyType::RealVector) return Value(std::move(reals));
        return Value(std::move(texts));
      }
    }
    return wrong_type();
  }

  void constants_table(const toml::node& node) {
    const toml::table* table = node.as_table();
    if (!table) {
      error(node.source(), "key 'constants' must be a table of NAME = number, got " +
                               describe(node) + "; write [constants] followed by e.g. L = 2.0");
      return;
    }
    for (auto&& [k, value] : *table) {
      constant(k.str(), value, at(k.source()), at(value.source()), position(value.source()));
    }
  }

  void constant(std::string_view name_view, const toml::node& value, const std::string& name_origin,
                const std::string& value_origin, Order order) {
    const std::string name(name_view);
    if (!is_identifier(name)) {
      error_at(name_origin, order,
               "constant name '" + name +
                   "' is not a valid identifier (letters, digits and '_', not starting with a "
                   "digit)");
      return;
    }
    if (Expression::is_reserved_name(name)) {
      error_at(name_origin, order,
               "constant name '" + name +
                   "' is reserved (x, y, z, t, pi, e and muparser's built-in names cannot be "
                   "redefined)");
      return;
    }
    double v;
    if (value.is_integer()) {
      v = static_cast<double>(value.as_integer()->get());
    } else if (value.is_floating_point()) {
      v = value.as_floating_point()->get();
    } else {
      error_at(value_origin, order,
               "constant '" + name + "' must be a number, got " + describe(value));
      return;
    }
    if (!std::isfinite(v)) {
      error_at(value_origin, order,
               "constant '" + name + "' = " + real_text(v) + " is not a finite number");
      return;
    }
    cfg_.constants_[name] = v;
    cfg_.constant_origins_[name] = value_origin;
  }

  Config& cfg_;
  std::vector<Error> errors_;
  std::map<std::string, Order> positions_;
};

namespace {
// The bytes of a file the user named; `what` ("config", "batch") names it in the messages. A
// configuration or batch file of more than 64 MiB is no such file (a mistaken argument).
constexpr std::uint64_t kMaxInputBytes = std::uint64_t{64} << 20;
std::string read_input_file(const std::string& path, std::string_view what) {
  return mpm::read_input_file(path, fmt::format("{} file", what), kMaxInputBytes);
}
}  // namespace

Config Config::load(const std::string& path, const std::vector<std::string>& overrides) {
  return parse(read_input_file(path, "config"), path, overrides);
}

Config Config::parse(std::string_view toml_text, const std::string& source_name,
                     const std::vector<std::string>& overrides) {
  Config cfg;
  cfg.source_ = source_name;
  toml::table root;
  check_nesting(toml_text, source_name);
  try {
    root = toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    throw InputError(location(source_name, e.source()) +
                     ": TOML syntax error: " + std::string(e.description()));
  }
  ConfigBuilder b(cfg);
  b.from_table(root, "");
  for (const std::string& o : overrides) b.override_arg(o);
  b.finish(/*check_required=*/true);
  return cfg;
}

void Config::set(std::string_view key, const std::string& value_text, const std::string& origin) {
  // Work on a copy so that a rejected value leaves *this unchanged.
  Config next = *this;
  ConfigBuilder b(next);
  b.apply(trim_blanks(key), std::string(trim_blanks(value_text)), origin);
  b.finish(/*check_required=*/false);
  *this = std::move(next);
}

// ---------------------------------------------------------------------------------------------
// Access
// ---------------------------------------------------------------------------------------------
namespace {

// The key's spec (a key of a named instance, [material.NAME], as its section's, named in full).
KeySpec spec_or_throw(std::string_view key) {
  if (const KeySpec* spec = find_key(key)) return *spec;
  if (auto spec = instance_spec(key)) return std::move(*spec);
  throw std::logic_error("undeclared configuration key '" + std::string(key) + "'");
}

[[noreturn]] void wrong_accessor(const KeySpec& spec, std::string_view accessor) {
  throw std::logic_error("configuration key '" + spec.name + "' is of type " +
                         std::string(type_name(spec.type)) + ", read with " +
                         std::string(accessor));
}

}  // namespace

const Config::Stored* Config::stored(std::string_view key) const {
  const auto it = values_.find(key);
  return it == values_.end() ? nullptr : &it->second;
}

const Value& Config::value_of(const KeySpec& spec) const {
  if (const Stored* s = stored(spec.name)) return s->value;
  if (spec.default_value) return *spec.default_value;
  throw InputError((source_.empty() ? "" : source_ + ": ") + ConfigBuilder::missing_message(spec));
}

std::int64_t Config::get_int(std::string_view key) const {
  const KeySpec& spec = spec_or_throw(key);
  if (spec.type != KeyType::Integer) wrong_accessor(spec, "get_int");
  return std::get<std::int64_t>(value_of(spec));
}

double Config::get_real(std::string_view key) const {
  const KeySpec& spec = spec_or_throw(key);
  if (spec.type == KeyType::Integer) return static_cast<double>(get_int(key));
  if (spec.type == KeyType::RealVector) {
    const std::vector<double> v = get_reals(key);
    if (v.size() != 1)
      throw InputError(
          fmt::format("{}: key '{}' needs a single value here (this benchmark is "
                      "1D), got an array of {}",
                      where(key), spec.name, v.size()));
    return v[0];
  }
  if (spec.type != KeyType::Real) wrong_accessor(spec, "get_real");
  return std::get<double>(value_of(spec));
}

std::vector<double> Config::get_reals(std::string_view key) const {
  const KeySpec& spec = spec_or_throw(key);
  if (spec.type != KeyType::RealVector) wrong_accessor(spec, "get_reals");
  const Value& v = value_of(spec);
  if (const auto* list = std::get_if<std::vector<double>>(&v)) return *list;
  return {std::get<double>(v)};
}

std::vector<std::string> Config::get_expressions(std::string_view key) const {
  const KeySpec& spec = spec_or_throw(key);
  if (spec.type != KeyType::ExpressionVector) wrong_accessor(spec, "get_expressions");
  const Value& v = value_of(spec);
  if (const auto* list = std::get_if<std::vector<std::string>>(&v)) return *list;
  return {std::get<std::string>(v)};
}

bool Config::get_bool(std::string_view key) const {
  const KeySpec& spec = spec_or_throw(key);
  if (spec.type != KeyType::Boolean) wrong_accessor(spec, "get_bool");
  return std::get<bool>(value_of(spec));
}

std::string Config::get_string(std::string_view key) const {
  const KeySpec& spec = spec_or_throw(key);
  if (spec.type == KeyType::ExpressionVector) {
    const std::vector<std::string> v = get_expressions(key);
    if (v.size() != 1)
      throw InputError(
          fmt::format("{}: key '{}' needs a single expression here (this benchmark "
                      "is 1D), got an array of {}",
                      where(key), spec.name, v.size()));
    return v[0];
  }
  if (spec.type != KeyType::String && spec.type != KeyType::Expression) {
    wrong_accessor(spec, "get_string");
  }
  return std::get<std::string>(value_of(spec));
}

Expression Config::get_expression(std::string_view key) const {
  const KeySpec& spec = spec_or_throw(key);
  if (spec.type != KeyType::Expression && spec.type != KeyType::ExpressionVector)
    wrong_accessor(spec, "get_expression");
  try {
    return Expression(get_string(key), constants_);
  } catch (const InputError& e) {
    // Only reachable for a Config not built by parse()/set(), which validate expressions.
    throw InputError(where(key) + ": key '" + spec.name + "': " + e.what());
  }
}

std::vector<std::string> Config::instances(std::string_view section) const {
  std::vector<std::string> names;
  for (const auto& [instance, origin] : instances_)
    if (instance.size() > section.size() && instance.starts_with(section) &&
        instance[section.size()] == '.')
      names.push_back(instance.substr(section.size() + 1));
  return names;
}

std::string Config::instance_where(std::string_view section, std::string_view name) const {
  const auto it = instances_.find(std::string(section) + "." + std::string(name));
  if (it == instances_.end())
    throw std::logic_error("no instance [" + std::string(section) + "." + std::string(name) + "]");
  return it->second;
}

bool Config::is_set(std::string_view key) const {
  if (key.starts_with(kConstants + ".")) {
    return constants_.contains(std::string(key.substr(kConstants.size() + 1)));
  }
  spec_or_throw(key);
  return stored(key) != nullptr;
}

std::filesystem::path Config::file_path(std::string_view key) const {
  std::filesystem::path path(get_string(key));
  std::error_code ec;
  if (!path.empty() && path.is_relative() && std::filesystem::is_regular_file(source_, ec))
    path = std::filesystem::path(source_).parent_path() / path;
  return path;
}

bool Config::at_default(std::string_view key) const {
  const KeySpec& spec = spec_or_throw(key);
  const Stored* s = stored(key);
  return s == nullptr || (spec.default_value && s->value == *spec.default_value);
}

std::string Config::where(std::string_view key) const {
  if (key.starts_with(kConstants + ".")) {
    const auto it = constant_origins_.find(key.substr(kConstants.size() + 1));
    if (it == constant_origins_.end()) {
      throw std::logic_error("no constant '" + std::string(key) + "' in the configuration");
    }
    return it->second;
  }
  spec_or_throw(key);
  const Stored* s = stored(key);
  return s ? s->origin : "default";
}

std::string Config::to_toml() const {
  std::ostringstream os;
  os << "# Effective configuration" << (source_.empty() ? "" : " from " + comment_text(source_))
     << ": every key, defaults included.\n"
        "# Accepted as-is by `mpm run`; see `mpm keys` for the meaning of each key.\n";

  // Top-level keys must precede the first [section] header.
  std::vector<std::string> sections{""};
  for (const KeySpec& k : schema()) {
    if (std::find(sections.begin(), sections.end(), k.section()) == sections.end()) {
      sections.push_back(k.section());
    }
  }
  // Each section, and after it its named instances ([material.NAME]) with every key of it.
  std::vector<std::pair<std::string, std::string>> tables;  // (section, table name)
  for (const std::string& section : sections) {
    tables.emplace_back(section, section);
    for (const auto& [instance, origin] : instances_)
      if (instance.substr(0, instance.find('.')) == section) tables.emplace_back(section, instance);
  }
  for (const auto& [section, table] : tables) {
    struct Line {
      std::string assignment, comment;
    };
    std::vector<Line> lines;
    for (const KeySpec& k : schema()) {
      if (k.section() != section) continue;
      const std::string leaf = section.empty() ? k.name : k.name.substr(section.size() + 1);
      std::string comment = (k.unit.empty() ? "" : "[" + k.unit + "] ") + k.description;
      const Stored* s = stored(table.empty() ? k.name : table + "." + leaf);
      if (s) {
        comment += "; from " + s->origin;
        lines.push_back({leaf + " = " + value_text(s->value), comment});
      } else if (k.default_value) {
        comment += "; default";
        lines.push_back({leaf + " = " + value_text(*k.default_value), comment});
      } else {
        // Only possible for a Config not built by parse(); keep the output valid TOML.
        lines.push_back({"# " + leaf + " = (required, missing)", comment});
      }
    }
    if (!table.empty()) os << "\n[" << table << "]\n";
    std::size_t width = 0;
    for (const Line& l : lines) width = std::max(width, l.assignment.size());
    for (const Line& l : lines) {
      os << l.assignment << std::string(width - l.assignment.size(), ' ') << "  # "
         << comment_text(l.comment) << '\n';
    }
  }
  if (!constants_.empty()) {
    os << "\n[" << kConstants << "]\n";
    for (const auto& [name, value] : constants_) {
      os << name << " = " << toml_float(value) << "  # from "
         << comment_text(constant_origins_.at(name)) << '\n';
    }
  }
  return os.str();
}

std::vector<BatchRun> read_batch(const std::string& path) {
  const std::string text = read_input_file(path, "batch");
  check_nesting(text, path);
  toml::table root;
  std::error_code ec;
  try {
    root = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw InputError(location(path, e.source()) +
                     ": TOML syntax error: " + std::string(e.description()));
  }
  constexpr std::string_view kForm =
      "a batch file holds one [[run]] table per run, with config = \"FILE\", out = \"DIR\" "
      "and optionally set = [\"section.key=value\", ...]";
  for (auto&& [key, node] : root)
    if (key.str() != "run" || !node.is_array_of_tables())
      throw InputError(fmt::format("{}: '{}' is not a [[run]] table; {}",
                                   location(path, key.source()), key.str(), kForm));
  const toml::array* tables = root["run"].as_array();
  if (tables == nullptr || tables->empty())
    throw InputError(fmt::format("{}: no [[run]] table; {}", path, kForm));
  std::vector<BatchRun> runs;
  std::map<std::filesystem::path, std::size_t> outs;  // normalised out -> index in runs
  for (const toml::node& item : *tables) {
    const toml::table& t = *item.as_table();
    BatchRun r;
    r.where = location(path, t.source());
    for (auto&& [key, node] : t) {
      const std::string at = location(path, key.source());
      if (key.str() == "config" || key.str() == "out") {
        const auto* v = node.as_string();
        if (v == nullptr || v->get().empty())
          throw InputError(
              fmt::format("{}: {} must be a non-empty string (a {})", at, key.str(),
                          key.str() == "config" ? "configuration file" : "output directory"));
        (key.str() == "config" ? r.config : r.out) = v->get();
      } else if (key.str() == "set") {
        const auto* a = node.as_array();
        if (a == nullptr || !a->is_homogeneous(toml::node_type::string))
          throw InputError(fmt::format(
              "{}: set must be an array of strings \"section.key=value\" (as --set)", at));
        for (const toml::node& v : *a) r.sets.push_back(v.as_string()->get());
      } else {
        throw InputError(fmt::format(
            "{}: unknown key '{}' in [[run]]; valid keys: config, out, set", at, key.str()));
      }
    }
    if (r.config.empty() || r.out.empty())
      throw InputError(fmt::format("{}: this [[run]] has no {}; {}", r.where,
                                   r.config.empty() ? "config" : "out", kForm));
    // "runs/a", "runs/a/", "./runs/a" and "link/a" with link a symbolic link to runs are one
    // directory: the part of the path that exists is resolved (links followed), the rest
    // normalised.
    auto key = std::filesystem::absolute(r.out, ec).lexically_normal();
    if (!key.has_filename()) key = key.parent_path();
    if (auto resolved = std::filesystem::weakly_canonical(key, ec); !ec) {
      key = resolved.lexically_normal();
      if (!key.has_filename()) key = key.parent_path();
    }
    if (const auto [it, fresh] = outs.emplace(key, runs.size()); !fresh)
      throw InputError(
          fmt::format("{}: run {} writes to '{}', as run {} does ({}); give each run its own out",
                      r.where, runs.size() + 1, r.out, it->second + 1, runs[it->second].where));
    runs.push_back(std::move(r));
  }
  return runs;
}

}  // namespace mpm
