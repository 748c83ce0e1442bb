// Finding values in a JSON document's text without parsing it: where a value ends, where an
// object's member lies. For the model file, whose checksum is taken over its own text and whose
// network layers are read by a faster scanner than the JSON parser (mlp_layers_text.h).
#pragma once

#include <cstddef>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace pyrocam::detail {

inline bool json_space(char c) { return c == ' ' || c == '\n' || c == '\t' || c == '\r'; }

inline std::size_t json_skip_space(const std::string& text, std::size_t i) {
  while (i < text.size() && json_space(text[i])) ++i;
  return i;
}

// The end of the JSON value that starts at text[i] (after any white space), or npos when it is
// not well formed as far as brackets and strings go. A model file is megabytes of numbers inside
// arrays, so inside a container everything but brackets and quotes is skipped in a tight loop,
// and a string's body up to its next quote or backslash.
inline std::size_t json_value_end(const std::string& text, std::size_t i) {
  const char* p = text.data();
  const std::size_t n = text.size();
  const auto structural = [](char c) {
    return c == '"' || c == '[' || c == ']' || c == '{' || c == '}';
  };
  int depth = 0;
  while (i < n) {
    if (depth > 0)  // strcspn scans many bytes at a time; it stops early at a NUL byte
      while (i < n && !structural(p[i])) i += p[i] ? std::strcspn(p + i, "\"[]{}") : 1;
    if (i >= n) break;
    const char c = p[i];
    if (c == '"') {
      for (++i; i < n && p[i] != '"'; ++i)
        if (p[i] == '\\') ++i;  // the escaped character is no quote
      if (i >= n) break;
      if (depth == 0) return i + 1;  // a string on its own (a key)
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if (c == ']' || c == '}') {
      if (depth == 0) return i;  // a number or literal ends at its container's end
      if (--depth == 0) return i + 1;
    } else if (depth == 0 && (c == ',' || json_space(c))) {
      return i;
    }
    ++i;
  }
  return std::string::npos;
}

// Where the value of member `name` of the object starting at text[object] (after any white
// space) lies, [begin, end): when the object is well formed as far as json_value_end tells and
// holds the name once, written without escapes. Nothing otherwise.
inline std::optional<std::pair<std::size_t, std::size_t>> json_member_span(const std::string& text,
                                                                           std::size_t object,
                                                                           std::string_view name) {
  std::size_t i = json_skip_space(text, object);
  if (i >= text.size() || text[i] != '{') return std::nullopt;
  std::optional<std::pair<std::size_t, std::size_t>> found;
  for (i = json_skip_space(text, i + 1); i < text.size() && text[i] == '"';) {
    const std::size_t key_end = json_value_end(text, i);
    if (key_end == std::string::npos) return std::nullopt;
    const bool match =
        key_end - i == name.size() + 2 && text.compare(i + 1, name.size(), name) == 0;
    i = json_skip_space(text, key_end);
    if (i >= text.size() || text[i] != ':') return std::nullopt;
    const std::size_t start = json_skip_space(text, i + 1), end = json_value_end(text, start);
    if (end == std::string::npos || end == start) return std::nullopt;
    if (match) {
      if (found) return std::nullopt;  // twice: the parser would keep the last
      found = std::pair{start, end};
    }
    i = json_skip_space(text, end);
    if (i < text.size() && text[i] == ',')
      i = json_skip_space(text, i + 1);
    else
      break;
  }
  if (i >= text.size() || text[i] != '}') return std::nullopt;
  return found;
}

}  // namespace pyrocam::detail
