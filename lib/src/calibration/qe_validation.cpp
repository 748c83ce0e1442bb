// How well a QE fit predicts rates it was not fitted to: residuals on held-out rates,
// cross-validation over temperature groups, and the extrapolation check (fit the cooler
// temperatures, predict the hottest).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "pyrocam/calibration/qe_fit.h"

namespace pyrocam {
namespace {

// Prediction error sums for pooling over folds.
void prediction_sums(const CameraProfile& profile, const QeFitResult& fit,
                     const CalibrationRates& data, Eigen::VectorXd& ss, Eigen::VectorXd& count) {
  for (std::size_t i = 0; i < data.temperatures_c.size(); ++i) {
    const Eigen::VectorXd sim =
        fitted_signal_rates(profile, fit, celsius_to_kelvin(data.temperatures_c[i]));
    for (int b = 0; b < profile.band_count(); ++b) {
      const double m = data.rates(b, static_cast<Eigen::Index>(i));
      if (!(std::isfinite(m) && m > 0)) continue;  // no usable rate
      ss[b] += (sim[b] / m - 1) * (sim[b] / m - 1);
      count[b] += 1;
    }
  }
}

CalibrationRates subset(const CalibrationRates& data, const std::vector<Eigen::Index>& cols) {
  CalibrationRates out;
  out.rates.resize(data.rates.rows(), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t c = 0; c < cols.size(); ++c) {
    out.temperatures_c.push_back(data.temperatures_c[cols[c]]);
    out.rates.col(static_cast<Eigen::Index>(c)) = data.rates.col(cols[c]);
  }
  return out;
}

std::vector<Eigen::Index> sorted_by_temperature(const CalibrationRates& data) {
  std::vector<Eigen::Index> idx(data.temperatures_c.size());
  std::iota(idx.begin(), idx.end(), 0);
  std::stable_sort(idx.begin(), idx.end(),
                   [&](auto a, auto b) { return data.temperatures_c[a] < data.temperatures_c[b]; });
  return idx;
}

}  // namespace

Eigen::VectorXd prediction_residuals(const CameraProfile& profile, const QeFitResult& fit,
                                     const CalibrationRates& data) {
  Eigen::VectorXd ss = Eigen::VectorXd::Zero(profile.band_count()), count = ss;
  prediction_sums(profile, fit, data, ss, count);
  return (ss.array() / count.array()).sqrt().matrix();  // NaN where a band has no rates
}

CrossValidation cross_validate(const CameraProfile& profile, const CalibrationRates& data,
                               const QeFitOptions& options, int groups) {
  const std::vector<Eigen::Index> order = sorted_by_temperature(data);
  if (groups < 2 || static_cast<std::size_t>(groups) > order.size())
    throw InputError("QE cross-validation: " + std::to_string(groups) + " groups for " +
                     std::to_string(order.size()) + " temperatures");
  CrossValidation cv;
  Eigen::VectorXd ss = Eigen::VectorXd::Zero(profile.band_count()), count = ss;
  for (int g = 0; g < groups; ++g) {
    std::vector<Eigen::Index> train, test;
    for (std::size_t i = 0; i < order.size(); ++i)
      (static_cast<int>(i % static_cast<std::size_t>(groups)) == g ? test : train)
          .push_back(order[i]);
    cv.folds.push_back(fit_qe(profile, subset(data, train), options));
    prediction_sums(profile, cv.folds.back(), subset(data, test), ss, count);
  }
  cv.heldout_residual = (ss.array() / count.array()).sqrt().matrix();
  Eigen::MatrixXd mean = Eigen::MatrixXd::Zero(profile.band_count(), profile.grid.size());
  for (const auto& f : cv.folds) mean += f.system_qe;
  mean /= groups;
  Eigen::MatrixXd var = Eigen::MatrixXd::Zero(mean.rows(), mean.cols());
  for (const auto& f : cv.folds) var += (f.system_qe - mean).cwiseAbs2();
  cv.qe_spread = (var / (groups - 1)).cwiseSqrt();
  return cv;
}

ExtrapolationCheck extrapolation_check(const CameraProfile& profile, const CalibrationRates& data,
                                       const QeFitOptions& options, int hottest_held_out) {
  const std::vector<Eigen::Index> order = sorted_by_temperature(data);
  if (hottest_held_out < 1 || static_cast<std::size_t>(hottest_held_out) + 2 > order.size())
    throw InputError("QE extrapolation check: cannot hold out " + std::to_string(hottest_held_out) +
                     " of " + std::to_string(order.size()) + " temperatures");
  const auto split = order.end() - hottest_held_out;
  const std::vector<Eigen::Index> train(order.begin(), split), test(split, order.end());
  ExtrapolationCheck out;
  out.fitted_up_to_c = data.temperatures_c[train.back()];
  out.fit = fit_qe(profile, subset(data, train), options);
  out.heldout_residual = prediction_residuals(profile, out.fit, subset(data, test));
  return out;
}

}  // namespace pyrocam
