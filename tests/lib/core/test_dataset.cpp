// The dataset format: a simulated campaign round-trips, and every promised rejection happens.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

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

// An ROI larger than the frame holds is refused before anything is written, with the largest
// that fits.
TEST(SimulatedCampaign, refuses_an_roi_the_frame_cannot_hold_and_writes_nothing_n) {
  ScratchDir dir{"campaign-roi"};
  Simulator camera(load_profile_by_name("rgb-reference"), UnitPerturbation{"typical", 3});
  CampaignSettings s = tiny_campaign();
  s.roi_area_px = 6000;  // the CLI's default, on a 40x32 frame
  const std::filesystem::path folder = dir / "campaign";
  try {
    write_furnace_campaign(folder, camera, s);
    ADD_FAILURE() << "wrote a campaign whose ROI does not fit";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("an ROI of 6000 px (--roi-area) does not fit a 40x32 "
                                         "frame: it takes from 1 to 889 px there"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(folder));
  s.roi_area_px = 889;  // the largest, accepted
  EXPECT_NO_THROW(write_furnace_campaign(folder, camera, s));
}

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
  expect_rejected("kind 'flat' must be 'frame', 'dark' or 'reference'");
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
  // The first frames of that exposure, by their file and manifest line.
  expect_rejected(
      "frames/T0900_e02_f0.pgm (manifest.csv line 10): frames at 900 degC, exposure 158.76 us have "
      "no dark row of that exposure");
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

TEST(Manifest, without_uncertainties_the_four_column_form_is_written_as_before) {
  ScratchDir dir("manifest4");
  write_manifest(dir / "manifest.csv", {{"a.pgm", FrameKind::kFrame, 1000, 125.99},
                                        {"c.pgm", FrameKind::kDark, 100, 125.99}});
  std::ifstream in(dir / "manifest.csv");
  const std::string text(std::istreambuf_iterator<char>(in), {});
  EXPECT_EQ(
      text,
      "file,kind,temperature_c,exposure_us\na.pgm,frame,1000,125.99\nc.pgm,dark,100,125.99\n");
  for (const auto& r : read_manifest(dir / "manifest.csv"))
    EXPECT_TRUE(std::isnan(r.temperature_uncertainty_c));
}

TEST(Manifest, the_uncertainty_column_round_trips_and_may_be_empty) {
  ScratchDir dir("manifest5");
  write_manifest(dir / "manifest.csv", {{"a.pgm", FrameKind::kFrame, 1000, 125.99},
                                        {"r.pgm", FrameKind::kReference, 1738, 2.5, 0.3},
                                        {"c.pgm", FrameKind::kDark, 100, 2.5}});
  std::ifstream in(dir / "manifest.csv");
  const std::string text(std::istreambuf_iterator<char>(in), {});
  EXPECT_EQ(text,
            "file,kind,temperature_c,exposure_us,temperature_uncertainty_c\n"
            "a.pgm,frame,1000,125.99,\nr.pgm,reference,1738,2.5,0.3\nc.pgm,dark,100,2.5,\n");
  const auto back = read_manifest(dir / "manifest.csv");
  ASSERT_EQ(back.size(), 3u);
  EXPECT_EQ(back[1].kind, FrameKind::kReference);
  EXPECT_DOUBLE_EQ(back[1].temperature_c, 1738);
  EXPECT_DOUBLE_EQ(back[1].temperature_uncertainty_c, 0.3);
  EXPECT_EQ(back[1].line, 3);
  EXPECT_TRUE(std::isnan(back[0].temperature_uncertainty_c));
  EXPECT_TRUE(std::isnan(back[2].temperature_uncertainty_c));
  // Under the five-column header a row may also leave the column out.
  write_text(dir / "manifest.csv",
             "file,kind,temperature_c,exposure_us,temperature_uncertainty_c\na.pgm,frame,1000,"
             "125.99\nr.pgm,reference,1738,2.5,1.5\n");
  EXPECT_DOUBLE_EQ(read_manifest(dir / "manifest.csv")[1].temperature_uncertainty_c, 1.5);
}

TEST(Manifest, rejects_an_uncertainty_that_is_not_a_number_above_zero_n) {
  ScratchDir dir("manifest-u");
  const std::string header = "file,kind,temperature_c,exposure_us,temperature_uncertainty_c\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"-0.5", "manifest.csv:3: temperature_uncertainty_c must be > 0"},
      {"0", "manifest.csv:3: temperature_uncertainty_c must be > 0"},
      {"nan", "manifest.csv:3 temperature_uncertainty_c: 'nan' is not a number"},
      {"abc", "manifest.csv:3 temperature_uncertainty_c: 'abc' is not a number"},
      {"0.5,1", "manifest.csv:3: 6 fields, expected 5"}};
  for (const auto& [value, needle] : cases) {
    write_text(dir / "manifest.csv",
               header + "a.pgm,frame,1000,100,\nr.pgm,reference,1738,2.5," + value + "\n");
    try {
      read_manifest(dir / "manifest.csv");
      ADD_FAILURE() << "accepted " << value;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  }
}

// A spreadsheet's UTF-8 byte-order mark before the header is not part of it.
TEST(Manifest, reads_a_header_after_a_byte_order_mark) {
  ScratchDir dir("manifest-bom");
  write_text(dir / "manifest.csv",
             "\xEF\xBB\xBF"
             "file,kind,temperature_c,exposure_us\na.pgm,frame,1000,100\n");
  const auto rows = read_manifest(dir / "manifest.csv");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].file, "a.pgm");
}

// One image is one setting: listed again at another temperature, exposure or kind it is
// refused, naming both lines; a dark may serve several furnace temperatures, and a row may be
// repeated as it is.
TEST(Manifest, refuses_one_image_listed_at_two_settings_n) {
  ScratchDir dir("manifest-twice");
  const std::string header = "file,kind,temperature_c,exposure_us\n";
  write_text(dir / "manifest.csv", header +
                                       "d.pgm,dark,100,100\nd.pgm,dark,700,100\n"
                                       "a.pgm,frame,700,100\na.pgm,frame,700,100\n");
  EXPECT_EQ(read_manifest(dir / "manifest.csv").size(), 4u);
  const std::vector<std::string> second = {"frames/../a.pgm,frame,800,100", "a.pgm,frame,700,126",
                                           "a.pgm,dark,700,100", "d.pgm,dark,100,126"};
  for (const std::string& row : second) {
    write_text(dir / "manifest.csv",
               header + "d.pgm,dark,100,100\na.pgm,frame,700,100\n" + row + "\n");
    try {
      read_manifest(dir / "manifest.csv");
      ADD_FAILURE() << "accepted " << row;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("manifest.csv:4: "), std::string::npos) << what;
      EXPECT_NE(what.find("is also listed at line"), std::string::npos) << what;
      EXPECT_NE(what.find("one image is one setting"), std::string::npos) << what;
    }
  }
}

// The same tiny campaign with one reference source, a Pt-C cell at 1738 degC.
class ReferenceDatasetFiles : public DatasetFiles {
 protected:
  void SetUp() override {
    Simulator camera(load_profile_by_name("rgb-reference"), UnitPerturbation{"typical", 3});
    CampaignSettings s = tiny_campaign();
    s.reference_temperatures_c = {1738};
    write_furnace_campaign(dir.path(), camera, s);
  }
  // Rewrites the manifest through read_manifest/write_manifest.
  template <typename Edit>
  void edit_rows(const Edit& edit) {
    std::vector<ManifestRow> rows = read_manifest(dir / "manifest.csv");
    edit(rows);
    write_manifest(dir / "manifest.csv", rows);
  }
  // The manifest line of the first row of kind reference at `exposure_us` (-1: none).
  int first_reference_line(double exposure_us) {
    for (const auto& r : read_manifest(dir / "manifest.csv"))
      if (r.kind == FrameKind::kReference && same_exposure(r.exposure_us, exposure_us))
        return r.line;
    return -1;
  }
};

TEST_F(ReferenceDatasetFiles, references_are_grouped_apart_from_the_frames) {
  const Dataset d = Dataset::open(dir.path());
  ASSERT_EQ(d.references().size(), 3u);  // 3 exposures
  for (const FrameGroup& g : d.references()) {
    EXPECT_EQ(g.kind, FrameKind::kReference);
    EXPECT_DOUBLE_EQ(g.temperature_c, 1738);
    EXPECT_DOUBLE_EQ(g.temperature_uncertainty_c, 0.5);
    EXPECT_EQ(g.files.size(), 2u);
    EXPECT_GT(g.line, 1);
    EXPECT_DOUBLE_EQ(d.dark_for(g.exposure_us).exposure_us, g.exposure_us);
  }
  EXPECT_LT(d.references()[0].exposure_us, d.references()[1].exposure_us);
  ASSERT_EQ(d.frames().size(), 6u);
  for (const FrameGroup& g : d.frames()) EXPECT_TRUE(std::isnan(g.temperature_uncertainty_c));
  EXPECT_EQ(d.temperatures_c(), (std::vector<double>{900, 1000}));
  EXPECT_EQ(d.darks().size(), 6u);  // the furnace's 3 exposures and the reference's 3
  EXPECT_FALSE(d.has_reference_roi());
  EXPECT_EQ(cv::countNonZero(d.reference_roi() != d.roi()), 0);
}

TEST_F(ReferenceDatasetFiles, the_furnace_part_is_the_same_without_references) {
  ScratchDir plain("dataset-plain");
  Simulator camera(load_profile_by_name("rgb-reference"), UnitPerturbation{"typical", 3});
  write_furnace_campaign(plain.path(), camera, tiny_campaign());
  const auto text = [](const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  // Every row of the plain manifest is a row of the other, there with an empty fifth column.
  std::istringstream plain_rows(text(plain / "manifest.csv"));
  const std::string with_refs = text(dir / "manifest.csv");
  std::string line;
  std::getline(plain_rows, line);
  EXPECT_EQ(line, kManifestHeader);
  EXPECT_EQ(with_refs.rfind(std::string(kManifestHeaderWithUncertainty) + "\n", 0), 0u);
  int rows = 0;
  while (std::getline(plain_rows, line)) {
    ++rows;
    EXPECT_NE(with_refs.find(line + ",\n"), std::string::npos) << line;
    const std::string file = line.substr(0, line.find(','));
    EXPECT_EQ(text(plain / file), text(dir / file)) << file;
  }
  EXPECT_EQ(rows, 18);  // (2 temperatures + darks) x 3 exposures x 2 frames
  const std::string truth = text(plain / "furnace-truth.csv");
  EXPECT_EQ(text(dir / "furnace-truth.csv").rfind(truth, 0), 0u);
  EXPECT_EQ(text(plain / "roi.png"), text(dir / "roi.png"));
}

TEST_F(ReferenceDatasetFiles, an_empty_uncertainty_means_half_a_degree) {
  edit_rows([](std::vector<ManifestRow>& rows) {
    for (auto& r : rows) r.temperature_uncertainty_c = NAN;  // written in the 4-column form
  });
  EXPECT_DOUBLE_EQ(Dataset::open(dir.path()).references()[0].temperature_uncertainty_c,
                   kDefaultReferenceUncertaintyC);
  edit_rows([](std::vector<ManifestRow>& rows) {
    for (auto& r : rows)
      if (r.kind == FrameKind::kReference) r.temperature_uncertainty_c = 1.5;
  });
  const Dataset d = Dataset::open(dir.path());
  for (const auto& g : d.references()) EXPECT_DOUBLE_EQ(g.temperature_uncertainty_c, 1.5);
}

TEST_F(ReferenceDatasetFiles, rejects_a_reference_exposure_without_its_dark_n) {
  const double exposure = Dataset::open(dir.path()).references()[1].exposure_us;
  edit_rows([&](std::vector<ManifestRow>& rows) {
    rows.erase(std::remove_if(rows.begin(), rows.end(),
                              [&](const ManifestRow& r) {
                                return r.kind == FrameKind::kDark &&
                                       same_exposure(r.exposure_us, exposure);
                              }),
               rows.end());
  });
  std::ostringstream e;
  e << std::setprecision(15) << "(manifest.csv line " << first_reference_line(exposure)
    << "): reference at 1738 degC, exposure " << exposure << " us has no dark row of that exposure";
  expect_rejected(e.str());
}

TEST_F(ReferenceDatasetFiles, rejects_rows_of_one_reference_stating_different_uncertainties_n) {
  const double exposure = Dataset::open(dir.path()).references()[2].exposure_us;
  edit_rows([&](std::vector<ManifestRow>& rows) {
    for (auto& r : rows)
      if (r.kind == FrameKind::kReference && same_exposure(r.exposure_us, exposure))
        r.temperature_uncertainty_c = 2;
  });
  expect_rejected("(manifest.csv line " + std::to_string(first_reference_line(exposure)) +
                  "): temperature_uncertainty_c 2 differs from the 0.5 that line");
}

TEST_F(ReferenceDatasetFiles, rejects_an_empty_or_misfit_reference_roi_n) {
  write_raw_image(dir / kReferenceRoiFile, cv::Mat::zeros(32, 40, CV_8U));
  expect_rejected("reference-roi.png: the reference ROI is empty (no nonzero pixel)");
  write_raw_image(dir / kReferenceRoiFile, cv::Mat(30, 40, CV_8U, cv::Scalar(255)));
  expect_rejected("reference-roi.png: image is 40x30, the ROI's size is 40x32");
  cv::Mat small = cv::Mat::zeros(32, 40, CV_8U);
  small(cv::Rect(10, 10, 6, 6)) = 1;
  write_raw_image(dir / kReferenceRoiFile, small);
  const Dataset d = Dataset::open(dir.path());
  EXPECT_TRUE(d.has_reference_roi());
  EXPECT_EQ(cv::countNonZero(d.reference_roi()), 36);
  EXPECT_EQ(d.reference_roi().at<std::uint8_t>(12, 12), 255);
}

}  // namespace
}  // namespace pyrocam
