// The above-range check: pixels hotter than the model's range are told apart from cold and
// unreadable ones, on simulated frames through the plane estimator (both paths), and the spots
// that count are those whose neighbourhood mostly reads above the range.
// Models: the small calibrated models the build makes (tests/data), whose camera is the
// simulator's "typical" unit 1; a narrow range is the same model with its end moved down.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/above_range.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/plane_estimator.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
#include "runtime/estimator_test_support.h"

namespace pyrocam::test {
namespace {

std::shared_ptr<const ThermalModel> up_to(const std::string& name, double max_c) {
  auto m = std::make_shared<ThermalModel>(*test_model(name));
  m->max_temperature_c = max_c;
  return m;
}

struct Frame {
  cv::Mat truth_c;  // the scene, at the planes' size
  cv::Mat mosaic;   // dark subtracted
  std::vector<cv::Mat> planes;
};

// A scene filmed by the model's own unit at an exposure that puts the scene's `exposed_c` at 150
// DN, demosaicked with kMatched.
Frame film(const ThermalModel& m, const cv::Mat& scene, double exposed_c, double emissivity) {
  const CameraProfile& p = m.profile();
  Simulator camera(p, UnitPerturbation::parse("typical", 1), 11);
  Frame f;
  const cv::Mat raw =
      camera.render(scene, camera.exposure_for(exposed_c, 150, emissivity), emissivity);
  subtract_dark_level(raw, p.dark_offset_dn, p.thresholds.inference_saturation_dn, f.mosaic);
  std::vector<SignalNoise> noise;
  for (int b = 0; b < p.band_count(); ++b) noise.push_back(signal_noise(p, b));
  demosaic(f.mosaic, p.mosaic, DemosaicMethod::kMatched, f.planes,
           static_cast<float>(no_signal_level_dn(noise)));
  cv::resize(scene, f.truth_c, f.planes[0].size(), 0, 0, cv::INTER_NEAREST);
  return f;
}

std::size_t count_hotter(const cv::Mat& truth_c, double c) {
  cv::Mat t = truth_c.clone();
  cv::patchNaNs(t, -1000);
  return static_cast<std::size_t>(cv::countNonZero(t > c));
}

TEST(AboveRange, a_plate_hotter_than_the_range_is_found_on_both_paths) {
  const auto model = up_to("test-model-rgb.json", 2000);
  const Frame f = film(*model, plate_scene(160, 120, 2300), 2300, 0.7);
  const cv::Size size = f.planes[0].size();
  PlaneEstimator estimator(model, Method::kLut);
  estimator.set_demosaic_noise(demosaic_noise(model->profile().mosaic, DemosaicMethod::kMatched));
  EXPECT_FALSE(estimator.above_range_check());
  cv::Mat t;
  estimator.estimate(f.planes, t);
  EXPECT_TRUE(estimator.take_above_range().empty());  // off by default
  estimator.set_above_range_check(true);
  estimator.estimate(f.planes, t);
  EXPECT_EQ(cv::countNonZero(t == t), 0);  // the model reads none of it
  const std::vector<cv::Point> found = estimator.take_above_range();
  EXPECT_TRUE(estimator.take_above_range().empty());  // handed over once
  const std::size_t plate = count_hotter(f.truth_c, 2000);
  // 300 degC above the end, where a pixel's reading has a standard deviation of about 50 degC
  // (colour, 150 DN; the check's own estimate, from one sample's noise per band, a little more):
  // 3 sigma below the plate leaves the check's margin of 3 sigma above the end, so about one
  // pixel in 700 is missed (normal), far fewer than the plate's edge pixels (mixed with the
  // background), which the bound leaves out.
  EXPECT_GE(found.size(), plate * 9 / 10);
  for (const cv::Point& p : found) EXPECT_GT(f.truth_c.at<float>(p), 2000) << p;
  const SaturatedSamples spots = above_range_spots(found, size);
  EXPECT_GE(spots.count, plate * 8 / 10);
  cv::Mat plate_mask = f.truth_c > 2000;
  EXPECT_EQ((spots.bounds & cv::boundingRect(plate_mask)), spots.bounds);
  // The fused path finds the same pixels.
  std::vector<SignalNoise> noise;
  for (int b = 0; b < 3; ++b) noise.push_back(signal_noise(model->profile(), b));
  const PlaneEstimator::MatchedMosaic fused{f.mosaic, model->profile().mosaic,
                                            static_cast<float>(no_signal_level_dn(noise))};
  estimator.set_dim_edge_mosaic(&fused);
  estimator.estimate(f.planes, t);
  std::vector<cv::Point> planes_found = estimator.take_above_range();
  estimator.set_dim_edge_mosaic(nullptr);
  cv::Mat codes;
  estimator.estimate_codes(fused, codes);
  std::vector<cv::Point> fused_found = estimator.take_above_range();
  const auto order = [](const cv::Point& a, const cv::Point& b) {
    return a.y != b.y ? a.y < b.y : a.x < b.x;
  };
  std::sort(planes_found.begin(), planes_found.end(), order);
  std::sort(fused_found.begin(), fused_found.end(), order);
  EXPECT_EQ(planes_found, fused_found);
  EXPECT_EQ(planes_found.size(), found.size());
}

// Scenes inside the range give no spot: melt pools (steep edges, mixed pixels), a plate 300 degC
// below the range's end on the narrow model and plates just below the full range's end; and the
// full range's model finds a plate at 4000 degC.
TEST(AboveRange, scenes_inside_the_range_have_no_spot_and_the_full_range_ends_too) {
  const auto narrow = up_to("test-model-rgb.json", 2000);
  PlaneEstimator estimator(narrow, Method::kLut);
  estimator.set_above_range_check(true);
  cv::Mat t;
  const Frame plate = film(*narrow, plate_scene(160, 120, 1700), 1700, 0.7);
  estimator.estimate(plate.planes, t);
  EXPECT_GT(cv::countNonZero(t == t), 4000);
  EXPECT_EQ(above_range_spots(estimator.take_above_range(), t.size()).count, 0u);

  const auto full = test_model("test-model-rgb.json");
  PlaneEstimator full_estimator(full, Method::kLut);
  full_estimator.set_above_range_check(true);
  for (int i = 0; i < 8; ++i) {
    SCOPED_TRACE(i);
    const Frame pool = film(*full, melt_pool_scene(512, 320, i, 8), melt_pool_peak_c(i, 8), 0.35);
    full_estimator.estimate(pool.planes, t);
    EXPECT_GT(cv::countNonZero(t == t), 100) << cv::countNonZero(t == t);
    EXPECT_EQ(above_range_spots(full_estimator.take_above_range(), t.size()).count, 0u);
  }
  // Plates just below the range's end: readings scatter over it (at 3450 degC the colour
  // camera's by some 100 degC), but none by 3 of their standard deviations.
  for (double c : {3400.0, 3450.0, 3490.0}) {
    const Frame near = film(*full, plate_scene(160, 120, c), c, 0.7);
    full_estimator.estimate(near.planes, t);
    EXPECT_EQ(full_estimator.take_above_range().size(), 0u) << c;
  }
  const Frame hot = film(*full, plate_scene(160, 120, 4000), 4000, 0.7);
  full_estimator.estimate(hot.planes, t);
  EXPECT_GE(above_range_spots(full_estimator.take_above_range(), t.size()).count,
            count_hotter(hot.truth_c, 3500) * 8 / 10);
}

TEST(AboveRange, the_5x5_camera_too) {
  const auto model = up_to("test-model-nir5x5.json", 2000);
  PlaneEstimator estimator(model, Method::kLikelihood);
  estimator.set_partial_bands(TemperatureEstimator::PartialBands::kSafe);
  estimator.set_above_range_check(true);
  const Frame f = film(*model, plate_scene(300, 200, 2300), 2300, 0.7);
  cv::Mat t;
  estimator.estimate(f.planes, t);
  const std::size_t plate = count_hotter(f.truth_c, 2000);
  ASSERT_GT(plate, 300u);
  EXPECT_GE(above_range_spots(estimator.take_above_range(), t.size()).count, plate * 7 / 10);
  const Frame cooler = film(*model, plate_scene(300, 200, 1700), 1700, 0.7);
  estimator.estimate(cooler.planes, t);
  EXPECT_EQ(above_range_spots(estimator.take_above_range(), t.size()).count, 0u);
}

TEST(AboveRange, spots_are_where_most_of_a_neighbourhood_is_above) {
  std::vector<cv::Point> found = {{2, 2}, {50, 40}, {0, 0}, {-1, 3}, {100, 100}};
  for (int y = 10; y < 13; ++y)
    for (int x = 20; x < 23; ++x) found.emplace_back(x, y);
  const SaturatedSamples spots = above_range_spots(found, cv::Size(64, 48));
  // The 3 x 3 block's corners see 4 of it, its edges 6, its centre 9: five pixels; the isolated
  // ones and those outside the frame none.
  EXPECT_EQ(spots.count, 5u);
  EXPECT_EQ(spots.bounds, cv::Rect(20, 10, 3, 3));
  std::array<std::uint64_t, kSaturationTiles> tiles{};
  for (const cv::Point& p : {cv::Point(21, 10), cv::Point(20, 11), cv::Point(21, 11),
                             cv::Point(22, 11), cv::Point(21, 12)})
    tiles[static_cast<std::size_t>(saturation_tile_of(p.y, 48))] |= std::uint64_t{1}
                                                                    << saturation_tile_of(p.x, 64);
  EXPECT_EQ(spots.tiles, tiles);
  EXPECT_EQ(above_range_spots({}, cv::Size(64, 48)).count, 0u);
}

// A frame that is hotter than the range over more pixels than the budget costs no more than it.
TEST(AboveRange, the_check_stops_at_its_budget) {
  const auto model = up_to("test-model-rgb.json", 2000);
  PlaneEstimator estimator(model, Method::kLut);
  estimator.set_above_range_check(true);
  const Frame f = film(*model, plate_scene(400, 400, 2300, 0.9), 2300, 0.7);
  ASSERT_GT(count_hotter(f.truth_c, 2000), kAboveRangeBudget + 10000);
  cv::Mat t;
  estimator.estimate(f.planes, t);
  const std::size_t found = estimator.take_above_range().size();
  EXPECT_LE(found, kAboveRangeBudget);
  EXPECT_GT(found, kAboveRangeBudget * 9 / 10);
}

}  // namespace
}  // namespace pyrocam::test
