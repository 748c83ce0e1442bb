#include "pyrocam/calibration/baselines.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>

#include "detail/portable_math.h"

namespace pyrocam {

OhnoEstimator::OhnoEstimator(const Locus& locus) : t_(locus.temperature_c) {
  const Eigen::MatrixXd all = locus.rates.array().colwise() / locus.rates.rowwise().sum().array();
  chroma_ = all.leftCols(std::max<Eigen::Index>(1, all.cols() - 1));
}

double OhnoEstimator::temperature_c(const Eigen::VectorXd& signals) const {
  const double sum = signals.sum();
  if (!std::isfinite(sum) || !(sum > 0)) return NAN;
  const Eigen::RowVectorXd c = (signals.head(chroma_.cols()) / sum).transpose();
  Eigen::Index i;
  (chroma_.rowwise() - c).rowwise().squaredNorm().minCoeff(&i);
  i = std::clamp<Eigen::Index>(i, 1, t_.size() - 2);
  const double dm = (chroma_.row(i - 1) - c).norm(), dp = (chroma_.row(i + 1) - c).norm();
  const double l = (chroma_.row(i + 1) - chroma_.row(i - 1)).norm();
  if (!(l > 0)) return t_[i];
  // Position along the chord between the neighbours (Ohno 2014, triangular solution).
  const double x = (dm * dm - dp * dp + l * l) / (2 * l);
  return t_[i - 1] + (t_[i + 1] - t_[i - 1]) * x / l;
}

double TwoColourEstimator::temperature_c(const Eigen::VectorXd& s) const {
  const double blue = p_.band_gain[2] * s[b_];
  const double rp = p_.band_gain[0] * s[r_] - blue, gp = p_.band_gain[1] * s[g_] - blue;
  if (!(rp > 0) || !(gp > 0)) return NAN;
  const double lr = p_.lambda_r_nm * 1e-9, lg = p_.lambda_g_nm * 1e-9;
  const double denom = 5 * portable::log(lg / lr) - portable::log(p_.gain * rp / gp);
  const double t_k = kC2 * (1 / lr - 1 / lg) / denom;
  return t_k > 0 ? kelvin_to_celsius(t_k) : NAN;
}

TwoColourEstimator TwoColourEstimator::fit(const std::vector<Eigen::VectorXd>& measured,
                                           const std::vector<Eigen::VectorXd>& simulated,
                                           const std::vector<double>& temperatures_c, int r, int g,
                                           int b) {
  TwoColourParams p;
  const int idx[3] = {r, g, b};
  // Step 1a: per-band gain = inverse slope of measured against simulated.
  for (int k = 0; k < 3; ++k) {
    double sm = 0, mm = 0;
    for (std::size_t i = 0; i < measured.size(); ++i) {
      sm += simulated[i][idx[k]] * measured[i][idx[k]];
      mm += measured[i][idx[k]] * measured[i][idx[k]];
    }
    p.band_gain[k] = mm > 0 ? sm / mm : 1;
  }
  // Step 1b: the gain ratio g that maps measured blue-subtracted ratios onto simulated ones.
  double sm = 0, mm = 0;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    const Eigen::VectorXd& m = measured[i];
    const Eigen::VectorXd& s = simulated[i];
    const double meas = (p.band_gain[0] * m[r] - p.band_gain[2] * m[b]) /
                        (p.band_gain[1] * m[g] - p.band_gain[2] * m[b]);
    const double sim = (s[r] - s[b]) / (s[g] - s[b]);
    if (std::isfinite(meas) && std::isfinite(sim)) sm += sim * meas, mm += meas * meas;
  }
  if (mm > 0) p.gain = sm / mm;
  // Step 2: equivalent wavelengths minimising the rms temperature error.
  auto rms = [&](const TwoColourParams& q) {
    const TwoColourEstimator e(q, r, g, b);
    double sum = 0;
    for (std::size_t i = 0; i < measured.size(); ++i) {
      const double t = e.temperature_c(measured[i]);
      const double err = std::isfinite(t) ? t - temperatures_c[i] : 1e4;
      sum += err * err;
    }
    return measured.empty() ? 1e9 : std::sqrt(sum / static_cast<double>(measured.size()));
  };
  const Eigen::VectorXd x = nelder_mead(
      [&](const Eigen::VectorXd& v) {
        if (v[0] <= v[1] + 1 || v[1] < 300 || v[0] > 1100) return 1e9;
        TwoColourParams q = p;
        q.lambda_r_nm = v[0];
        q.lambda_g_nm = v[1];
        return rms(q);
      },
      Eigen::Vector2d(p.lambda_r_nm, p.lambda_g_nm), Eigen::Vector2d(10, 10));
  p.lambda_r_nm = x[0];
  p.lambda_g_nm = x[1];
  return TwoColourEstimator(p, r, g, b);
}

Eigen::VectorXd nelder_mead(const std::function<double(const Eigen::VectorXd&)>& f,
                            Eigen::VectorXd x0, const Eigen::VectorXd& step, int iterations) {
  const Eigen::Index n = x0.size();
  std::vector<Eigen::VectorXd> pts(n + 1, x0);
  std::vector<double> val(n + 1);
  for (Eigen::Index i = 0; i < n; ++i) pts[i + 1][i] += step[i];
  for (Eigen::Index i = 0; i <= n; ++i) val[i] = f(pts[i]);
  std::vector<std::size_t> order(n + 1);
  for (int it = 0; it < iterations; ++it) {
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](auto a, auto b) { return val[a] < val[b]; });
    const std::size_t best = order.front(), worst = order.back(), second = order[n - 1];
    if (std::abs(val[worst] - val[best]) <= 1e-12 * (std::abs(val[best]) + 1e-12) && it > 20) break;
    Eigen::VectorXd centroid = Eigen::VectorXd::Zero(n);
    for (std::size_t k = 0; k < order.size() - 1; ++k) centroid += pts[order[k]];
    centroid /= static_cast<double>(n);
    const Eigen::VectorXd xr = centroid + (centroid - pts[worst]);
    const double fr = f(xr);
    if (fr < val[best]) {
      const Eigen::VectorXd xe = centroid + 2 * (centroid - pts[worst]);
      const double fe = f(xe);
      pts[worst] = fe < fr ? xe : xr;
      val[worst] = std::min(fe, fr);
    } else if (fr < val[second]) {
      pts[worst] = xr;
      val[worst] = fr;
    } else {
      const Eigen::VectorXd xc = centroid + 0.5 * (pts[worst] - centroid);
      const double fc = f(xc);
      if (fc < val[worst]) {
        pts[worst] = xc;
        val[worst] = fc;
      } else {
        for (std::size_t k = 0; k <= static_cast<std::size_t>(n); ++k)
          if (k != best) {
            pts[k] = pts[best] + 0.5 * (pts[k] - pts[best]);
            val[k] = f(pts[k]);
          }
      }
    }
  }
  return pts[static_cast<std::size_t>(std::min_element(val.begin(), val.end()) - val.begin())];
}

}  // namespace pyrocam
