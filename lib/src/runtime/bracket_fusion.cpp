#include "pyrocam/runtime/bracket_fusion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "pyrocam/core/error.h"
#include "runtime/bracket_motion.h"

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

MosaicBracketFusion::MosaicBracketFusion(int frames, int period)
    : frames_(frames), period_(period) {
  if (frames < 1 || frames > kMaxBracketFrames)
    throw InputError("mosaic bracket fusion: frames must be 1.." +
                     std::to_string(kMaxBracketFrames) + ", not " + std::to_string(frames));
  if (period < 1 || period > 16)
    throw InputError("mosaic bracket fusion: the mosaic's period must be 1..16, not " +
                     std::to_string(period));
}

namespace {

// Samples of a band this many cells away, along rows, columns and diagonals, are its
// neighbours: 24 of them. Where one of n neighbours decides, a sample alone saturating decides
// by its own noise still: the fused values lean phi(z) Phi(z)^n of a sample's standard
// deviation low (z: the surface's distance below the level in them), at most 0.077 with 8
// neighbours and 0.033 with 24.
constexpr int kNeighbourCells = 2;
// Samples below this fraction of the largest number seen are left to the plain rule: a sample's
// noise at the saturation level is a few percent of the level at most (the shot noise of a
// well of a thousand electrons is 3 %), so they are not near it; and on a steep side, where a
// neighbour saturates, a far dimmer sample would come from a much shorter exposure, with far
// more noise (without it the bracket targets' wild readings rose from 0.4 to 1.9 %).
constexpr float kNearLevelFraction = 0.85f;

// A frame whose content moved less than this since is fused where it is, not interpolated.
constexpr double kLeastShiftPx = 0.25;

// An earlier frame's sample whose brightness changed by more than this (in the logarithm: a
// factor 2) since is not fused: a change found as a steady rate over a cycle is no measure of
// one that large (a light switched on, an arc struck), and a sample brought forward that far
// could read anything.
constexpr float kMostLogChange = 0.6931472f;

// MosaicBracketFusion::Agreement's bound on a sample's noise (see there).
constexpr double kMotionShotDnPerDn = 1;
constexpr double kMotionFloorDn2 = 4;
constexpr double kMotionRelative = 0.05;
constexpr double kMotionDeviations = 4;

// How `now` (light `now_light`) agrees with `before`: samples in [low, high] in both.
MosaicBracketFusion::Agreement agreement(const cv::Mat& now, double now_light,
                                         const cv::Mat& before, double before_light, double low,
                                         double high) {
  MosaicBracketFusion::Agreement a;
  const double reference = std::max(now_light, before_light);
  const double s_now = reference / now_light, s_before = reference / before_light;
  for (int y = 0; y < now.rows; ++y) {
    const float *p = now.ptr<float>(y), *q = before.ptr<float>(y);
    for (int x = 0; x < now.cols; ++x) {
      const double u = p[x], v = q[x];
      if (!(u >= low && u <= high && v >= low && v <= high)) continue;  // NaN, +INF fail
      ++a.compared;
      const double su = u * s_now, sv = v * s_before;
      const double variance = (kMotionShotDnPerDn * u + kMotionFloorDn2) * s_now * s_now +
                              (kMotionShotDnPerDn * v + kMotionFloorDn2) * s_before * s_before;
      a.disagreeing += std::abs(su - sv) >
                       kMotionDeviations * std::sqrt(variance) + kMotionRelative * std::max(su, sv);
    }
  }
  return a;
}

// 1 where a sample within kNeighbourCells cells of its band's grid (`period` pixels a cell) is
// +INF and the sample is at least kNearLevelFraction of `largest`, the largest number seen, this
// frame's included (it is raised to it): at most the saturation level less the dark. A
// dilation made of a pass along rows and one along columns.
cv::Mat near_saturated(const cv::Mat& signal, int period, float& largest) {
  const int w = signal.cols, h = signal.rows, reach = kNeighbourCells * period;
  cv::Mat saturated(signal.size(), CV_8U), along_rows(signal.size(), CV_8U),
      out(signal.size(), CV_8U);
  for (int y = 0; y < h; ++y) {
    const float* v = signal.ptr<float>(y);
    std::uint8_t* m = saturated.ptr<std::uint8_t>(y);
    for (int x = 0; x < w; ++x) {
      m[x] = v[x] == INFINITY;
      if (v[x] < INFINITY && v[x] > largest) largest = v[x];
    }
  }
  const float near_level = kNearLevelFraction * largest;
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* m = saturated.ptr<std::uint8_t>(y);
    std::uint8_t* r = along_rows.ptr<std::uint8_t>(y);
    for (int x = 0; x < w; ++x) {
      std::uint8_t any = 0;
      for (int dx = -reach; dx <= reach; dx += period)
        if (x + dx >= 0 && x + dx < w) any |= m[x + dx];
      r[x] = any;
    }
  }
  for (int y = 0; y < h; ++y) {
    const float* v = signal.ptr<float>(y);
    std::uint8_t* o = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < w; ++x) o[x] = 0;
    for (int dy = -reach; dy <= reach; dy += period) {
      if (y + dy < 0 || y + dy >= h) continue;
      const std::uint8_t* r = along_rows.ptr<std::uint8_t>(y + dy);
      for (int x = 0; x < w; ++x) o[x] |= r[x];
    }
    for (int x = 0; x < w; ++x) o[x] &= v[x] >= near_level;
  }
  return out;
}

}  // namespace

double MosaicBracketFusion::add(const cv::Mat& signal, double light, cv::Mat& out) {
  if (signal.type() != CV_32F)
    throw InputError("mosaic bracket fusion: mosaics must be float32 (dark-subtracted)");
  if (!(light > 0) || !std::isfinite(light))
    throw InputError("mosaic bracket fusion: a frame's exposure must be above 0, not " +
                     std::to_string(light));
  if (!held_.empty() && held_.front().signal.size() != signal.size()) reset();
  Held now{signal.clone(), near_saturated(signal, period_, largest_), light, {}, {}, {}};
  agreement_ = held_.empty() ? Agreement{}
                             : agreement(now.signal, light, held_.back().signal, held_.back().light,
                                         kMotionLowDn, kNearLevelFraction * largest_);
  if (follows_motion_ && frames_ > 1) {
    now.cells = bracket_motion::cell_logs(signal, period_, static_cast<float>(kMotionLowDn),
                                          kNearLevelFraction * largest_);
    // The last frame with the same light (exposures repeat exactly, cycle after cycle). A
    // velocity found holds for a cycle: a short exposure's frame may show too little to find it.
    ++frames_since_velocity_;
    const Held* same = nullptr;  // the last frame with the same light, `same_age` frames ago
    std::size_t same_age = 0;
    bool found = false, still = false;
    cv::Point2d shift;
    for (std::size_t age = 1; age <= held_.size() && !same; ++age) {
      const Held& h = held_[held_.size() - age];
      if (std::abs(h.light - light) > 1e-9 * light) continue;
      same = &h, same_age = age;
      found = bracket_motion::find_shift(now.cells, h.cells, period_, shift, &still);
      if (found) {
        velocity_ = shift / static_cast<double>(age);
        frames_since_velocity_ = 0;
      }
    }
    if (frames_since_velocity_ >= frames_) velocity_ = {};
    // How the brightness changed since, where the content's move is known (found, still, or
    // the velocity held from a frame before).
    if (same && (found || still || velocity_ != cv::Point2d()))
      now.rates = bracket_motion::log_rates(now.cells, same->cells,
                                            found   ? shift
                                            : still ? cv::Point2d()
                                                    : velocity_ * static_cast<double>(same_age),
                                            period_, static_cast<int>(same_age));
  }
  // The frames fused by light, most first; among equals the latest first. Each with the shift
  // of its content since (its age times the velocity).
  struct Fused {
    const Held* held;
    bracket_motion::Displacement displacement;
    bool displaced;
    float age;
  };
  std::vector<Fused> order{{&now, {{}, period_}, false, 0}};
  const std::size_t fused = std::min<std::size_t>(held_.size(), frames_ - 1);
  std::vector<cv::Mat> rates{now.rates};
  std::vector<cv::Point2d> shifts{cv::Point2d()};
  for (std::size_t age = 1; age <= fused; ++age) {
    const cv::Point2d shift = velocity_ * static_cast<double>(age);
    Held& h = held_[held_.size() - age];
    const bool displaced = std::hypot(shift.x, shift.y) >= kLeastShiftPx;
    if (displaced && h.logs.empty()) h.logs = bracket_motion::sample_logs(h.signal);
    order.push_back({&h, {shift, period_}, displaced, static_cast<float>(age)});
    rates.push_back(h.rates), shifts.push_back(shift);
  }
  // A log brightness change a frame at each of the latest frame's cells (0: none known); an
  // earlier frame's samples are brought forward by their age's worth of it.
  const cv::Mat change =
      follows_motion_ ? bracket_motion::brightness_change(rates, shifts, period_) : cv::Mat();
  std::stable_sort(order.begin(), order.end(),
                   [](const Fused& a, const Fused& b) { return a.held->light > b.held->light; });
  const double reference = order.front().held->light;
  std::vector<float> scale;
  for (const Fused& f : order) scale.push_back(static_cast<float>(reference / f.held->light));
  out.create(signal.size(), CV_32F);
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  std::vector<bracket_motion::DisplacedRow> rows;
  rows.reserve(order.size());
  std::vector<const float*> values(order.size());
  std::vector<const std::uint8_t*> near_level(order.size());
  for (int y = 0; y < out.rows; ++y) {
    // Each frame's row, a displaced frame's read where its content was.
    rows.clear();
    for (std::size_t k = 0; k < order.size(); ++k) {
      const Held& h = *order[k].held;
      rows.emplace_back(h.signal, h.near_saturated, h.logs, order[k].displacement, y);
      values[k] = h.signal.ptr<float>(y);
      near_level[k] = h.near_saturated.ptr<std::uint8_t>(y);
    }
    float* o = out.ptr<float>(y);
    const float* change_row =
        !change.empty() && y / period_ < change.rows ? change.ptr<float>(y / period_) : nullptr;
    for (int x = 0; x < out.cols; ++x) {
      const float rate = change_row && x / period_ < change.cols ? change_row[x / period_] : 0.0f;
      float first_number = kNaN;  // the first frame's whose sample is a number, scaled
      bool missing = false, taken = false;
      for (std::size_t k = 0; k < order.size() && !taken; ++k) {
        bool near;
        float v;
        if (order[k].displaced) {
          v = rows[k].at(x, &near);
        } else {
          v = values[k][x];
          near = near_level[k][x] != 0;
        }
        const float change_since = rate * order[k].age;
        if (std::isfinite(v) && std::abs(change_since) > kMostLogChange) {
          missing = true;  // no reading rather than a guess at what it shows now
          continue;
        }
        if (std::isfinite(v)) {
          const float brought = change_since != 0 ? v * std::exp(change_since) : v;
          if (std::isnan(first_number)) first_number = brought * scale[k];
          if (!near) {
            o[x] = brought * scale[k];
            taken = true;
          }
        }
        missing |= std::isnan(v);
      }
      if (taken) continue;
      // As everywhere in the chain, no reading (NaN) wins over saturated.
      o[x] = !std::isnan(first_number) ? first_number : missing ? kNaN : INFINITY;
    }
  }
  held_.push_back(std::move(now));
  const int kept = follows_motion_ && frames_ > 1 ? frames_ : frames_ - 1;
  while (static_cast<int>(held_.size()) > kept) held_.pop_front();
  return reference;
}

}  // namespace pyrocam
