// libFuzzer target: pyrocam::read_imec_band_responses, the IMEC factory calibration XML.
#include "fuzz_support.h"
#include "pyrocam/core/spectrum.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = pyrocam::fuzz::write_input("imec.xml", data, size);
  pyrocam::fuzz::expect_input_error_only([&] { pyrocam::read_imec_band_responses(path); });
  return 0;
}
