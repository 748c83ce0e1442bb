// The furnace calibration dataset: a folder with manifest.csv, raw mosaic images and an ROI
// mask (format in docs/dataset-format.md). Frames are streamed, never all held in memory.
#pragma once

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace pyrocam {

// frame: the furnace plate; dark: no light; reference: a source at a known temperature beyond
// the furnace (fixed-point cell, strip lamp, ...) whose absolute scale is unknown.
enum class FrameKind { kFrame, kDark, kReference };

struct ManifestRow {
  std::string file;  // relative to the dataset folder
  FrameKind kind = FrameKind::kFrame;
  double temperature_c = 0;
  double exposure_us = 0;
  // Standard uncertainty (k=1) of temperature_c, degC, from the optional column
  // temperature_uncertainty_c; NaN where not given.
  double temperature_uncertainty_c = NAN;
  int line = 0;  // in manifest.csv, for messages (0: not read from a file)
};

// All rows that share one (kind, temperature, exposure) setting; their images are averaged.
struct FrameGroup {
  FrameKind kind = FrameKind::kFrame;
  double temperature_c = 0;
  double exposure_us = 0;
  // Standard uncertainty of temperature_c, degC: the value the rows state, NaN where none does;
  // for references the default kDefaultReferenceUncertaintyC where none does.
  double temperature_uncertainty_c = NAN;
  int line = 0;                              // the setting's first manifest line
  std::vector<std::filesystem::path> files;  // absolute
};

// The header of a manifest without, and with, the optional uncertainty column.
inline constexpr const char* kManifestHeader = "file,kind,temperature_c,exposure_us";
inline constexpr const char* kManifestHeaderWithUncertainty =
    "file,kind,temperature_c,exposure_us,temperature_uncertainty_c";
// A reference row's standard uncertainty, degC, when its temperature_uncertainty_c is empty.
inline constexpr double kDefaultReferenceUncertaintyC = 0.5;
// Optional mask beside roi.png for reference rows (a reference source is often smaller than the
// furnace plate); without it reference rows use the ROI.
inline constexpr const char* kReferenceRoiFile = "reference-roi.png";
// Optional file beside the manifest naming the images' mosaic layout, since a raw image carries
// none: one line, "rggb", "bggr", "grbg", "gbrg" (Bayer, by the top-left cell) or a snapshot
// period such as "5x5".
inline constexpr const char* kMosaicFile = "mosaic.txt";

class Dataset {
 public:
  // Reads and checks manifest.csv, the ROI and reference-roi.png; checks every listed file
  // exists, every frame and reference exposure has a dark, and that the rows of one reference
  // state one uncertainty. Image sizes are checked as images are loaded. Throws InputError.
  static Dataset open(const std::filesystem::path& folder);

  const std::filesystem::path& folder() const { return folder_; }
  // Settings of kind frame, each averaging the rows that share it (calibration), sorted by
  // temperature then exposure.
  const std::vector<FrameGroup>& frames() const { return frames_; }
  // Settings of kind reference, grouped and sorted like frames(): the rows of one reference
  // temperature are one source swept over exposure.
  const std::vector<FrameGroup>& references() const { return references_; }
  // Every row in manifest order (sequences, where each frame stands alone).
  const std::vector<ManifestRow>& rows() const { return rows_; }
  std::filesystem::path path_of(const ManifestRow& row) const { return folder_ / row.file; }
  const std::vector<FrameGroup>& darks() const { return darks_; }  // by exposure
  const FrameGroup& dark_for(double exposure_us) const;
  std::vector<double> temperatures_c() const;  // of the frames (not the references)
  const cv::Mat& roi() const { return roi_; }  // CV_8U, 255 inside
  // The mask for reference rows: reference-roi.png when the dataset has one, else roi().
  const cv::Mat& reference_roi() const { return reference_roi_.empty() ? roi_ : reference_roi_; }
  bool has_reference_roi() const { return !reference_roi_.empty(); }
  int width() const { return roi_.cols; }
  int height() const { return roi_.rows; }
  int bit_depth() const { return bit_depth_; }  // of the first image loaded (0 before)
  // The images' layout from mosaic.txt, lower case; empty when the dataset has no mosaic.txt.
  const std::string& mosaic_pattern() const { return mosaic_pattern_; }

  // Mean of a group's images as CV_64F. Throws InputError naming a file that is unreadable or
  // whose size or sample type differs from the dataset's.
  cv::Mat average(const FrameGroup& group) const;
  // One image, checked as above.
  cv::Mat load(const std::filesystem::path& file) const;

 private:
  std::filesystem::path folder_;
  std::vector<ManifestRow> rows_;
  std::vector<FrameGroup> frames_, darks_, references_;
  cv::Mat roi_, reference_roi_;
  std::string mosaic_pattern_;
  mutable int bit_depth_ = 0;
};

// A mosaic layout name, trimmed and in lower case, as `pyrocam-calib measure` compares it with
// the model's: a Bayer pattern or a snapshot period "WxH". Throws InputError "<where>: ..." for
// anything else.
std::string parse_mosaic_pattern(const std::string& text, const std::string& where);
// Writes `pattern` to folder/mosaic.txt.
void write_mosaic_pattern(const std::filesystem::path& folder, const std::string& pattern);

// Reads either header (kManifestHeader, kManifestHeaderWithUncertainty). Throws InputError naming
// the line for a wrong field count, an unknown kind, a non-number, an exposure <= 0 or an
// uncertainty that is not a number > 0.
std::vector<ManifestRow> read_manifest(const std::filesystem::path& manifest_csv);
// Writes the uncertainty column only when some row has a finite temperature_uncertainty_c
// (empty in the others), so that a manifest without uncertainties is written as before.
void write_manifest(const std::filesystem::path& manifest_csv,
                    const std::vector<ManifestRow>& rows);

// Equal within a relative tolerance: exposures written as text round-trip.
bool same_exposure(double a_us, double b_us);

}  // namespace pyrocam
