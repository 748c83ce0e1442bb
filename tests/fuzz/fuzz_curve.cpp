// libFuzzer target: pyrocam::read_spectrum_csv, the CSV curves a profile names (QE, filters).
#include "fuzz_support.h"
#include "pyrocam/core/spectrum.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = pyrocam::fuzz::write_input("curve.csv", data, size);
  pyrocam::fuzz::expect_input_error_only([&] {
    const pyrocam::Spectrum s = pyrocam::read_spectrum_csv(path, "", 1.0);
    s.resample(pyrocam::WavelengthGrid(400, 1000, 5));
  });
  return 0;
}
