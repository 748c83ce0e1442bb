// The dark level check: a cold background reads 0 after the camera's own dark, in every place of
// the mosaic alike; a dark 20 DN off shows, on simulated colour and 5x5 frames.
#include <gtest/gtest.h>

#include <string>

#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/dark_level_check.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {
namespace {

// The verdict on one simulated frame with the dark `dark_error_dn` off (positive: the dark
// subtracted is too high, so the signals are that much too low).
DarkLevelVerdict verdict_of(const CameraProfile& p, const char* unit, const cv::Mat& scene,
                            double t, double longer, double gain_db, double dark_error_dn) {
  Simulator camera(p, UnitPerturbation::parse(unit, 4), 13);
  const double exposure = longer * camera.exposure_for(t, 140) / analogue_gain_factor(gain_db);
  const cv::Mat dark = dark_from_image(camera.render_dark(scene.cols, scene.rows, exposure));
  cv::Mat signal;
  subtract_dark(camera.render(scene, exposure, 0.7, gain_db), dark + dark_error_dn, 220, signal);
  const int period = p.mosaic.kind == MosaicLayout::Kind::kSnapshot ? p.mosaic.period_width : 2;
  DarkLevelSamples samples;
  add_dark_level_samples(signal, period, period, 0, samples);
  return dark_level_verdict(samples, 8);
}

TEST(DarkLevelCheck, a_dark_20_dn_off_shows_and_the_cameras_own_does_not) {
  for (const char* profile : {"rgb-reference", "nir5x5-reference"}) {
    const CameraProfile p = load_profile_by_name(profile);
    for (const char* unit : {"typical", "hostile"})
      for (double t : {800.0, 2500.0})
        for (double area : {0.36, 0.9, 1.0})
          for (double longer : {0.3, 1.0, 2.0})
            for (double gain_db : {0.0, 24.0}) {
              SCOPED_TRACE(std::string(profile) + " " + unit + " " + std::to_string(t) +
                           " degC, area " + std::to_string(area) + ", x" + std::to_string(longer) +
                           ", " + std::to_string(gain_db) + " dB");
              const cv::Mat scene = plate_scene(320, 240, t, area);
              const DarkLevelVerdict right = verdict_of(p, unit, scene, t, longer, gain_db, 0);
              // (A frame-filling plate exposed for longer saturates a band everywhere.)
              if (area < 1 && longer <= 1) {
                ASSERT_TRUE(right.decided);
              }
              EXPECT_EQ(right.offset_dn, 0) << right.least_dn << ".." << right.most_dn;
              for (double error : {-20.0, 20.0}) {
                const DarkLevelVerdict off = verdict_of(p, unit, scene, t, longer, gain_db, error);
                // Never the wrong way; with a background and the noise of 0 dB, found.
                EXPECT_LE(off.offset_dn * error, 0) << error;
                if (area < 0.5 && gain_db == 0) {
                  EXPECT_NEAR(off.offset_dn, -error, 3) << off.least_dn << ".." << off.most_dn;
                }
              }
            }
  }
}

TEST(DarkLevelCheck, melt_pools_read_right_with_the_cameras_dark) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  for (int i = 0; i < 100; i += 9) {
    SCOPED_TRACE(i);
    const cv::Mat scene = melt_pool_scene(320, 240, i, 100);
    EXPECT_EQ(verdict_of(p, "typical", scene, 2000, 1, 0, 0).offset_dn, 0);
    EXPECT_NEAR(verdict_of(p, "typical", scene, 2000, 1, 0, -20).offset_dn, 20, 3);
  }
}

TEST(DarkLevelCheck, waits_for_enough_samples_of_every_place) {
  DarkLevelSamples samples;
  add_dark_level_samples(cv::Mat(8, 8, CV_32F, cv::Scalar(30)), 2, 2, 0, samples);
  EXPECT_FALSE(dark_level_verdict(samples, 8).decided);
  EXPECT_TRUE(dark_level_verdict(samples, 8, 16).decided);
  EXPECT_THROW(add_dark_level_samples(cv::Mat(8, 8, CV_8U), 2, 2, 0, samples), InputError);
}

// Every frame until a first verdict, then every 8th; the message says which way and how much.
TEST(DarkLevelCheck, the_watch_samples_every_8th_frame_after_a_verdict) {
  cv::Mat frame(240, 320, CV_32F);
  cv::RNG rng(3);
  rng.fill(frame, cv::RNG::NORMAL, 20, 1);  // a background 20 DN up
  DarkLevelWatch watch;
  std::string verdicts;
  for (int i = 0; i < 17; ++i) {
    const auto v = watch.add(frame, 2, 8);
    verdicts += v ? "v" : ".";
    if (v) {
      EXPECT_NEAR(v->offset_dn, 20, 1);
    }
  }
  EXPECT_EQ(verdicts, "v.......v.......v");
  DarkLevelVerdict v;
  v.offset_dn = -20, v.least_dn = -21, v.most_dn = -19;
  EXPECT_EQ(dark_level_message(v, "dark-level 70 DN", "the frame's").substr(0, 68),
            "after the dark (dark-level 70 DN) the frame's darkest parts read -20");
  EXPECT_NE(dark_level_message(v, "", "x").find("about 20 DN too high"), std::string::npos);
}

}  // namespace
}  // namespace pyrocam
