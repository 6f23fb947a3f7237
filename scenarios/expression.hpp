#pragma once
// Scene parameters: a scene may declare "parameters" (names and numbers) and write any number as
// a string "=expression" of them — arithmetic (+ - * / ^, parentheses, unary minus), the
// constant pi, and sqrt, abs, exp, log, sin, cos, tan, asin, acos, atan, atan2(y, x), min, max
// — so that `--set /parameters/angle_deg=20` or `sweep --vary /parameters/angle_deg=10,20,30`
// moves every value that depends on it. Evaluated before the scene is read; an error names the
// JSON pointer of the value, the expression and what went wrong.
#include <nlohmann/json.hpp>

#include <map>
#include <string>

namespace palpable {

// Evaluates one expression (without the leading '='). Throws InputError naming `where`.
double evaluate_expression(const std::string& text, const std::map<std::string, double>& names,
                           const std::string& where);

// Replaces, in a scene document, every string value "=..." by its value, with the names of the
// document's "parameters" object (numbers, or expressions of the parameters before them in
// alphabetical order). Returns the document unchanged if it has no expression. `source` names the
// file in errors.
nlohmann::json expand_parameters(const nlohmann::json& document, const std::string& source);

}  // namespace palpable
