// libFuzzer target: pyrocam::read_raw_image (PGM, PNG, TIFF; OpenCV picks the decoder by the
// file's signature, so one target covers all three).
#include "fuzz_support.h"
#include "pyrocam/core/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = pyrocam::fuzz::write_input("image", data, size);
  pyrocam::fuzz::expect_input_error_only([&] {
    const cv::Mat image = pyrocam::read_raw_image(path);
    // Touch every sample: a decoder that claims more than it filled shows up here.
    volatile double sum = cv::sum(image)[0];
    (void)sum;
  });
  return 0;
}
