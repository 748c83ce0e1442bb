// The export formats of a temperature recording (`pyrocam-calib export`, and `measure
// --recording` for re-measured frames): a 16-bit multi-page TIFF, a uint16 .npy and a CSV of
// per-frame statistics, each written under a temporary name and renamed when complete.
#pragma once

#include <fstream>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace pyrocam::cli {

struct ExportPaths {
  std::string tiff, npy, csv;  // empty: not written
  int peak_window = 5;         // for the CSV's peak_c
};

class ExportWriter {
 public:
  // Opens the outputs (throws InputError naming one that cannot be written).
  explicit ExportWriter(const ExportPaths& paths);
  ~ExportWriter();  // removes what was not finished
  ExportWriter(const ExportWriter&) = delete;
  ExportWriter& operator=(const ExportWriter&) = delete;
  // One frame of codes (CV_16U, 0.1 K, 0 = no reading), in order.
  void add(std::size_t index, double timestamp_s, const cv::Mat& codes);
  // Completes every output under its name.
  void finish();
  std::size_t frames() const { return frames_; }

 private:
  struct Output;
  ExportPaths paths_;
  std::unique_ptr<Output> npy_out_, csv_out_, tiff_out_;
  std::ofstream npy_, csv_;
  std::vector<cv::Mat> pages_;
  std::size_t tiff_bytes_ = 0, frames_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace pyrocam::cli
