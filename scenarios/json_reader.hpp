#pragma once
// The one reader of Palpable's JSON inputs — scenes, references, impact specs, plot parameters:
// it walks a document keeping the JSON pointer of every value it reads, so that each error names
// the file (or option), the pointer, the value found and what was expected:
//   scene.json:/bodies/2/shape/radius: got -1, expected a positive number
#include "core/check.hpp"
#include "core/types.hpp"

#include <nlohmann/json.hpp>

#include <set>
#include <string>

namespace palpable {

class JsonReader {
 public:
  // `source` prefixes every error's location: a file name ("scene.json", then ":" + pointer) or
  // an option ("--param").
  explicit JsonReader(std::string source, std::string separator = ":")
      : source_(std::move(source)), separator_(std::move(separator)) {}

  // True for an error this reader raised (it already names the JSON path).
  bool is_ours(const InputError& e) const;

  [[noreturn]] void fail(const std::string& path, const std::string& message) const;
  [[noreturn]] void fail_value(const std::string& path, const nlohmann::json& value,
                               const std::string& expected) const;

  const nlohmann::json& object(const nlohmann::json& value, const std::string& path) const;
  // Rejects keys not in `allowed` (typos would otherwise be silently ignored).
  void only_keys(const nlohmann::json& obj, const std::string& path,
                 const std::set<std::string>& allowed) const;
  const nlohmann::json& required(const nlohmann::json& obj, const std::string& path,
                                 const std::string& key) const;

  double number(const nlohmann::json& value, const std::string& path) const;
  double positive(const nlohmann::json& value, const std::string& path) const;
  double non_negative(const nlohmann::json& value, const std::string& path) const;
  bool boolean(const nlohmann::json& value, const std::string& path) const;
  std::string string(const nlohmann::json& value, const std::string& path) const;
  Vec3 vec3(const nlohmann::json& value, const std::string& path) const;
  // A non-zero 3-vector, normalised (a direction).
  Vec3 direction(const nlohmann::json& value, const std::string& path) const;
  Quat quaternion(const nlohmann::json& value, const std::string& path) const;

 private:
  std::string source_;
  std::string separator_;
};

// The limits of every JSON input: nesting depth and size. Deeper documents are rejected before
// they are built (a 100,000-deep one crashed the formatter and the copies that follow parsing).
inline constexpr int kMaxJsonDepth = 256;
inline constexpr std::size_t kMaxJsonBytes = std::size_t{1} << 30;  // 1 GiB

// Parses user JSON text: syntax errors, numbers out of range of a double (1e999), documents
// nested deeper than kMaxJsonDepth or larger than kMaxJsonBytes all throw InputError naming
// `where` (a file, or an option).
nlohmann::json parse_json_text(const std::string& text, const std::string& where);

// True if `text` is well-formed UTF-8 (no overlong forms, surrogates or code points past U+10FFFF).
bool is_valid_utf8(const std::string& text);

// A value given on the command line (--set, --param, --vary): JSON, or a bare word — text that is
// not JSON and starts with a letter, '_' or '=' (an expression) — taken as a string. JSON that is
// out of range (1e999) or too deep is an InputError naming `where`, not a word.
nlohmann::json parse_command_line_value(const std::string& text, const std::string& where);

// A JSON value for an error message: its text, cut at 60 characters.
std::string describe_json(const nlohmann::json& value);

}  // namespace palpable
