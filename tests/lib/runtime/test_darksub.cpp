// Dark subtraction: values, saturation marks, dark capture.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "pyrocam/core/error.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {
namespace {

TEST(DarkSub, default_saturation_is_220_of_255_of_full_scale) {
  EXPECT_EQ(default_saturation_level(8), 220);
  EXPECT_EQ(default_saturation_level(12), std::round(220.0 / 255.0 * 4095));
  EXPECT_EQ(default_saturation_level(16), std::round(220.0 / 255.0 * 65535));
  EXPECT_THROW(default_saturation_level(0), InputError);
  EXPECT_THROW(default_saturation_level(17), InputError);
}

// A dark frame of one level everywhere (CV_32F).
cv::Mat level_dark(int width, int height, double level_dn) {
  return cv::Mat(height, width, CV_32F, cv::Scalar(level_dn));
}

TEST(DarkSub, subtracts_and_marks_saturation_before_subtraction) {
  cv::Mat raw = (cv::Mat_<std::uint8_t>(2, 3) << 50, 100, 219, 220, 255, 0);
  cv::Mat dark = level_dark(3, 2, 50);
  dark.at<float>(1, 2) = std::nanf("");
  cv::Mat out;
  subtract_dark(raw, dark, 220, out);
  ASSERT_EQ(out.type(), CV_32F);
  EXPECT_EQ(out.at<float>(0, 0), 0.f);
  EXPECT_EQ(out.at<float>(0, 1), 50.f);
  EXPECT_EQ(out.at<float>(0, 2), 169.f);
  EXPECT_TRUE(std::isinf(out.at<float>(1, 0)) && out.at<float>(1, 0) > 0);
  EXPECT_TRUE(std::isinf(out.at<float>(1, 1)));
  EXPECT_TRUE(std::isnan(out.at<float>(1, 2)));
}

// The samples marked saturated, counted with the rectangle that holds them, on both paths and
// on a large frame (two threads); NaN (a bad dark) is not saturated.
TEST(DarkSub, counts_and_bounds_the_saturated_samples) {
  cv::Mat raw(600, 700, CV_8U, cv::Scalar(100));
  raw.at<std::uint8_t>(10, 600) = 230;
  raw.at<std::uint8_t>(500, 20) = 255;
  raw.at<std::uint8_t>(300, 300) = 220;
  cv::Mat dark = level_dark(700, 600, 50), a, b;
  dark.at<float>(5, 5) = std::nanf("");
  const SaturatedSamples with_dark = subtract_dark(raw, dark, 220, a);
  const SaturatedSamples with_level = subtract_dark_level(raw, 50, 220, b);
  for (const SaturatedSamples& s : {with_dark, with_level, find_saturated(a), find_saturated(b)}) {
    EXPECT_EQ(s.count, 3u);
    EXPECT_EQ(s.bounds, cv::Rect(cv::Point(20, 10), cv::Point(601, 501)));
    // The tiles that hold them, and no other: (600, 10) is in tile column 600 * 64 / 700 = 54
    // of tile row 10 * 64 / 600 = 1.
    std::array<std::uint64_t, kSaturationTiles> want{};
    want[1] |= std::uint64_t{1} << 54;
    want[53] |= std::uint64_t{1} << 1;
    want[32] |= std::uint64_t{1} << 27;
    EXPECT_EQ(s.tiles, want);
    EXPECT_TRUE(saturation_tile_rect(1, 54, 700, 600).contains(cv::Point(600, 10)));
    EXPECT_TRUE(saturation_tile_rect(53, 1, 700, 600).contains(cv::Point(20, 500)));
  }
  const SaturatedSamples none = subtract_dark_level(raw, 50, 256, b);
  EXPECT_EQ(none.count, 0u);
  EXPECT_TRUE(none.bounds.empty());
  EXPECT_EQ(none.tiles, (std::array<std::uint64_t, kSaturationTiles>{}));
  EXPECT_EQ(find_saturated(b).count, 0u);
  EXPECT_THROW(find_saturated(raw), InputError);
}

TEST(DarkSub, sixteen_bit_frames_and_caller_buffers) {
  cv::Mat raw = (cv::Mat_<std::uint16_t>(1, 3) << 100, 4000, 3522);
  cv::Mat dark = dark_from_image((cv::Mat_<std::uint16_t>(1, 3) << 60, 60, 60));
  float buffer[3] = {1, 2, 3};
  cv::Mat out(1, 3, CV_32F, buffer);
  const SaturatedSamples saturated = subtract_dark(raw, dark, default_saturation_level(12), out);
  EXPECT_EQ(saturated.count, 1u);
  EXPECT_EQ(saturated.bounds, cv::Rect(1, 0, 1, 1));
  EXPECT_EQ(subtract_dark_level(raw, 60, 3999.5, out).count, 1u);  // 4000 >= 3999.5
  EXPECT_EQ(subtract_dark_level(raw, 60, 4000.5, out).count, 0u);
  subtract_dark(raw, dark, default_saturation_level(12), out);
  EXPECT_EQ(out.ptr<float>(), buffer);  // written in place
  EXPECT_EQ(buffer[0], 40.f);
  EXPECT_TRUE(std::isinf(buffer[1]));
  EXPECT_EQ(buffer[2], 3462.f);  // 3522 < 3523 = round(220/255 * 4095)
}

TEST(DarkSub, constant_level_and_large_frames_match_the_dark_frame_path) {
  cv::Mat raw(600, 700, CV_16U);
  cv::randu(raw, 0, 4096);
  cv::Mat dark = level_dark(700, 600, 64.5), a, b;
  subtract_dark(raw, dark, 3533, a);
  subtract_dark_level(raw, 64.5, 3533, b);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(cv::countNonZero(a != b), 0);  // +INF == +INF
  for (int y : {0, 299, 599})
    for (int x : {0, 350, 699}) {
      const float v = raw.at<std::uint16_t>(y, x);
      if (v >= 3533) {
        EXPECT_TRUE(std::isinf(a.at<float>(y, x)));
      } else {
        EXPECT_EQ(a.at<float>(y, x), v - 64.5f);
      }
    }
}

TEST(DarkSub, rejects_a_dark_of_another_size_naming_both) {
  cv::Mat raw(4, 6, CV_8U, cv::Scalar(10)), out;
  try {
    subtract_dark(raw, level_dark(8, 4, 0), 220, out);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("8x4"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("6x4"), std::string::npos) << e.what();
  }
}

TEST(DarkSub, accumulator_averages_frames) {
  DarkAccumulator acc;
  EXPECT_THROW(acc.mean(), InputError);
  acc.add(cv::Mat(2, 2, CV_8U, cv::Scalar(49)));
  acc.add(cv::Mat(2, 2, CV_8U, cv::Scalar(52)));
  EXPECT_EQ(acc.count(), 2);
  EXPECT_FLOAT_EQ(acc.mean().at<float>(1, 1), 50.5f);
  EXPECT_THROW(acc.add(cv::Mat(2, 4, CV_8U, cv::Scalar(1))), InputError);
  acc.reset();
  EXPECT_EQ(acc.count(), 0);
}

// The simulated colour camera's plates, as exposed and at half the exposure: read as the rggb
// they are, the greens are where rggb puts them; shifted by one column or one row (a crop at the
// left or top) they are on the other diagonal; shifted by both (red and blue traded) they are in
// place again, which this check cannot see. Twice as long, the red samples saturate: a cell
// with a saturated sample does not count, and nothing is said whatever the labelling.
TEST(DarkSub, a_bayer_mosaic_shifted_by_a_row_or_a_column_has_its_greens_elsewhere) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  for (const char* unit : {"typical", "hostile"}) {
    Simulator camera(p, UnitPerturbation::parse(unit, 2), 5);
    for (double t : {700.0, 1500.0, 2500.0}) {
      for (double longer : {0.5, 1.0, 2.0}) {
        SCOPED_TRACE(std::string(unit) + " " + std::to_string(t) + " degC x" +
                     std::to_string(longer));
        const double exposure = longer * camera.exposure_for(t, 140);
        const cv::Mat raw = camera.render(plate_scene(96, 72, t, 0.5), exposure);
        cv::Mat signal;
        subtract_dark(raw, dark_from_image(camera.render_dark(96, 72, exposure)), 220, signal);
        const auto sums_of = [&](int dx, int dy) {
          BayerCellSums sums;
          add_bayer_cell_sums(signal(cv::Rect(dx, dy, 94, 70)), 4, 51, 0, 1, SignalNoise{}, sums);
          return sums;
        };
        const bool saturated = longer > 1;
        if (!saturated) {
          ASSERT_GT(sums_of(0, 0).cells, 500u);
        }
        EXPECT_FALSE(bayer_greens_elsewhere(sums_of(0, 0), "rggb"));
        EXPECT_EQ(bayer_greens_elsewhere(sums_of(1, 0), "rggb"), !saturated);
        EXPECT_EQ(bayer_greens_elsewhere(sums_of(0, 1), "rggb"), !saturated);
        EXPECT_FALSE(bayer_greens_elsewhere(sums_of(1, 1), "rggb"));
        // Labelled as what the shift leaves, each reads as it is.
        EXPECT_FALSE(bayer_greens_elsewhere(sums_of(1, 0), "grbg"));
        EXPECT_FALSE(bayer_greens_elsewhere(sums_of(0, 1), "gbrg"));
        EXPECT_FALSE(bayer_greens_elsewhere(sums_of(1, 1), "bggr"));
      }
    }
  }
}

// On a small plate the cells on its edges, lit in one column and dark in the other, outweighed
// the colours (the greens read 10 % apart unshifted, and a shift went unseen at 1000 degC): only
// cells inside the body count.
TEST(DarkSub, a_small_bodys_edges_neither_hide_nor_fake_a_shift) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  Simulator camera(p, UnitPerturbation::parse("typical", 1), 7);
  for (double t : {700.0, 1000.0, 1500.0, 2500.0}) {
    SCOPED_TRACE(t);
    const double exposure = camera.exposure_for(t, 140, 0.7);
    const cv::Mat raw = camera.render(plate_scene(128, 128, t), exposure, 0.7);
    const cv::Mat dark = camera.render_dark(128, 128, exposure);
    for (int dx : {0, 1}) {
      cv::Mat signal;
      subtract_dark(raw.colRange(dx, 126 + dx).clone(),
                    dark_from_image(dark.colRange(dx, 126 + dx).clone()), 220, signal);
      BayerCellSums sums;
      add_bayer_cell_sums(signal, 5, 51, 0, 4, SignalNoise{}, sums);
      EXPECT_GT(sums.cells, 256u);
      EXPECT_EQ(bayer_greens_elsewhere(sums, "rggb"), dx == 1) << dx;
    }
  }
}

// darksub judges at most max_cells lit cells a frame (all of a bright 2048x2048 plate's took 7 ms
// a frame): the sums stop there and still tell a shift.
TEST(DarkSub, bayer_cell_sums_stop_after_max_cells) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  Simulator camera(p, UnitPerturbation::parse("typical", 1), 7);
  const double exposure = camera.exposure_for(1500, 140, 0.7);
  const cv::Mat raw = camera.render(plate_scene(128, 128, 1500), exposure, 0.7);
  const cv::Mat dark = camera.render_dark(128, 128, exposure);
  cv::Mat signal;
  subtract_dark(raw.colRange(1, 127).clone(), dark_from_image(dark.colRange(1, 127).clone()), 220,
                signal);
  BayerCellSums all, capped;
  add_bayer_cell_sums(signal, 5, 51, 0, 1, SignalNoise{}, all);
  add_bayer_cell_sums(signal, 5, 51, 0, 1, SignalNoise{}, capped, 300);
  EXPECT_GT(all.cells, 1000u);
  EXPECT_EQ(capped.cells, 300u);
  EXPECT_LE(capped.bright[0] + capped.bright[1], 600u);
  EXPECT_TRUE(bayer_greens_elsewhere(all, "rggb"));
  EXPECT_TRUE(bayer_greens_elsewhere(capped, "rggb"));
}

// Frames of a snapshot mosaic (5x5: no two neighbours behind one filter) read as a Bayer mosaic
// give temperatures that look right and are wrong (a 1400 degC plate read 1031 with a colour
// model), and their cell sums, every place of the 2x2 cell averaging all 25 filters, do not show
// it: the pattern's greens differ in most bright cells, whatever the pattern. A Bayer mosaic's do
// not, on the simulated colour camera's plates exposed to 30 % and 60 % of the 170 DN that
// auto-exposure aims at (at 170, 50 DN of dark make most cells saturate), at 0 dB and at 24 dB
// of analogue gain, where 51 DN of green are about 54 electrons and a green pair's difference
// scatters by about 19 % of its mean: 12 % alone called half of such cells apart.
TEST(DarkSub, frames_that_are_no_bayer_mosaic_have_greens_that_disagree) {
  const auto sums_of = [](const CameraProfile& p, const char* unit, double t, double longer,
                          double gain_db) {
    Simulator camera(p, UnitPerturbation::parse(unit, 3), 11);
    const double gain = analogue_gain_factor(gain_db);
    const double exposure = longer * camera.exposure_for(t, 170) / gain;
    cv::Mat signal;
    subtract_dark(camera.render(plate_scene(320, 240, t, 0.8), exposure, 1.0, gain_db),
                  dark_from_image(camera.render_dark(320, 240, exposure)), 220, signal);
    SignalNoise noisiest{0, 0};
    for (int b = 0; b < p.band_count(); ++b) {
      const SignalNoise n = signal_noise(p, b, gain);
      noisiest = {std::max(noisiest.shot_gain, n.shot_gain),
                  std::max(noisiest.floor_dn2, n.floor_dn2)};
    }
    BayerCellSums sums;
    add_bayer_cell_sums(signal, 5, 51, 0, 1, noisiest, sums);
    return sums;
  };
  const CameraProfile snapshot = load_profile_by_name("nir5x5-reference");
  const CameraProfile colour = load_profile_by_name("rgb-reference");
  for (const char* unit : {"typical", "hostile"}) {
    for (double t : {700.0, 1500.0, 2500.0}) {
      SCOPED_TRACE(std::string(unit) + " " + std::to_string(t) + " degC");
      const BayerCellSums s = sums_of(snapshot, unit, t, 1, 0);
      ASSERT_GE(std::min(s.bright[0], s.bright[1]), 64u);
      for (const char* pattern : {"rggb", "bggr", "grbg", "gbrg"})
        EXPECT_TRUE(bayer_greens_disagree(s, pattern))
            << pattern << ": " << s.apart[0] << ", " << s.apart[1] << " of " << s.bright[0] << ", "
            << s.bright[1];
      for (double gain_db : {0.0, 24.0}) {
        for (double longer : {0.3, 0.6}) {  // the brightest band at 51 and 102 DN
          const BayerCellSums c = sums_of(colour, unit, t, longer, gain_db);
          EXPECT_FALSE(bayer_greens_disagree(c, "rggb"))
              << gain_db << " dB: " << c.apart[1] << " of " << c.bright[1];
          if (longer > 0.5) {
            EXPECT_GE(c.bright[1], 64u);  // the greens were tried
          }
        }
      }
    }
  }
}

// darksub knows no camera profile, and without exposure metadata no gain: it assumes a full well
// of 5000 electrons at 0 dB. A colour camera at 24-36 dB (51 DN of green are 54-14 electrons)
// scatters far more than that, and its greens must still not be called apart; nor may the
// measured scatter hide a snapshot mosaic, whatever its exposure.
TEST(DarkSub, greens_at_a_gain_the_noise_model_does_not_know_are_not_called_apart) {
  const SignalNoise assumed{255.0 / 5000, 2.0};  // darksub's for 8 bits without metadata
  const auto sums_of = [&](const CameraProfile& p, double t, double longer, double gain_db) {
    Simulator camera(p, UnitPerturbation::parse("typical", 3), 17);
    const double exposure = longer * camera.exposure_for(t, 170) / analogue_gain_factor(gain_db);
    cv::Mat signal;
    subtract_dark(camera.render(plate_scene(320, 240, t, 0.8), exposure, 1.0, gain_db),
                  dark_from_image(camera.render_dark(320, 240, exposure)), 220, signal);
    BayerCellSums sums;
    add_bayer_cell_sums(signal, 5, 51, 0, 1, assumed, sums);
    return sums;
  };
  const CameraProfile colour = load_profile_by_name("rgb-reference");
  const CameraProfile snapshot = load_profile_by_name("nir5x5-reference");
  for (double t : {1000.0, 2000.0}) {
    for (double gain_db : {24.0, 30.0, 36.0}) {
      for (double longer : {0.3, 0.6}) {
        SCOPED_TRACE(std::to_string(t) + " degC, " + std::to_string(gain_db) + " dB, x" +
                     std::to_string(longer));
        const BayerCellSums c = sums_of(colour, t, longer, gain_db);
        EXPECT_FALSE(bayer_greens_disagree(c, "rggb")) << c.apart[1] << " of " << c.bright[1];
        const BayerCellSums s = sums_of(snapshot, t, longer + 0.4, gain_db);
        EXPECT_TRUE(bayer_greens_disagree(s, "rggb")) << s.apart[1] << " of " << s.bright[1];
      }
    }
  }
}

TEST(DarkSub, bayer_cell_sums_tell_nothing_without_light_or_for_5x5) {
  BayerCellSums sums;
  add_bayer_cell_sums(cv::Mat(8, 8, CV_32F, cv::Scalar(2.0f)), 4, 51, 0, 1, SignalNoise{}, sums);
  EXPECT_EQ(sums.cells, 0u);
  EXPECT_FALSE(bayer_greens_elsewhere(sums, "rggb"));
  sums.at[0][0] = 100, sums.at[0][1] = 200, sums.at[1][0] = 100, sums.at[1][1] = 100;
  sums.cells = 1000;
  EXPECT_TRUE(bayer_greens_elsewhere(sums, "rggb"));
  EXPECT_FALSE(bayer_greens_elsewhere(sums, "5x5"));
  EXPECT_THROW(add_bayer_cell_sums(cv::Mat(8, 8, CV_8U), 4, 51, 0, 1, SignalNoise{}, sums),
               InputError);
  EXPECT_THROW(add_bayer_cell_sums(cv::Mat(8, 8, CV_32F), 4, 51, 4, 4, SignalNoise{}, sums),
               InputError);
  EXPECT_FALSE(bayer_greens_disagree(sums, "rggb"));  // no bright cells
  sums.bright[1] = 64, sums.apart[1] = 17;
  EXPECT_TRUE(bayer_greens_disagree(sums, "rggb"));
  EXPECT_FALSE(bayer_greens_disagree(sums, "grbg"));
  EXPECT_FALSE(bayer_greens_disagree(sums, "5x5"));
  sums.apart[1] = 16;
  EXPECT_FALSE(bayer_greens_disagree(sums, "rggb"));
}

}  // namespace
}  // namespace pyrocam
