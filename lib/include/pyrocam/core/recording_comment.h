// The comment a recording carries about itself: "pyrocam-recording; key=value; ..." written by
// ratiotemp, "pyrocam-raw; key=value; ..." by the recording script for a raw mosaic. Writer and
// reader go through this header so that a number written is the number read back.
#pragma once

#include <map>
#include <string>

namespace pyrocam {

inline constexpr const char* kTemperatureRecordingMark = "pyrocam-recording";
inline constexpr const char* kRawRecordingMark = "pyrocam-raw";

// A number as a comment field writes it (%.6g).
std::string recording_comment_number(double value);

// A field's value without the field separator (';' and line breaks become ',').
std::string recording_comment_value(std::string value);

// The fields of a comment that starts with one of the marks; empty for any other comment.
std::map<std::string, std::string> parse_recording_comment(const std::string& comment);

// The number at the start of a field's value ("10 %/100 nm" -> 10). Throws InputError naming
// the text when it does not start with a finite number.
double recording_comment_field_number(const std::string& text);

}  // namespace pyrocam
