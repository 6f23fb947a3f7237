#include "scenarios/expression.hpp"
#include "scenarios/json_reader.hpp"

#include "core/check.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <functional>

namespace palpable {
namespace {

using nlohmann::json;

constexpr double kPi = 3.14159265358979323846;
// Deepest nesting of parentheses, function calls, signs and powers in one expression: each level
// is a few frames of the recursive descent, so "((((..." a million deep would overflow the stack.
constexpr int kMaxExpressionDepth = 256;

// Recursive descent over: expr = term (('+'|'-') term)*; term = power (('*'|'/') power)*;
// power = unary ('^' power)?; unary = '-' unary | primary; primary = number | name | name '('
// args ')' | '(' expr ')'.
class Parser {
 public:
  Parser(const std::string& text, const std::map<std::string, double>& names,
         const std::string& where)
      : text_(text), names_(names), where_(where) {}

  double parse() {
    const double x = expr();
    skip();
    if (pos_ != text_.size()) fail("unexpected \"" + shorten(text_.substr(pos_)) + "\"");
    if (!std::isfinite(x)) fail("the value is not finite");
    return x;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(where_, "in \"=" + shorten(text_) + "\": " + what);
  }
  // Text for a message, cut at 60 characters (an expression may be megabytes long).
  static std::string shorten(const std::string& text) {
    return text.size() > 60 ? text.substr(0, 57) + "..." : text;
  }
  void skip() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool eat(char c) {
    skip();
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  double expr() {
    double x = term();
    for (;;) {
      if (eat('+')) {
        x += term();
      } else if (eat('-')) {
        x -= term();
      } else {
        return x;
      }
    }
  }
  double term() {
    double x = power();
    for (;;) {
      if (eat('*')) {
        x *= power();
      } else if (eat('/')) {
        x /= power();
      } else {
        return x;
      }
    }
  }
  // Counts the recursion levels of the descent while one is open.
  struct Level {
    explicit Level(Parser& p) : parser(p) {
      if (++parser.depth_ > kMaxExpressionDepth) {
        parser.fail("nested deeper than " + std::to_string(kMaxExpressionDepth) + " levels");
      }
    }
    ~Level() { --parser.depth_; }
    Parser& parser;
  };
  double power() {
    const double base = unary();
    if (eat('^')) {
      Level level(*this);
      return std::pow(base, power());
    }
    return base;
  }
  double unary() {
    if (eat('-')) {
      Level level(*this);
      return -unary();
    }
    if (eat('+')) {
      Level level(*this);
      return unary();
    }
    return primary();
  }
  double primary() {
    skip();
    if (eat('(')) {
      Level level(*this);
      const double x = expr();
      if (!eat(')')) fail("missing \")\"");
      return x;
    }
    if (pos_ < text_.size() &&
        (std::isdigit(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '.')) {
      // strtod reads the number in place (stod on the rest of the text copied it for every
      // number: quadratic in a long expression); out of range is malformed, as stod had it.
      const char* start = text_.c_str() + pos_;
      char* end = nullptr;
      errno = 0;
      const double x = std::strtod(start, &end);
      if (end == start || errno == ERANGE) fail("a malformed number");
      pos_ += static_cast<std::size_t>(end - start);
      return x;
    }
    std::string name;
    while (pos_ < text_.size() &&
           (std::isalnum(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '_')) {
      name += text_[pos_++];
    }
    if (name.empty())
      fail(pos_ < text_.size() ? "unexpected \"" + shorten(text_.substr(pos_)) + "\""
                               : "an expression ends too early");
    if (eat('(')) {
      Level level(*this);
      std::vector<double> args{expr()};
      while (eat(',')) args.push_back(expr());
      if (!eat(')')) fail("missing \")\" after the arguments of " + name);
      return call(name, args);
    }
    if (name == "pi") return kPi;
    auto it = names_.find(name);
    if (it == names_.end()) fail("unknown name \"" + name + "\" (not a parameter)");
    return it->second;
  }
  double call(const std::string& name, const std::vector<double>& a) {
    static const std::map<std::string, std::function<double(double)>> one = {
        {"sqrt", [](double x) { return std::sqrt(x); }},
        {"abs", [](double x) { return std::abs(x); }},
        {"exp", [](double x) { return std::exp(x); }},
        {"log", [](double x) { return std::log(x); }},
        {"sin", [](double x) { return std::sin(x); }},
        {"cos", [](double x) { return std::cos(x); }},
        {"tan", [](double x) { return std::tan(x); }},
        {"asin", [](double x) { return std::asin(x); }},
        {"acos", [](double x) { return std::acos(x); }},
        {"atan", [](double x) { return std::atan(x); }},
    };
    if (auto it = one.find(name); it != one.end()) {
      if (a.size() != 1) fail(name + " takes one argument");
      return it->second(a[0]);
    }
    if (name == "atan2" || name == "min" || name == "max") {
      if (a.size() != 2) fail(name + " takes two arguments");
      if (name == "atan2") return std::atan2(a[0], a[1]);
      return name == "min" ? std::min(a[0], a[1]) : std::max(a[0], a[1]);
    }
    fail("unknown function \"" + name + "\"");
  }

  const std::string& text_;
  const std::map<std::string, double>& names_;
  const std::string& where_;
  std::size_t pos_ = 0;
  int depth_ = 0;
};

void expand(json& value, const std::map<std::string, double>& names, const std::string& pointer,
            const std::string& source, int depth) {
  if (depth > 64) throw InputError(source + ":" + pointer, "nested too deep for parameters");
  if (value.is_string()) {
    const std::string& text = value.get_ref<const std::string&>();
    if (!text.empty() && text[0] == '=') {
      value = evaluate_expression(text.substr(1), names, source + ":" + pointer);
    }
  } else if (value.is_array()) {
    for (std::size_t i = 0; i < value.size(); ++i) {
      expand(value[i], names, pointer + "/" + std::to_string(i), source, depth + 1);
    }
  } else if (value.is_object()) {
    for (auto it = value.begin(); it != value.end(); ++it) {
      if (depth == 0 && (it.key() == "parameters" || it.key() == "description")) continue;
      expand(it.value(), names, pointer + "/" + it.key(), source, depth + 1);
    }
  }
}

}  // namespace

double evaluate_expression(const std::string& text, const std::map<std::string, double>& names,
                           const std::string& where) {
  return Parser(text, names, where).parse();
}

json expand_parameters(const json& document, const std::string& source) {
  if (!document.is_object()) return document;
  std::map<std::string, double> names;
  json out = document;
  if (auto p = out.find("parameters"); p != out.end()) {
    if (!p->is_object()) {
      throw InputError(source + ":/parameters",
                       "got " + describe_json(*p) + ", expected an object of named numbers");
    }
    for (auto it = p->begin(); it != p->end(); ++it) {
      const std::string where = source + ":/parameters/" + it.key();
      if (it.key().empty() || it.key() == "pi" ||
          !std::isalpha(static_cast<unsigned char>(it.key()[0]))) {
        throw InputError(where, "a parameter name starts with a letter and is not \"pi\"");
      }
      for (char c : it.key()) {
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') {
          throw InputError(where, "a parameter name holds letters, digits and _ only");
        }
      }
      if (it->is_number()) {
        const double x = it->get<double>();
        if (!std::isfinite(x)) throw InputError(where, "expected a finite number");
        names[it.key()] = x;
      } else if (it->is_string() && !it->get<std::string>().empty() &&
                 it->get<std::string>()[0] == '=') {
        names[it.key()] = evaluate_expression(it->get<std::string>().substr(1), names, where);
        *it = names[it.key()];
      } else {
        throw InputError(where,
                         "got " + describe_json(*it) + ", expected a number or \"=expression\"");
      }
    }
  }
  expand(out, names, "", source, 0);
  return out;
}

}  // namespace palpable
