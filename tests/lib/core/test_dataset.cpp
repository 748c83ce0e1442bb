// The dataset format: a simulated campaign round-trips, and every promised rejection happens.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "pyrocam/core/dataset.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::ScratchDir;
using test::write_text;

CampaignSettings tiny_campaign() {
  CampaignSettings s;
  s.temperatures_c = {900, 1000};
  s.exposure_count = 3;
  s.frames_per_setting = 2;
  s.width = 40;
  s.height = 32;
  s.roi_area_px = 300;
  return s;
}

class DatasetFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    Simulator camera(load_profile_by_name("rgb-reference"), UnitPerturbation{"typical", 3});
    write_furnace_campaign(dir.path(), camera, tiny_campaign());
  }
  void expect_rejected(const std::string& needle) {
    try {
      const Dataset d = Dataset::open(dir.path());
      for (const auto& g : d.frames()) d.average(g);
      ADD_FAILURE() << "accepted a dataset that should fail with: " << needle;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  }
  void rewrite_manifest(const std::string& from, const std::string& to) {
    std::ifstream in(dir / "manifest.csv");
    std::string text(std::istreambuf_iterator<char>(in), {});
    const auto pos = text.find(from);
    ASSERT_NE(pos, std::string::npos) << from;
    text.replace(pos, from.size(), to);
    write_text(dir / "manifest.csv", text);
  }
  ScratchDir dir{"dataset"};
};

TEST_F(DatasetFiles, simulated_campaign_round_trips) {
  const Dataset d = Dataset::open(dir.path());
  EXPECT_EQ(d.width(), 40);
  EXPECT_EQ(d.height(), 32);
  ASSERT_EQ(d.frames().size(), 6u);  // 2 temperatures x 3 exposures
  EXPECT_EQ(d.darks().size(), 3u);
  EXPECT_EQ(d.temperatures_c(), (std::vector<double>{900, 1000}));
  EXPECT_NEAR(d.frames()[1].exposure_us, 126.0, 1e-9);
  const FrameGroup& g = d.frames()[4];
  ASSERT_EQ(g.files.size(), 2u);
  const cv::Mat mean = d.average(g);
  cv::Mat a, b;
  read_raw_image(g.files[0]).convertTo(a, CV_64F);
  read_raw_image(g.files[1]).convertTo(b, CV_64F);
  EXPECT_LT(cv::norm(mean, (a + b) / 2, cv::NORM_INF), 1e-12);
  EXPECT_EQ(d.bit_depth(), 8);
  const int roi_px = cv::countNonZero(d.roi());
  EXPECT_NEAR(roi_px, 300, 30);
  EXPECT_DOUBLE_EQ(d.dark_for(g.exposure_us).exposure_us, g.exposure_us);
}

TEST_F(DatasetFiles, rejects_missing_manifest_n) {
  std::filesystem::remove(dir / "manifest.csv");
  expect_rejected("manifest not found");
}

TEST_F(DatasetFiles, rejects_a_fifo_as_manifest_without_blocking_n) {
  std::filesystem::remove(dir / "manifest.csv");
  ASSERT_EQ(mkfifo((dir / "manifest.csv").c_str(), 0600), 0);
  expect_rejected("manifest.csv: manifest is not a regular file (a FIFO, socket or device)");
}

TEST_F(DatasetFiles, rejects_a_directory_listed_as_an_image_n) {
  std::filesystem::remove(dir / "frames/T0900_e01_f1.pgm");
  std::filesystem::create_directory(dir / "frames/T0900_e01_f1.pgm");
  expect_rejected("T0900_e01_f1.pgm (manifest.csv line 11): is a directory, not an image");
}

TEST_F(DatasetFiles, rejects_a_path_climbing_out_of_the_folder_n) {
  rewrite_manifest("frames/T0900_e01_f1.pgm", "frames/../../T0900_e01_f1.pgm");
  expect_rejected(
      "manifest.csv:11: file 'frames/../../T0900_e01_f1.pgm' leaves the dataset folder");
}

TEST_F(DatasetFiles, rejects_an_unknown_mosaic_layout_n) {
  write_text(dir / "mosaic.txt", "rgbg\n");
  expect_rejected("mosaic.txt: mosaic layout 'rgbg' is not rggb, bggr, grbg, gbrg");
}

TEST_F(DatasetFiles, reads_the_mosaic_layout_the_simulator_wrote) {
  EXPECT_EQ(Dataset::open(dir.path()).mosaic_pattern(), "rggb");
  std::filesystem::remove(dir / "mosaic.txt");
  EXPECT_EQ(Dataset::open(dir.path()).mosaic_pattern(), "");
}

TEST_F(DatasetFiles, rejects_wrong_header_n) {
  rewrite_manifest("file,kind,temperature_c,exposure_us", "file,kind,temp,exposure");
  expect_rejected("first line must be 'file,kind,temperature_c,exposure_us'");
}

TEST_F(DatasetFiles, rejects_non_numeric_temperature_n) {
  rewrite_manifest(",frame,900,", ",frame,hot,");
  expect_rejected("temperature_c: 'hot' is not a number");
}

TEST_F(DatasetFiles, rejects_non_numeric_exposure_n) {
  rewrite_manifest(",dark,100,100\n", ",dark,100,1e\n");
  expect_rejected("exposure_us: '1e' is not a number");
}

TEST_F(DatasetFiles, rejects_unknown_kind_n) {
  rewrite_manifest(",frame,900,", ",flat,900,");
  expect_rejected("kind 'flat' must be 'frame' or 'dark'");
}

TEST_F(DatasetFiles, rejects_missing_image_n) {
  std::filesystem::remove(dir / "frames/T0900_e01_f1.pgm");
  expect_rejected("T0900_e01_f1.pgm (manifest.csv line 11): listed but not found");
}

TEST_F(DatasetFiles, rejects_exposure_without_dark_n) {
  // Drop every dark row of the longest exposure.
  std::ifstream in(dir / "manifest.csv");
  std::string line, kept;
  while (std::getline(in, line))
    if (line.find(",dark,") == std::string::npos || line.find("158.76") == std::string::npos)
      kept += line + "\n";
  write_text(dir / "manifest.csv", kept);
  expect_rejected("no dark frame for exposure 158.76 us");
}

TEST_F(DatasetFiles, rejects_empty_roi_n) {
  write_raw_image(dir / "roi.png", cv::Mat::zeros(32, 40, CV_8U));
  expect_rejected("the ROI is empty");
}

TEST_F(DatasetFiles, rejects_missing_roi_n) {
  std::filesystem::remove(dir / "roi.png");
  expect_rejected("no roi.png or roi.pgm");
}

TEST_F(DatasetFiles, rejects_images_of_different_sizes_n) {
  write_raw_image(dir / "frames/T1000_e02_f0.pgm", cv::Mat::zeros(30, 40, CV_8U));
  expect_rejected("T1000_e02_f0.pgm: image is 40x30, the dataset's (ROI) size is 40x32");
}

TEST_F(DatasetFiles, rejects_mixed_bit_depths_n) {
  write_raw_image(dir / "frames/T1000_e02_f1.pgm", cv::Mat::zeros(32, 40, CV_16U));
  expect_rejected("16-bit image in a 8-bit dataset");
}

TEST_F(DatasetFiles, rejects_truncated_pgm_n) {
  const auto f = dir / "frames/T0900_e00_f0.pgm";
  std::filesystem::resize_file(f, std::filesystem::file_size(f) - 100);
  expect_rejected("truncated PGM");
}

TEST_F(DatasetFiles, rejects_truncated_png_n) {
  cv::Mat img(32, 40, CV_8U);
  cv::randu(img, 0, 255);
  const auto f = dir / "frames/T0900_e00_f0.png";
  write_raw_image(f, img);
  std::filesystem::resize_file(f, std::filesystem::file_size(f) / 2);
  rewrite_manifest("frames/T0900_e00_f0.pgm", "frames/T0900_e00_f0.png");
  expect_rejected("T0900_e00_f0.png: unreadable or truncated image");
}

TEST_F(DatasetFiles, rejects_garbage_image_n) {
  write_text(dir / "frames/T0900_e01_f0.pgm", "this is not an image");
  expect_rejected("T0900_e01_f0.pgm");
}

TEST_F(DatasetFiles, rejects_colour_image_n) {
  cv::imwrite((dir / "frames/T0900_e01_f0.png").string(), cv::Mat::zeros(32, 40, CV_8UC3));
  rewrite_manifest("frames/T0900_e01_f0.pgm", "frames/T0900_e01_f0.png");
  expect_rejected("3 channels; raw mosaic images must be single-channel");
}

TEST(Manifest, rows_sharing_a_setting_are_grouped_and_texts_round_trip) {
  ScratchDir dir("manifest");
  std::vector<ManifestRow> rows = {{"a.pgm", FrameKind::kFrame, 1000, 125.99},
                                   {"b.pgm", FrameKind::kFrame, 1000, 125.99},
                                   {"c.pgm", FrameKind::kDark, 100, 125.99}};
  write_manifest(dir / "manifest.csv", rows);
  const auto back = read_manifest(dir / "manifest.csv");
  ASSERT_EQ(back.size(), 3u);
  EXPECT_EQ(back[2].kind, FrameKind::kDark);
  EXPECT_DOUBLE_EQ(back[1].exposure_us, 125.99);
}

}  // namespace
}  // namespace pyrocam
