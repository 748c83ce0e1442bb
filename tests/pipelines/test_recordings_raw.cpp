// Raw recordings (record.sh RAW=1): the camera's mosaic beside the temperatures, measured again
// by `pyrocam-calib measure --recording` with the settings the temperatures' tags name, and
// refused with a model of another mosaic.
#include <gtest/gtest.h>

#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "element_support.h"
#include "pipeline_support.h"
#include "recording_files.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

namespace fs = std::filesystem;
using namespace recording_files;  // NOLINT(google-build-using-namespace)

constexpr int kWidth = 320, kHeight = 240, kFrames = 30;  // two 0.5 s segments
const std::string kScene = "pyrocamsrc scene=melt-pool seed=7";

// RAW=1: the camera's mosaic recorded beside the temperatures, frame for frame; measured again
// with the same model it gives the recorded codes bit for bit (with the settings the temperature
// segments' tags say they were read with: here brightness-radius=2), with another model others.
TEST(RecordingsRaw, remeasured_with_its_model_gives_the_recorded_codes_and_another_model_not) {
  for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp"}) REQUIRE_ELEMENT(e);
  ScratchDir dir("recordings-raw");
  const fs::path rec = dir / "rec";
  const Env env = {{"MODEL", rgb_model()},
                   {"OUT", rec.string()},
                   {"SOURCE", kScene},
                   {"CAPS", "video/x-bayer,format=rggb,width=320,height=240,framerate=30/1"},
                   {"NUM_BUFFERS", std::to_string(kFrames)},
                   {"SEGMENT_SECONDS", "0.5"},
                   {"BRIGHTNESS_RADIUS", "2"},
                   {"RAW", "1"}};
  const ScriptRun run =
      run_script("record.sh", {}, env, (dir / "record.log").string(), milliseconds(60000));
  ASSERT_EQ(run.status, 0) << run.log;
  const auto raw = files_in(rec.string(), "raw-", ".mkv");
  ASSERT_EQ(raw.size(), 2u);
  for (const auto& file : raw) {
    const std::string comment = discovered_tags(file).second;
    EXPECT_EQ(comment, "pyrocam-raw; dark=dark-level=50; pattern=rggb") << file;
  }
  const std::string tool = "'" + std::string(PYROCAM_CALIB_TOOL) + "' -q ";
  const fs::path recorded = dir / "recorded.npy";
  ASSERT_EQ(run_command(tool + "export --recording '" + rec.string() + "' --npy '" +
                            recorded.string() + "'",
                        dir / "export.log"),
            0)
      << read_text(dir / "export.log");
  const Npy codes = read_npy(recorded);
  ASSERT_EQ(codes.shape, (std::vector<long>{kFrames, kHeight, kWidth}));

  // The same model and method (auto, as ratiotemp's default): the recorded codes exactly.
  const auto measure = [&](const std::string& model, const std::string& out) {
    return run_command(tool + "measure --recording '" + rec.string() + "' --model '" + model +
                           "' --method auto --out '" + (dir / out).string() + "'",
                       dir / (out + ".log"));
  };
  ASSERT_EQ(measure(rgb_model(), "same"), 0) << read_text(dir / "same.log");
  const Npy same = read_npy(dir / "same" / "temperature.npy");
  EXPECT_EQ(same.shape, codes.shape);
  EXPECT_TRUE(same.data == codes.data) << "re-measured codes differ from the recorded ones";
  EXPECT_EQ(read_csv(dir / "same" / "temperature.csv").size(), kFrames + 1u);
  EXPECT_EQ(read_text(dir / "same.log").find("dark"), std::string::npos)
      << read_text(dir / "same.log");

  // A dark that is not the camera's (its black is 50 DN) is said, as darksub says it, even
  // with -q: the cold background reads 20 DN above 0 in every place of the mosaic.
  ASSERT_EQ(
      run_command(tool + "measure --recording '" + rec.string() + "' --model '" + rgb_model() +
                      "' --dark-level 30 --out '" + (dir / "dark-30").string() + "'",
                  dir / "dark-30.log"),
      0)
      << read_text(dir / "dark-30.log");
  EXPECT_NE(read_text(dir / "dark-30.log").find("too low"), std::string::npos)
      << read_text(dir / "dark-30.log");

  // demosaic25's method comes from the tags too: the first raw segment read again through
  // bilinear demosaicking, as a user's own pipeline might have, measures to those codes.
  const fs::path bilinear = dir / "bilinear";
  fs::create_directories(bilinear);
  fs::copy_file(raw[0], bilinear / "raw-00000.mkv");
  ASSERT_EQ(run_command("gst-launch-1.0 -q filesrc location='" + raw[0] +
                            "' ! matroskademux ! avdec_ffv1 ! capssetter join=false "
                            "caps=video/x-bayer,format=rggb ! darksub dark-level=50 ! "
                            "demosaic25 method=bilinear ! ratiotemp model='" +
                            rgb_model() +
                            "' ! avenc_ffv1 gop-size=1 ! matroskamux ! filesink "
                            "location='" +
                            (bilinear / "temperature-00000.mkv").string() + "'",
                        dir / "bilinear.log"),
            0)
      << read_text(dir / "bilinear.log");
  ASSERT_EQ(run_command(tool + "export --recording '" + bilinear.string() + "' --npy '" +
                            (dir / "bilinear.npy").string() + "' && " + tool +
                            "measure --recording '" + bilinear.string() + "' --model '" +
                            rgb_model() + "' --out '" + (dir / "bilinear-out").string() + "'",
                        dir / "bilinear-measure.log"),
            0)
      << read_text(dir / "bilinear-measure.log");
  const Npy bilinear_codes = read_npy(dir / "bilinear.npy");
  ASSERT_FALSE(bilinear_codes.data.empty());
  EXPECT_FALSE(bilinear_codes.data == same.data.substr(0, bilinear_codes.data.size()))
      << "bilinear demosaicking read as matched does";
  EXPECT_TRUE(read_npy(dir / "bilinear-out" / "temperature.npy").data == bilinear_codes.data)
      << "re-measured codes differ from those recorded through bilinear demosaicking";

  // A later segment read with other settings is said, naming it.
  Env plain = env;
  plain["OUT"] = (dir / "plain").string();
  plain["BRIGHTNESS_RADIUS"] = "0";
  plain["NUM_BUFFERS"] = "5";
  ASSERT_EQ(
      run_script("record.sh", {}, plain, (dir / "plain.log").string(), milliseconds(60000)).status,
      0);
  fs::copy(rec, dir / "mixed");
  fs::copy_file(dir / "plain" / "temperature-00000.mkv", dir / "mixed" / "temperature-00001.mkv",
                fs::copy_options::overwrite_existing);
  ASSERT_EQ(run_command("'" + std::string(PYROCAM_CALIB_TOOL) + "' measure --recording '" +
                            (dir / "mixed").string() + "' --model '" + rgb_model() + "' --out '" +
                            (dir / "mixed-out").string() + "'",
                        dir / "mixed.log"),
            0);
  EXPECT_NE(read_text(dir / "mixed.log")
                .find("temperature-00001.mkv was read with brightness-radius 0, "
                      "temperature-00000.mkv with 2"),
            std::string::npos)
      << read_text(dir / "mixed.log");

  // Another model: a hostile unit of the same camera type, calibrated as the test model is.
  const fs::path other = dir / "other.json", campaign = dir / "campaign";
  ASSERT_EQ(run_command(tool + "simulate campaign --profile rgb-reference --unit hostile " +
                            "--frames 2 --size 64x64 --roi-area 1500 --out '" + campaign.string() +
                            "' && " + tool + "calibrate --dataset '" + campaign.string() +
                            "' --profile rgb-reference --solver regularised " +
                            "--epochs 30 --polish-iterations 50 --mc-refits 0 --locus-step 2 " +
                            "--out '" + other.string() + "'",
                        dir / "other.log"),
            0)
      << read_text(dir / "other.log");
  ASSERT_EQ(measure(other.string(), "other"), 0) << read_text(dir / "other.log");
  const Npy changed = read_npy(dir / "other" / "temperature.npy");
  ASSERT_EQ(changed.data.size(), codes.data.size());
  std::size_t both = 0, differ = 0;
  for (std::size_t i = 0; i + 1 < codes.data.size(); i += 2) {
    const int a = static_cast<unsigned char>(codes.data[i]) |
                  static_cast<unsigned char>(codes.data[i + 1]) << 8;
    const int b = static_cast<unsigned char>(changed.data[i]) |
                  static_cast<unsigned char>(changed.data[i + 1]) << 8;
    if (a && b) {
      ++both;
      differ += a != b;
    }
  }
  std::cout << "[ info     ] another model: " << differ << " of " << both
            << " readings in both differ\n";
  EXPECT_GT(both, static_cast<std::size_t>(kFrames) * 10);
  EXPECT_GT(differ * 2, both) << "another model left most readings unchanged";

  // A model of another mosaic is refused, naming both.
  ASSERT_EQ(measure(test_model("test-model-nir5x5.json"), "nir"), 1);
  EXPECT_NE(read_text(dir / "nir.log").find("5x5 mosaic"), std::string::npos)
      << read_text(dir / "nir.log");
  EXPECT_NE(read_text(dir / "nir.log").find("rggb Bayer mosaic"), std::string::npos)
      << read_text(dir / "nir.log");
}

// The raw tags say the mosaic whatever the caps say (the default simulated camera's, its
// profile's rggb), and the temperatures' tags the camera profile: a model of another mosaic is
// refused, not read as nonsense. A temperature segment given as the recording is refused, saying
// which segments measure reads. A Bayer recording whose tags name no layout is refused unless
// --pattern names it (read as the model's rggb a bggr camera read 1300 degC at 631), and so is
// RAW=1 where record.sh cannot know the layout; darksub's saturation level in DARK is measure's.
TEST(RecordingsRaw, a_model_of_another_mosaic_is_refused_whatever_the_caps_say) {
  for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp"}) REQUIRE_ELEMENT(e);
  ScratchDir dir("recordings-raw-mosaic");
  const std::string tool = "'" + std::string(PYROCAM_CALIB_TOOL) + "' ";
  const auto measure = [&](const fs::path& rec, const std::string& model, const std::string& log) {
    return run_command(tool + "measure --recording '" + rec.string() + "' --model '" + model +
                           "' --out '" + (dir / (log + "-out")).string() + "'",
                       dir / (log + ".log"));
  };
  const fs::path nir = dir / "nir", rgb = dir / "rgb";
  ASSERT_EQ(run_script("record.sh", {},
                       {{"PROFILE", "nir5x5-reference"},
                        {"MODEL", test_model("test-model-nir5x5.json")},
                        {"OUT", nir.string()},
                        {"NUM_BUFFERS", "3"},
                        {"RAW", "1"}},
                       (dir / "nir-record.log").string(), milliseconds(60000))
                .status,
            0)
      << read_text(dir / "nir-record.log");
  const auto nir_raw = files_in(nir.string(), "raw-", ".mkv");
  ASSERT_EQ(nir_raw.size(), 1u);
  EXPECT_EQ(discovered_tags(nir_raw[0]).second, "pyrocam-raw; dark=dark-level=50; pattern=5x5");
  EXPECT_EQ(measure(nir, rgb_model(), "nir-with-rgb"), 1);
  EXPECT_NE(read_text(dir / "nir-with-rgb.log")
                .find("the model was calibrated for a rggb Bayer mosaic (profile rgb-reference), "
                      "the recording " +
                      nir.string() + " for a 5x5 mosaic"),
            std::string::npos)
      << read_text(dir / "nir-with-rgb.log");

  ASSERT_EQ(run_script(
                "record.sh", {},
                {{"MODEL", rgb_model()}, {"OUT", rgb.string()}, {"NUM_BUFFERS", "3"}, {"RAW", "1"}},
                (dir / "rgb-record.log").string(), milliseconds(60000))
                .status,
            0)
      << read_text(dir / "rgb-record.log");
  const auto rgb_raw = files_in(rgb.string(), "raw-", ".mkv");
  ASSERT_EQ(rgb_raw.size(), 1u);
  EXPECT_EQ(discovered_tags(rgb_raw[0]).second, "pyrocam-raw; dark=dark-level=50; pattern=rggb");
  EXPECT_EQ(measure(rgb, test_model("test-model-nir5x5.json"), "rgb-with-nir"), 1);
  EXPECT_NE(
      read_text(dir / "rgb-with-nir.log").find("for a rggb Bayer mosaic (profile rgb-reference"),
      std::string::npos)
      << read_text(dir / "rgb-with-nir.log");
  EXPECT_EQ(measure(rgb, rgb_model(), "rgb-with-rgb"), 0) << read_text(dir / "rgb-with-rgb.log");

  const auto temperatures = files_in(rgb.string(), "temperature-", ".mkv");
  ASSERT_EQ(temperatures.size(), 1u);
  EXPECT_EQ(measure(temperatures[0], rgb_model(), "temperatures"), 1);
  EXPECT_NE(read_text(dir / "temperatures.log").find("holds temperatures"), std::string::npos)
      << read_text(dir / "temperatures.log");

  // Tags without the layout (as record.sh wrote them with a CAPS without format=).
  const fs::path untold = dir / "untold";
  fs::create_directories(untold);
  ASSERT_EQ(run_command("gst-launch-1.0 -q pyrocamsrc num-buffers=3 ! "
                        "video/x-bayer,width=320,height=240,framerate=30/1 ! capssetter "
                        "join=false caps=video/x-raw,format=GRAY8 ! taginject "
                        "'tags=\"comment=\\\"pyrocam-raw; dark=dark-level=50\\\"\"' ! avenc_ffv1 "
                        "gop-size=1 ! matroskamux ! filesink location='" +
                            (untold / "raw-00000.mkv").string() + "'",
                        dir / "untold-make.log"),
            0)
      << read_text(dir / "untold-make.log");
  ASSERT_EQ(discovered_tags((untold / "raw-00000.mkv").string()).second,
            "pyrocam-raw; dark=dark-level=50");
  EXPECT_EQ(measure(untold, rgb_model(), "untold"), 1);
  EXPECT_NE(read_text(dir / "untold.log").find("does not say its Bayer layout"), std::string::npos)
      << read_text(dir / "untold.log");
  EXPECT_EQ(
      run_command(tool + "measure --recording '" + untold.string() + "' --model '" + rgb_model() +
                      "' --pattern rggb --out '" + (dir / "untold-rggb").string() + "'",
                  dir / "untold-rggb.log"),
      0)
      << read_text(dir / "untold-rggb.log");

  Env custom = {{"MODEL", rgb_model()},
                {"OUT", (dir / "custom").string()},
                {"SOURCE", "pyrocamsrc is-live=true"},
                {"NUM_BUFFERS", "3"},
                {"RAW", "1"}};
  EXPECT_EQ(run_script("record.sh", {}, custom, (dir / "custom.log").string(), milliseconds(60000))
                .status,
            2);
  EXPECT_NE(read_text(dir / "custom.log").find("RAW=1 needs the camera's Bayer layout"),
            std::string::npos)
      << read_text(dir / "custom.log");
  EXPECT_FALSE(fs::exists(dir / "custom")) << "a refused setting left OUT behind";
  // The layout from DARK, the camera's Bayer frames carried as gray video (the overlay then goes
  // over the gray mosaic: bayer2rgb takes video/x-bayer only).
  custom["DARK"] = "dark-level=50 pattern=rggb saturation-level=150";
  custom["CAPS"] =
      "video/x-bayer,width=320,height=240,framerate=30/1 ! capssetter join=false "
      "caps=video/x-raw,format=GRAY8,width=320,height=240,framerate=30/1";
  ASSERT_EQ(run_script("record.sh", {}, custom, (dir / "custom.log").string(), milliseconds(60000))
                .status,
            0)
      << read_text(dir / "custom.log");
  ASSERT_EQ(run_command(tool + "-q export --recording '" + (dir / "custom").string() + "' --npy '" +
                            (dir / "custom.npy").string() + "'",
                        dir / "custom-export.log"),
            0)
      << read_text(dir / "custom-export.log");
  ASSERT_EQ(measure(dir / "custom", rgb_model(), "custom-measure"), 0)
      << read_text(dir / "custom-measure.log");
  const Npy low_saturation = read_npy(dir / "custom.npy");
  EXPECT_TRUE(read_npy(dir / "custom-measure-out" / "temperature.npy").data == low_saturation.data)
      << "saturation-level=150 in DARK not measure's";
  // With its saturation at 150 DN the simulated plate reads little (every codes' pair 0 in most
  // pixels), unlike the default camera's recording.
  std::size_t zero = 0;
  for (std::size_t i = 0; i + 1 < low_saturation.data.size(); i += 2)
    zero += low_saturation.data[i] == 0 && low_saturation.data[i + 1] == 0;
  EXPECT_GT(zero * 2, low_saturation.data.size() / 2) << "saturation-level=150 changed nothing";
}

}  // namespace
}  // namespace pyrocam::test
