#include "pyrocam/core/error.h"

namespace pyrocam {

void require_regular_file(const std::filesystem::path& path, const std::string& what) {
  std::error_code ec;
  const std::filesystem::file_type type = std::filesystem::status(path, ec).type();
  if (type == std::filesystem::file_type::regular) return;
  if (type == std::filesystem::file_type::not_found)
    throw InputError(path.string() + ": " + what + " not found");
  if (ec) throw InputError(path.string() + ": cannot read " + what + " (" + ec.message() + ")");
  if (type == std::filesystem::file_type::directory)
    throw InputError(path.string() + ": " + what + " is a directory");
  throw InputError(path.string() + ": " + what +
                   " is not a regular file (a FIFO, socket or device)");
}

}  // namespace pyrocam
