// The lookup table against the network it tabulates, on noisy simulated pixels and far from the
// locus. Models: the small calibrated models the build makes (tests/data).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/core/error.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/runtime/plane_estimator.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
#include "runtime/estimator_test_support.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

TEST(LutEstimator, gives_the_networks_answer_on_noisy_pixels) {
  const auto model = test_model("test-model-rgb.json");
  const ThermalModel& m = *model;
  const NoisyPixels px = noisy_pixels(m, kSweepC, 1500, 15, 200, saturation_signal_dn(m), 0.02, 11);
  const std::vector<cv::Mat> planes = as_planes(px);
  // Rows of band planes go to two threads: the table is filled from both at once.
  // A row of unrelated pixels, not an image: no neighbours to judge the saturation level by.
  cv::Mat mlp, lut;
  PlaneEstimator mlp_estimator(model, Method::kMlp), lut_estimator(model, Method::kLut);
  mlp_estimator.set_saturation_level(INFINITY);
  lut_estimator.set_saturation_level(INFINITY);
  mlp_estimator.estimate(planes, mlp);
  lut_estimator.estimate(planes, lut);
  const Agreement a = compare(mlp, lut, 0.5);
  EXPECT_EQ(a.only_reference, 0u);
  EXPECT_EQ(a.only_fast, 0u);
  // Both decisions are exercised: readings and no readings (saturated, dim, out of range).
  EXPECT_GT(a.both, px.size() / 2);
  EXPECT_GT(a.neither, px.size() / 20);
  // The stated tolerance: 0.5 degC for 99.9 % of the readings; nowhere beyond the range guard.
  EXPECT_LE(a.over_tolerance, a.both / 1000) << "largest difference " << a.max_difference_c;
  EXPECT_LT(a.max_difference_c, 2.0);
  // The same table again (now filled): the same image, and the single-pixel path agrees.
  cv::Mat again;
  lut_estimator.estimate(planes, again);
  int differ = 0;
  for (int i = 0; i < lut.cols; ++i) {
    const float x = lut.at<float>(0, i), y = again.at<float>(0, i);
    differ += !(x == y || (std::isnan(x) && std::isnan(y)));
  }
  EXPECT_EQ(differ, 0);
  for (std::size_t i = 0; i < px.size(); i += 97) {
    const double single = lut_estimator.estimator().temperature_c(px.pixel(i));
    const float image = lut.at<float>(0, static_cast<int>(i));
    if (std::isnan(image)) {
      EXPECT_TRUE(std::isnan(single)) << i;
    } else {
      EXPECT_NEAR(single, image, 1e-3) << i;
    }
  }
}

// The hot end, where a degree is the smallest step in ratio and the table's cells span the most
// degrees: on simulated 2000 and 2500 degC plates exposed as the benchmark's (brightest pixels at
// 140 DN, the default demosaicking), within 0.1 degC of the network for 99.9 % of the readings
// at 2000 degC (13 of 92416 off by more, measured; cells 1.4 times as wide: 234). At 2500 degC
// this test model's network (30 epochs of training) bends more than a calibrated one: 414 off by
// more than 0.1 degC, the largest 0.25 degC (cells 1.4 times as wide: 1244), against a
// calibrated model's 99.9th percentile of 0.03-0.09 degC in the benchmark. Its bound is 0.6 %.
// The model's bits are the same on every machine since Eigen's products no longer size their
// blocks by the processor's caches (meson.build): before, an Intel processor's model gave 31 and
// 40 here. (Single pixels without demosaicking's averaging scatter further off the locus, where
// the network bends more, and reach about 0.1 degC.)
TEST(LutEstimator, agrees_to_a_tenth_of_a_degree_on_hot_plates) {
  const auto model = test_model("test-model-rgb.json");
  Simulator camera(model->profile(), UnitPerturbation::parse("typical", 1), 3);
  const int size = 512;  // the plate: about 90 000 pixels
  MeasureOptions lut_options, mlp_options;
  lut_options.method = Method::kLut;
  mlp_options.method = Method::kMlp;
  FrameMeasurer lut(model, lut_options);
  FrameMeasurer mlp(model, mlp_options);
  for (const double plate_c : {2000.0, 2500.0}) {
    const double exposure = camera.exposure_for(plate_c, 140, 0.7);
    const cv::Mat raw = camera.render(plate_scene(size, size, plate_c), exposure, 0.7);
    const cv::Mat dark = camera.render_dark(size, size, exposure);
    cv::Mat t_lut, t_mlp;
    lut.measure(raw, dark, t_lut);
    mlp.measure(raw, dark, t_mlp);
    const Agreement a = compare(t_mlp.reshape(1, 1), t_lut.reshape(1, 1), 0.1);
    EXPECT_EQ(a.only_reference + a.only_fast, 0u) << plate_c;
    ASSERT_GT(a.both, static_cast<std::size_t>(size * size / 4)) << plate_c;
    // About 90 000 readings: the 99.9th percentile's bound at 2000 degC, as the benchmark
    // prints it; 0.6 % at 2500 degC (above).
    const std::size_t bound = plate_c < 2200 ? a.both / 1000 : a.both * 6 / 1000;
    EXPECT_LE(a.over_tolerance, bound)
        << plate_c << " degC, largest difference " << a.max_difference_c;
    std::printf(
        "%.0f degC plate: %zu readings, %zu more than 0.1 degC off (bound %zu), "
        "largest %.3f degC\n",
        plate_c, a.both, a.over_tolerance, bound, a.max_difference_c);
  }
}

// The per-pixel passes work on chunks of pixels (each pixel's block and corners gathered for the
// chunk, then interpolated together): a whole row gives every pixel the very bits it gets alone,
// with saturated, dim, NaN and off-table pixels scattered between readable ones, and two rows
// that share the table's blocks in a different order give the same bits again.
TEST(LutEstimator, a_row_gives_each_pixel_the_bits_it_gets_alone) {
  const auto model = test_model("test-model-rgb.json");
  const NoisyPixels px =
      noisy_pixels(*model, kSweepC, 120, 15, 200, saturation_signal_dn(*model), 0.02, 17);
  std::vector<cv::Mat> planes = as_planes(px);
  const int n = planes[0].cols;
  for (int i = 0; i < n; i += 13) {  // every kind of pixel without a reading, or an odd one
    const float odd[][3] = {{NAN, 100, 60}, {INFINITY, 120, 60}, {100, 2, 60},
                            {150, 20, 150}, {20, 150, 20},       {100, 120, -5}};
    const auto& o = odd[(i / 13) % 6];
    for (int b = 0; b < 3; ++b) planes[static_cast<std::size_t>(b)].at<float>(0, i) = o[b];
  }
  // Unrelated pixels, not an image: no neighbours to judge the saturation level by.
  PlaneEstimator lut(model, Method::kLut), lut_backwards(model, Method::kLut);
  lut.set_saturation_level(INFINITY);
  lut_backwards.set_saturation_level(INFINITY);
  cv::Mat row;
  lut.estimate(planes, row);
  std::vector<cv::Mat> reversed(3);
  for (int b = 0; b < 3; ++b) cv::flip(planes[static_cast<std::size_t>(b)], reversed[b], 1);
  cv::Mat backwards;
  lut_backwards.estimate(reversed, backwards);
  int differ = 0, read = 0;
  for (int i = 0; i < n; ++i) {
    double s[3];
    for (int b = 0; b < 3; ++b) s[b] = planes[static_cast<std::size_t>(b)].at<float>(0, i);
    const auto alone = static_cast<float>(lut.estimator().temperature_c(s));
    const float x = row.at<float>(0, i), y = backwards.at<float>(0, n - 1 - i);
    const auto same = [](float a, float b) {
      return std::memcmp(&a, &b, sizeof a) == 0 || (std::isnan(a) && std::isnan(b));
    };
    differ += !same(x, alone) || !same(x, y);
    read += !std::isnan(x);
  }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(read, n / 2);
  EXPECT_LT(read, n - n / 20);
}

TEST(LutEstimator, answers_with_the_network_far_from_the_locus) {
  const auto model = test_model("test-model-rgb.json");
  const auto mlp = make_estimator(model, Method::kMlp);
  const auto lut = make_estimator(model, Method::kLut);
  // Ratios no graybody gives (edges of hot objects, mixed pixels): outside the table.
  const double far[][3] = {{150, 20, 150}, {20, 150, 20}, {160, 25, 21}, {21, 30, 160}};
  for (const auto& s : far) {
    const double a = mlp->temperature_c(s), b = lut->temperature_c(s);
    EXPECT_EQ(std::isnan(a), std::isnan(b));
    if (!std::isnan(a)) {
      EXPECT_NEAR(a, b, 1e-3);
    }
  }
}

TEST(LutEstimator, rejects_saturated_dim_and_invalid_bands_n) {
  const auto model = test_model("test-model-rgb.json");
  const auto lut = make_estimator(model, Method::kLut);
  const double ok[3] = {100, 120, 60}, saturated[3] = {INFINITY, 120, 60}, dim[3] = {100, 12, 60},
               nan[3] = {100, NAN, 60}, negative[3] = {100, -5, 60};
  EXPECT_TRUE(std::isfinite(lut->temperature_c(ok)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(saturated)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(dim)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(nan)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(negative)));
}

// The table cache: a second estimator of the model starts with the blocks the first filled, and
// reads every pixel as the first did; a cache of another model, cut short or altered adds
// nothing.
TEST(LutEstimator, table_cache_round_trip_gives_the_same_readings) {
  const auto model = test_model("test-model-rgb.json");
  ASSERT_FALSE(model->fingerprint.empty());
  const NoisyPixels px =
      noisy_pixels(*model, kSweepC, 100, 15, 200, saturation_signal_dn(*model), 0.02, 11);
  const std::vector<cv::Mat> planes = as_planes(px);
  ScratchDir dir("lut-cache");
  const std::string file = table_cache_file(*model, dir.path().string());
  EXPECT_EQ(file, (dir / ("lut-" + model->fingerprint + ".bin")).string());

  const PlaneEstimator first(model, Method::kLut);
  cv::Mat first_c;
  first.estimate(planes, first_c);
  const std::size_t filled = first.estimator().memory_bytes();
  const std::size_t saved = first.estimator().save_tables(file);
  EXPECT_GT(saved, 10u);
  EXPECT_EQ(first.estimator().save_tables(file), saved) << "it holds blocks the file did not give";

  const PlaneEstimator second(model, Method::kLut);
  EXPECT_EQ(second.estimator().load_tables(file), saved);
  EXPECT_EQ(second.estimator().memory_bytes(), filled);
  EXPECT_EQ(second.estimator().save_tables(file), 0u) << "nothing new to keep";
  cv::Mat second_c;
  second.estimate(planes, second_c);
  EXPECT_EQ(second.estimator().memory_bytes(), filled) << "no block filled again";
  int differ = 0;
  for (int i = 0; i < first_c.cols; ++i) {
    const float x = first_c.at<float>(0, i), y = second_c.at<float>(0, i);
    differ += !(x == y || (std::isnan(x) && std::isnan(y)));
  }
  EXPECT_EQ(differ, 0);

  // Altered, cut short, another model's, not a cache: InputError, nothing added.
  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto write = [&](const std::string& path, const std::string& content) {
    std::ofstream(path, std::ios::binary) << content;
    return path;
  };
  std::string altered = bytes;
  altered[altered.size() / 2] ^= 0x10;
  ThermalModel other_model = *model;
  other_model.fingerprint = "0123456789abcdef";
  const auto other = std::make_shared<const ThermalModel>(other_model);
  const std::vector<std::pair<std::shared_ptr<const ThermalModel>, std::string>> bad = {
      {model, write((dir / "altered.bin").string(), altered)},
      {model, write((dir / "short.bin").string(), bytes.substr(0, bytes.size() - 100))},
      {model, write((dir / "text.bin").string(), "not a cache\n")},
      {model, (dir / "missing.bin").string()},
      {other, file}};
  for (const auto& [m, path] : bad) {
    const auto fresh = make_estimator(m, Method::kLut);
    EXPECT_THROW(fresh->load_tables(path), InputError) << path;
    EXPECT_EQ(fresh->memory_bytes(), make_estimator(m, Method::kLut)->memory_bytes()) << path;
  }
  // A model not loaded from a file has no fingerprint to name its cache by.
  ThermalModel unnamed = *model;
  unnamed.fingerprint.clear();
  EXPECT_EQ(table_cache_file(unnamed, dir.path().string()), "");
}

}  // namespace
}  // namespace pyrocam::test
