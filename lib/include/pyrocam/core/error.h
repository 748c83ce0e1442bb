// The one error type for bad input (a file, a setting, a stream that does not fit) and the
// file check every reader makes before opening.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace pyrocam {

// Raised for any malformed input; the message names the file (or setting) and the problem.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Throws InputError unless `path` is a regular file (after following links): "<path>: <what>
// not found", "<path>: <what> is a directory" or "<path>: <what> is not a regular file (a FIFO,
// socket or device)". It never opens the file, so a FIFO cannot block it.
void require_regular_file(const std::filesystem::path& path, const std::string& what);

}  // namespace pyrocam
