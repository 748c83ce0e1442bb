// libFuzzer target: pyrocam::load_model, the thermal model JSON. Model files carry a checksum of
// their payload, which a mutated input would almost never match: when the input parses as an
// object with a payload (and is not nested deeper than the harness itself can dump), its
// checksum is set right before the file is written, so that the fuzzer reaches the content checks.
#include <nlohmann/json.hpp>

#include "fuzz_support.h"
#include "pyrocam/runtime/model.h"

namespace {

// Deepest bracket nesting outside strings.
int nesting(const std::uint8_t* data, std::size_t size) {
  int depth = 0, deepest = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < size; ++i) {
    const char c = static_cast<char>(data[i]);
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::filesystem::path path;
  nlohmann::json file;
  if (nesting(data, size) < 100)
    file = nlohmann::json::parse(data, data + size, nullptr, /*allow_exceptions=*/false);
  if (file.is_object() && file.contains("payload")) {
    file["checksum_fnv1a64"] = pyrocam::fnv1a_hex(file["payload"].dump());
    const std::string text = file.dump();
    path = pyrocam::fuzz::write_input(
        "model.json", reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  } else {
    path = pyrocam::fuzz::write_input("model.json", data, size);
  }
  pyrocam::fuzz::expect_input_error_only([&] { pyrocam::load_model(path); });
  return 0;
}
