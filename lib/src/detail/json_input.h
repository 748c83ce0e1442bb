// Parsing JSON files that may be corrupt or hostile. Every later walk over the document (dump()
// for a checksum, comparisons, destruction) recurses once per nesting level, so a file nested a
// million levels deep would exhaust the stack; the parser refuses it first.
#pragma once

#include <istream>
#include <nlohmann/json.hpp>
#include <string>

#include "pyrocam/core/error.h"

namespace pyrocam {

// Deeper than any pyrocam file needs (a model's profile mosaic band map sits at level 6).
inline constexpr int kMaxJsonNesting = 64;

// json::parse with nesting bounded to kMaxJsonNesting levels: deeper throws InputError
// "<where>: JSON nested deeper than 64 levels". Syntax errors throw json::parse_error as usual.
inline nlohmann::json parse_bounded_json(std::istream& in, const std::string& where,
                                         bool ignore_comments = false) {
  using nlohmann::json;
  // `depth` counts the containers around the one that starts: 0 for the top level.
  const json::parser_callback_t bound = [&where](int depth, json::parse_event_t event, json&) {
    if ((event == json::parse_event_t::object_start || event == json::parse_event_t::array_start) &&
        depth >= kMaxJsonNesting)
      throw InputError(where + ": JSON nested deeper than " + std::to_string(kMaxJsonNesting) +
                       " levels");
    return true;
  };
  return json::parse(in, bound, /*allow_exceptions=*/true, ignore_comments);
}

// The same for a document already in memory (no comments), several times faster: the nesting is
// bounded by a scan of the brackets outside strings first, so the parser needs no callback per
// value, and it reads the string's bytes directly rather than through a stream.
inline nlohmann::json parse_bounded_json(const std::string& text, const std::string& where) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonNesting)
        throw InputError(where + ": JSON nested deeper than " + std::to_string(kMaxJsonNesting) +
                         " levels");
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return nlohmann::json::parse(text);
}

}  // namespace pyrocam
