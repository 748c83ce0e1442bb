// A simulated plate measured as FrameMeasurer reads it: the share of its interior that reads
// and the median error, for the tests of the edges a band's threshold makes (dim, saturation).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "../true_model.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {

// The simulated colour camera (a typical unit, seed 3) with a model of its true QE, read by
// the likelihood fit where every band must read (the colour camera has no monotonic pair), and
// a 1200 degC plate on it (emissivity 0.8, 200 x 150).
struct TrueQeColourPlate {
  static constexpr double kTruthC = 1200;
  CameraProfile profile = load_profile_by_name("rgb-reference");
  UnitPerturbation unit = UnitPerturbation::parse("typical", 3);
  Simulator camera{profile, unit, 11};
  cv::Mat truth = plate_scene(200, 150, kTruthC, 0.8);
  FrameMeasurer measurer{test::true_model(profile, unit), options()};

  static MeasureOptions options() {
    MeasureOptions o;
    o.method = Method::kLikelihood;
    o.safe_partial = true;
    return o;
  }
};

struct PlateReadings {
  double read = 0;      // share of the interior's pixels with a reading
  double median = NAN;  // their median error, degC (NaN: none read)
};

// `frames` frames of `truth` (a plate at truth_c) at `exposure_us`, against a dark of 16
// frames; the interior: clear of the plate's edges (a tenth of the frame) by more than a
// footprint and a check's ring.
inline PlateReadings measure_plate(FrameMeasurer& measurer, Simulator& camera, const cv::Mat& truth,
                                   double truth_c, double exposure_us, int frames = 2) {
  const int w = truth.cols, h = truth.rows;
  cv::Mat dark = cv::Mat::zeros(h, w, CV_32F);
  for (int i = 0; i < 16; ++i)
    cv::add(dark, camera.render_dark(w, h, exposure_us), dark, cv::noArray(), CV_32F);
  dark /= 16;
  std::vector<double> errors;
  std::size_t pixels = 0;
  for (int frame = 0; frame < frames; ++frame) {
    cv::Mat t;
    measurer.measure(camera.render(truth, exposure_us), dark, t);
    const int mx = w / 10 + 8, my = h / 10 + 8;
    for (int y = my; y < h - my; ++y)
      for (int x = mx; x < w - mx; ++x) {
        ++pixels;
        if (std::isfinite(t.at<float>(y, x))) errors.push_back(t.at<float>(y, x) - truth_c);
      }
  }
  PlateReadings r;
  r.read = static_cast<double>(errors.size()) / static_cast<double>(pixels);
  if (!errors.empty()) {
    std::nth_element(errors.begin(),
                     errors.begin() + static_cast<std::ptrdiff_t>(errors.size() / 2), errors.end());
    r.median = errors[errors.size() / 2];
  }
  return r;
}

}  // namespace pyrocam
