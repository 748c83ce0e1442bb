#include "pyrocam/runtime/dark_level_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "pyrocam/core/error.h"
#include "pyrocam/runtime/darksub.h"

namespace pyrocam {

void add_dark_level_samples(const cv::Mat& signal, int period_width, int period_height,
                            unsigned frame, DarkLevelSamples& samples) {
  if (signal.type() != CV_32F) throw InputError("dark level check: the mosaic must be CV_32F");
  if (period_width < 1 || period_height < 1)
    throw InputError("dark level check: the mosaic period must be at least 1x1");
  if (samples.period_width != period_width || samples.period_height != period_height) {
    samples.period_width = period_width;
    samples.period_height = period_height;
    samples.by_place.assign(static_cast<std::size_t>(period_width * period_height), {});
  }
  const int period_rows = signal.rows / period_height, period_cols = signal.cols / period_width;
  if (period_rows < 1 || period_cols < 1) return;
  // About 32 rows and 64 columns of periods a frame.
  const int row_step = std::max(1, period_rows / 32), col_step = std::max(1, period_cols / 64);
  for (int pr = static_cast<int>(frame % static_cast<unsigned>(row_step)); pr < period_rows;
       pr += row_step)
    for (int dy = 0; dy < period_height; ++dy) {
      const float* row = signal.ptr<float>(pr * period_height + dy);
      for (int pc = 0; pc < period_cols; pc += col_step)
        for (int dx = 0; dx < period_width; ++dx) {
          const float v = row[pc * period_width + dx];
          if (std::isfinite(v))
            samples.by_place[static_cast<std::size_t>(dy * period_width + dx)].push_back(v);
        }
    }
}

DarkLevelVerdict dark_level_verdict(DarkLevelSamples& samples, int bit_depth,
                                    std::size_t min_samples) {
  DarkLevelVerdict v;
  if (samples.by_place.empty()) return v;
  for (const auto& place : samples.by_place)
    if (place.size() < min_samples) return v;
  v.decided = true;
  std::vector<double> centres;
  double noise = 0;
  for (auto& place : samples.by_place) {
    // The means of the lowest 20 % and 5 % (smooth where the samples are whole DN, as
    // percentiles are not): of a normal background N(mu, sigma), mu - 1.400 sigma and
    // mu - 2.063 sigma.
    const auto n20 = static_cast<std::ptrdiff_t>(0.20 * static_cast<double>(place.size()));
    const auto n05 = static_cast<std::ptrdiff_t>(0.05 * static_cast<double>(place.size()));
    std::nth_element(place.begin(), place.begin() + n20, place.end());
    std::nth_element(place.begin(), place.begin() + n05, place.begin() + n20);
    double sum05 = 0, sum20 = 0;
    for (std::ptrdiff_t i = 0; i < n20; ++i)
      (i < n05 ? sum05 : sum20) += place[static_cast<std::size_t>(i)];
    const double m05 = sum05 / static_cast<double>(n05);
    const double m20 = (sum05 + sum20) / static_cast<double>(n20);
    const double sigma = std::max(0.0, (m20 - m05) / (2.063 - 1.400));
    centres.push_back(m20 + 1.400 * sigma);
    noise = std::max(noise, sigma);
  }
  v.least_dn = *std::min_element(centres.begin(), centres.end());
  v.most_dn = *std::max_element(centres.begin(), centres.end());
  const double beyond = std::max(0.02 * full_scale_dn(bit_depth), 4 * noise);
  const bool low = v.least_dn > beyond && v.most_dn <= 1.2 * v.least_dn;
  const bool high = v.most_dn < -beyond && -v.least_dn <= -1.2 * v.most_dn;
  if (low || high) {
    double sum = 0;
    for (double c : centres) sum += c;
    v.offset_dn = sum / static_cast<double>(centres.size());
  }
  for (auto& place : samples.by_place) place.clear();
  return v;
}

std::optional<DarkLevelVerdict> DarkLevelWatch::add(const cv::Mat& signal, int period,
                                                    int bit_depth) {
  const unsigned frame = frame_++;
  if (decided_ && frame % 8 != 0) return std::nullopt;
  add_dark_level_samples(signal, period, period, decided_ ? frame / 8 : frame, samples_);
  const DarkLevelVerdict v = dark_level_verdict(samples_, bit_depth);
  if (!v.decided) return std::nullopt;
  decided_ = true;
  return v;
}

std::string dark_level_message(const DarkLevelVerdict& v, const std::string& dark_used,
                               const std::string& frames) {
  char text[400];
  std::snprintf(text, sizeof text,
                "after the dark%s%s%s %s darkest parts read %+.0f DN (%.0f..%.0f) in every band "
                "alike, where a cold background reads 0: the dark is about %.0f DN too %s for "
                "this camera, and the temperatures would look right and be wrong",
                dark_used.empty() ? "" : " (", dark_used.c_str(), dark_used.empty() ? "" : ")",
                frames.c_str(), v.offset_dn, v.least_dn, v.most_dn, std::abs(v.offset_dn),
                v.offset_dn > 0 ? "low" : "high");
  return text;
}

}  // namespace pyrocam
