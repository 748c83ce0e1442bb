// Shared by the libFuzzer targets: a private temporary folder for readers that take a path, and
// what counts as a finding. A crash, a sanitizer report, an out-of-memory or a timeout always
// does; an exception other than pyrocam::InputError (the library's "bad input, here is what is
// wrong" error) does only with PYROCAM_FUZZ_STRICT=1, since it still reaches the user as a message.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "pyrocam/core/error.h"

namespace pyrocam::fuzz {

// A folder made once per process under $TMPDIR, removed at exit.
inline const std::filesystem::path& work_dir() {
  static const std::filesystem::path dir = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "pyrocam-fuzz-XXXXXX").string();
    if (!mkdtemp(pattern.data())) {
      std::perror("pyrocam fuzz: mkdtemp");
      std::abort();
    }
    static std::filesystem::path made = pattern;
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(made, ec);
    });
    return made;
  }();
  return dir;
}

// Writes the input to `name` in the work folder and returns its path.
inline std::filesystem::path write_input(const std::string& name, const std::uint8_t* data,
                                         std::size_t size) {
  const std::filesystem::path path = work_dir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) {
    std::perror("pyrocam fuzz: writing the input");
    std::abort();
  }
  return path;
}

inline bool env_is_1(const char* name) {
  const char* s = std::getenv(name);
  return s && std::string(s) == "1";
}

// Runs `read`; InputError is the expected answer to bad input. Other exceptions abort in strict
// mode (PYROCAM_FUZZ_STRICT=1), naming the exception, so that libFuzzer keeps the input.
// PYROCAM_FUZZ_VERBOSE=1 prints every message (to check what seeds reach).
template <typename F>
void expect_input_error_only(F&& read) {
  static const bool strict = env_is_1("PYROCAM_FUZZ_STRICT");
  static const bool verbose = env_is_1("PYROCAM_FUZZ_VERBOSE");
  try {
    read();
    if (verbose) std::fprintf(stderr, "pyrocam fuzz: read without error\n");
  } catch (const InputError& e) {
    if (verbose) std::fprintf(stderr, "pyrocam fuzz: InputError: %s\n", e.what());
  } catch (const std::exception& e) {
    if (verbose) std::fprintf(stderr, "pyrocam fuzz: other exception: %s\n", e.what());
    if (strict) {
      std::fprintf(stderr, "pyrocam fuzz: exception other than InputError: %s\n", e.what());
      std::abort();
    }
  }
}

}  // namespace pyrocam::fuzz
