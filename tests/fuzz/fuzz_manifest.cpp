// libFuzzer target: the calibration dataset reader. The input is manifest.csv of a small fixed
// dataset folder (roi.pgm, dark.pgm, frame.pgm, 8x8, written once); a dataset that opens has its
// frame and dark groups averaged, as calibration does.
#include <opencv2/core.hpp>

#include "fuzz_support.h"
#include "pyrocam/core/dataset.h"
#include "pyrocam/core/image_io.h"

namespace {

void make_folder() {
  const auto& dir = pyrocam::fuzz::work_dir();
  pyrocam::write_raw_image(dir / "roi.pgm", cv::Mat(8, 8, CV_8U, cv::Scalar(255)));
  pyrocam::write_raw_image(dir / "dark.pgm", cv::Mat(8, 8, CV_16U, cv::Scalar(50)));
  pyrocam::write_raw_image(dir / "frame.pgm", cv::Mat(8, 8, CV_16U, cv::Scalar(900)));
  pyrocam::write_raw_image(dir / "small.pgm", cv::Mat(4, 4, CV_16U, cv::Scalar(900)));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool made = (make_folder(), true);
  (void)made;
  pyrocam::fuzz::write_input("manifest.csv", data, size);
  pyrocam::fuzz::expect_input_error_only([&] {
    const pyrocam::Dataset d = pyrocam::Dataset::open(pyrocam::fuzz::work_dir());
    int averaged = 0;
    for (const auto* groups : {&d.frames(), &d.darks()})
      for (const auto& g : *groups)
        if (averaged++ < 8) d.average(g);
    d.temperatures_c();
  });
  return 0;
}
