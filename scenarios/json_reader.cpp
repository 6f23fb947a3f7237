#include "scenarios/json_reader.hpp"

#include "core/check.hpp"

#include <cctype>
#include <cmath>
#include <cstdint>

namespace palpable {

using nlohmann::json;

json parse_json_text(const std::string& text, const std::string& where) {
  if (text.size() > kMaxJsonBytes) {
    throw InputError(where, "larger than " + std::to_string(kMaxJsonBytes) + " bytes");
  }
  // Depth is checked as the parser enters each level, so nothing deeper is ever built.
  const json::parser_callback_t limit = [&where](int depth, json::parse_event_t event, json&) {
    if ((event == json::parse_event_t::object_start || event == json::parse_event_t::array_start) &&
        depth >= kMaxJsonDepth) {
      throw InputError(where, "nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
    }
    return true;
  };
  try {
    return json::parse(text, limit);
  } catch (const json::exception& e) {
    // Syntax errors, and numbers out of range of a double (e.g. 1e999).
    throw InputError(where, std::string("not valid JSON: ") + e.what());
  }
}

bool is_valid_utf8(const std::string& text) {
  const auto* p = reinterpret_cast<const unsigned char*>(text.data());
  const auto* end = p + text.size();
  while (p < end) {
    const unsigned char c = *p;
    int length = 0;
    std::uint32_t code = 0;
    if (c < 0x80) {
      ++p;
      continue;
    } else if ((c & 0xE0) == 0xC0) {
      length = 2;
      code = c & 0x1F;
    } else if ((c & 0xF0) == 0xE0) {
      length = 3;
      code = c & 0x0F;
    } else if ((c & 0xF8) == 0xF0) {
      length = 4;
      code = c & 0x07;
    } else {
      return false;
    }
    if (end - p < length) return false;
    for (int k = 1; k < length; ++k) {
      if ((p[k] & 0xC0) != 0x80) return false;
      code = (code << 6) | (p[k] & 0x3F);
    }
    // Overlong forms, UTF-16 surrogates and code points past U+10FFFF are not UTF-8.
    static constexpr std::uint32_t kSmallest[] = {0, 0, 0x80, 0x800, 0x10000};
    if (code < kSmallest[length] || (code >= 0xD800 && code <= 0xDFFF) || code > 0x10FFFF) {
      return false;
    }
    p += length;
  }
  return true;
}

json parse_command_line_value(const std::string& text, const std::string& where) {
  // A bare word becomes a JSON string, which must be UTF-8 (JSON text is checked by the parser).
  if (!is_valid_utf8(text)) throw InputError(where, "not valid UTF-8 text");
  const bool word_like = !text.empty() && (std::isalpha(static_cast<unsigned char>(text[0])) ||
                                           text[0] == '_' || text[0] == '=');
  if (word_like && !json::accept(text)) return text;
  return parse_json_text(text, where);
}

std::string describe_json(const json& value) {
  // Invalid UTF-8 (which no parsed document holds, but a value built in code may) is shown as
  // U+FFFD rather than thrown while an error is being reported.
  std::string text = value.dump(-1, ' ', false, json::error_handler_t::replace);
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return text;
}

bool JsonReader::is_ours(const InputError& e) const {
  return e.where().rfind(source_ + separator_, 0) == 0;
}

void JsonReader::fail(const std::string& path, const std::string& message) const {
  throw InputError(source_ + separator_ + (path.empty() ? "/" : path), message);
}

void JsonReader::fail_value(const std::string& path, const json& value,
                            const std::string& expected) const {
  fail(path, "got " + describe_json(value) + ", expected " + expected);
}

const json& JsonReader::object(const json& value, const std::string& path) const {
  if (!value.is_object()) fail_value(path, value, "an object");
  return value;
}

void JsonReader::only_keys(const json& obj, const std::string& path,
                           const std::set<std::string>& allowed) const {
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    if (!allowed.count(it.key())) {
      std::string list;
      for (const auto& k : allowed) list += (list.empty() ? "" : ", ") + k;
      fail(path + "/" + it.key(), "unknown key; expected one of: " + list);
    }
  }
}

const json& JsonReader::required(const json& obj, const std::string& path,
                                 const std::string& key) const {
  auto it = obj.find(key);
  if (it == obj.end()) fail(path + "/" + key, "missing required key");
  return *it;
}

double JsonReader::number(const json& value, const std::string& path) const {
  if (!value.is_number()) fail_value(path, value, "a number");
  const double x = value.get<double>();
  if (!std::isfinite(x)) fail_value(path, value, "a finite number");
  return x;
}

double JsonReader::positive(const json& value, const std::string& path) const {
  const double x = number(value, path);
  if (!(x > 0.0)) fail_value(path, value, "a positive number");
  return x;
}

double JsonReader::non_negative(const json& value, const std::string& path) const {
  const double x = number(value, path);
  if (!(x >= 0.0)) fail_value(path, value, "a number >= 0");
  return x;
}

bool JsonReader::boolean(const json& value, const std::string& path) const {
  if (!value.is_boolean()) fail_value(path, value, "true or false");
  return value.get<bool>();
}

std::string JsonReader::string(const json& value, const std::string& path) const {
  if (!value.is_string()) fail_value(path, value, "a string");
  return value.get<std::string>();
}

Vec3 JsonReader::vec3(const json& value, const std::string& path) const {
  if (!value.is_array() || value.size() != 3) fail_value(path, value, "an array of 3 numbers");
  return Vec3(number(value[0], path + "/0"), number(value[1], path + "/1"),
              number(value[2], path + "/2"));
}

Vec3 JsonReader::direction(const json& value, const std::string& path) const {
  const Vec3 v = vec3(value, path);
  // Any finite non-zero length: stableNorm does not square the components (1e200 or 1e-170).
  const double length = v.stableNorm();
  if (!(length > 0.0) || !std::isfinite(length)) {
    fail_value(path, value, "a non-zero direction [x, y, z]");
  }
  return v / length;
}

Quat JsonReader::quaternion(const json& value, const std::string& path) const {
  if (!value.is_array() || value.size() != 4) {
    fail_value(path, value, "a unit quaternion [w, x, y, z]");
  }
  Quat q(number(value[0], path + "/0"), number(value[1], path + "/1"),
         number(value[2], path + "/2"), number(value[3], path + "/3"));
  // Accept rounding in hand-written or generated files; reject anything that is not meant to be
  // a unit quaternion.
  if (std::abs(q.norm() - 1.0) > 1e-6) {
    fail_value(path, value,
               "a unit quaternion [w, x, y, z] (norm within 1e-6 of 1; this has norm " +
                   std::to_string(q.norm()) + ")");
  }
  q.normalize();
  return q;
}

}  // namespace palpable
