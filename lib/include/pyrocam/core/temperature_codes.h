// The temperature code, the one wire format for temperatures between ratiotemp, thermalcolormap,
// recordings and the command-line tool: GRAY16 in units of 0.1 K, 0 = no reading. Everything
// that writes or reads codes does so through this header.
#pragma once

#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>

#include "pyrocam/core/physics.h"

namespace pyrocam {

inline constexpr double kCodesPerKelvin = 10;       // one code = 0.1 K
inline constexpr std::uint16_t kNoReadingCode = 0;  // NaN, or a temperature the code cannot hold
inline constexpr std::uint16_t kMaxCode = 65535;    // 6553.5 K

// degC to code: round((t + 273.15) * 10), 0 for NaN or a result outside 1..65535 (0.1..6553.5 K).
inline std::uint16_t temperature_code(double temperature_c) {
  const double code = std::round((temperature_c + kZeroCelsius) * kCodesPerKelvin);
  return code >= 1 && code <= kMaxCode ? static_cast<std::uint16_t>(code)
                                       : kNoReadingCode;  // NaN fails both
}

// Code to degC; NaN for 0 (no reading).
inline double code_to_celsius(std::uint16_t code) {
  return code != kNoReadingCode ? code / kCodesPerKelvin - kZeroCelsius : NAN;
}

// CV_32F degC -> CV_16U codes, written into `codes`, which may wrap a caller's buffer: written in
// place when its size and type fit, else (re)allocated. Throws InputError for another type.
void encode_decikelvin(const cv::Mat& temperature_c, cv::Mat& codes);
cv::Mat encode_decikelvin(const cv::Mat& temperature_c);
// One row of n values, for loops that encode while the row is in cache.
void encode_temperature_row(const float* in, std::uint16_t* out, int n);
// CV_16U codes -> CV_32F degC (NaN for 0).
cv::Mat decode_decikelvin(const cv::Mat& codes);

// Temperature differences such as expanded uncertainties, in the same 0.1 K steps but without
// the 273.15 offset: round(10 * value), at least 1 (a reading is never 0) and at most 65535;
// 0 for NaN, infinite or negative values.
inline std::uint16_t difference_code(double difference_c) {
  if (!std::isfinite(difference_c) || difference_c < 0) return kNoReadingCode;
  const double code = std::round(difference_c * kCodesPerKelvin);
  return static_cast<std::uint16_t>(code < 1 ? 1 : code > kMaxCode ? kMaxCode : code);
}
inline double difference_code_to_celsius(std::uint16_t code) {
  return code != kNoReadingCode ? code / kCodesPerKelvin : NAN;
}
cv::Mat encode_decikelvin_difference(const cv::Mat& difference_c);
cv::Mat decode_decikelvin_difference(const cv::Mat& codes);

}  // namespace pyrocam
