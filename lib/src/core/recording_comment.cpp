#include "pyrocam/core/recording_comment.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "pyrocam/core/error.h"

namespace pyrocam {

std::string recording_comment_number(double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", value);
  return buf;
}

std::string recording_comment_value(std::string value) {
  for (char& c : value)
    if (c == ';' || c == '\n' || c == '\r') c = ',';
  return value;
}

std::map<std::string, std::string> parse_recording_comment(const std::string& comment) {
  std::map<std::string, std::string> fields;
  if (comment.rfind(kTemperatureRecordingMark, 0) != 0 && comment.rfind(kRawRecordingMark, 0) != 0)
    return fields;
  std::size_t start = 0;
  while (start < comment.size()) {
    std::size_t end = comment.find("; ", start);
    if (end == std::string::npos) end = comment.size();
    const std::string part = comment.substr(start, end - start);
    const std::size_t eq = part.find('=');
    if (eq != std::string::npos) fields[part.substr(0, eq)] = part.substr(eq + 1);
    start = end + 2;
  }
  return fields;
}

double recording_comment_field_number(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || !std::isfinite(v))
    throw InputError("the recording's tags: '" + text + "' is not a number");
  return v;
}

}  // namespace pyrocam
