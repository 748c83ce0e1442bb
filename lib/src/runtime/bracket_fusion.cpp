#include "pyrocam/runtime/bracket_fusion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "pyrocam/core/error.h"

namespace pyrocam {

std::vector<double> parse_bracket(const std::string& text) {
  std::vector<double> factors;
  if (text.empty()) return factors;
  std::size_t at = 0;
  for (;;) {
    const std::size_t comma = text.find(',', at);
    const std::string item = text.substr(at, comma == std::string::npos ? comma : comma - at);
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || end == item.c_str() || *end != '\0' || !(v >= kMinBracketFactor) ||
        !(v <= kMaxBracketFactor))
      throw InputError("bracket '" + text + "': '" + item +
                       "' is no exposure factor from 0.001 to 1000 (comma-separated numbers)");
    factors.push_back(v);
    if (comma == std::string::npos) break;
    at = comma + 1;
  }
  if (static_cast<int>(factors.size()) > kMaxBracketFrames)
    throw InputError("bracket '" + text + "' has more than " + std::to_string(kMaxBracketFrames) +
                     " exposures");
  return factors;
}

BracketFusion::BracketFusion(int frames) : frames_(frames) {
  if (frames < 1 || frames > kMaxBracketFrames)
    throw InputError("bracket fusion: frames must be 1.." + std::to_string(kMaxBracketFrames) +
                     ", not " + std::to_string(frames));
}

void BracketFusion::add(const cv::Mat& decikelvin, double light, cv::Mat& out) {
  if (decikelvin.type() != CV_16U)
    throw InputError("bracket fusion: temperature frames must be 16-bit codes");
  if (!(light > 0) || !std::isfinite(light))
    throw InputError("bracket fusion: a frame's exposure must be above 0, not " +
                     std::to_string(light));
  if (!held_.empty() && held_.front().decikelvin.size() != decikelvin.size()) held_.clear();
  const cv::Mat latest = decikelvin.clone();
  // The frames by light, most first; among equals the latest first.
  std::vector<const Held*> order;
  const Held now{latest, light};
  order.push_back(&now);
  for (auto it = held_.rbegin(); it != held_.rend(); ++it) order.push_back(&*it);
  std::stable_sort(order.begin(), order.end(),
                   [](const Held* a, const Held* b) { return a->light > b->light; });
  out.create(decikelvin.size(), CV_16U);
  for (int y = 0; y < out.rows; ++y) {
    std::uint16_t* o = out.ptr<std::uint16_t>(y);
    std::fill(o, o + out.cols, std::uint16_t{0});
    for (const Held* h : order) {
      const std::uint16_t* in = h->decikelvin.ptr<std::uint16_t>(y);
      for (int x = 0; x < out.cols; ++x) o[x] = o[x] != 0 ? o[x] : in[x];
    }
  }
  held_.push_back(now);
  while (static_cast<int>(held_.size()) > frames_ - 1) held_.pop_front();
}

MosaicBracketFusion::MosaicBracketFusion(int frames) : frames_(frames) {
  if (frames < 1 || frames > kMaxBracketFrames)
    throw InputError("mosaic bracket fusion: frames must be 1.." +
                     std::to_string(kMaxBracketFrames) + ", not " + std::to_string(frames));
}

double MosaicBracketFusion::add(const cv::Mat& signal, double light, cv::Mat& out) {
  if (signal.type() != CV_32F)
    throw InputError("mosaic bracket fusion: mosaics must be float32 (dark-subtracted)");
  if (!(light > 0) || !std::isfinite(light))
    throw InputError("mosaic bracket fusion: a frame's exposure must be above 0, not " +
                     std::to_string(light));
  if (!held_.empty() && held_.front().signal.size() != signal.size()) held_.clear();
  const Held now{signal.clone(), light};
  // The frames by light, most first; among equals the latest first.
  std::vector<const Held*> order;
  order.push_back(&now);
  for (auto it = held_.rbegin(); it != held_.rend(); ++it) order.push_back(&*it);
  std::stable_sort(order.begin(), order.end(),
                   [](const Held* a, const Held* b) { return a->light > b->light; });
  const double reference = order.front()->light;
  std::vector<float> scale;
  for (const Held* h : order) scale.push_back(static_cast<float>(reference / h->light));
  out.create(signal.size(), CV_32F);
  constexpr float kInf = std::numeric_limits<float>::infinity();
  for (int y = 0; y < out.rows; ++y) {
    float* o = out.ptr<float>(y);
    for (int x = 0; x < out.cols; ++x) {
      bool missing = false, taken = false;
      for (std::size_t k = 0; k < order.size() && !taken; ++k) {
        const float v = order[k]->signal.ptr<float>(y)[x];
        if (std::isfinite(v)) {
          o[x] = v * scale[k];
          taken = true;
        }
        missing |= std::isnan(v);
      }
      // As everywhere in the chain, no reading (NaN) wins over saturated.
      if (!taken) o[x] = missing ? std::numeric_limits<float>::quiet_NaN() : kInf;
    }
  }
  held_.push_back(now);
  while (static_cast<int>(held_.size()) > frames_ - 1) held_.pop_front();
  return reference;
}

}  // namespace pyrocam
