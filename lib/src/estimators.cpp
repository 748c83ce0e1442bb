#include "pyrocam/estimators.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "pyrocam/spectrum.h"

namespace pyrocam {
namespace {

constexpr int kMaxBands = 64;

class MlpEstimator : public TemperatureEstimator {
 public:
  using TemperatureEstimator::TemperatureEstimator;
  double temperature_c(const double* s) const override {
    if (!all_bands_valid(s)) return NAN;
    const Normalisation& n = model_.profile().normalisation;
    double ref = 0;
    for (int b : n.reference) ref += s[b];
    ref /= static_cast<double>(n.reference.size());
    double x[kMaxBands];
    for (std::size_t i = 0; i < n.numerators.size(); ++i) x[i] = s[n.numerators[i]] / ref;
    return in_range(model_.mlp.predict(x));
  }
};

// Weighted least squares of the band signals against the modelled locus with a free scale
// (unknown emissivity, exposure and geometry): chi2(T) = sum w (S - a m(T))^2, a profiled out.
class LikelihoodEstimator : public TemperatureEstimator {
 public:
  // Two minima closer than this in chi2 (about 3 sigma) make the reading ambiguous.
  static constexpr double kAmbiguityChi2 = 9.0;

  explicit LikelihoodEstimator(const ThermalModel& m)
      : TemperatureEstimator(m),
        locus_(make_locus(m.camera, m.min_temperature_c, m.max_temperature_c, 1.0)) {}

  double temperature_c(const double* s) const override {
    double w[kMaxBands];
    int valid = 0;
    for (int b = 0; b < bands_; ++b) {
      // A saturated or dim band is dropped; the rest still fix the temperature.
      if (std::isfinite(s[b]) && s[b] >= dim_dn_) {
        w[b] = 1.0 / signal_variance_dn2(model_.profile(), b, s[b]);
        ++valid;
      } else {
        w[b] = 0;
      }
    }
    if (valid < 2) return NAN;
    const Eigen::Index n = locus_.size();
    auto chi2 = [&](Eigen::Index i) {
      double smm = 0, ssm = 0, sss = 0;
      for (int b = 0; b < bands_; ++b) {
        if (w[b] == 0) continue;
        const double m = locus_.rates(i, b);
        smm += w[b] * m * m;
        ssm += w[b] * s[b] * m;
        sss += w[b] * s[b] * s[b];
      }
      return sss - ssm * ssm / smm;
    };
    const Eigen::Index coarse = 20;
    // Coarse scan, keeping every local minimum: with few valid bands the locus can pass the
    // same ratios twice, and a reading that fits two temperatures is no reading.
    std::vector<double> c;
    for (Eigen::Index i = 0; i < n; i += coarse) c.push_back(chi2(i));
    auto refine = [&](Eigen::Index around, double& value) {
      Eigen::Index best_i = around;
      value = chi2(around);
      const Eigen::Index lo = std::max<Eigen::Index>(0, around - coarse);
      const Eigen::Index hi = std::min<Eigen::Index>(n - 1, around + coarse);
      for (Eigen::Index i = lo; i <= hi; ++i) {
        const double v = chi2(i);
        if (v < value) value = v, best_i = i;
      }
      return best_i;
    };
    std::vector<Eigen::Index> minima;
    for (std::size_t k = 0; k < c.size(); ++k)
      if ((k == 0 || c[k] <= c[k - 1]) && (k + 1 == c.size() || c[k] <= c[k + 1]))
        minima.push_back(static_cast<Eigen::Index>(k) * coarse);
    Eigen::Index best = 0;
    double best_chi2 = std::numeric_limits<double>::infinity();
    std::vector<std::pair<Eigen::Index, double>> refined;
    for (Eigen::Index m : minima) {
      double v;
      const Eigen::Index i = refine(m, v);
      refined.emplace_back(i, v);
      if (v < best_chi2) best_chi2 = v, best = i;
    }
    for (const auto& [i, v] : refined)
      if (std::abs(i - best) > 3 * coarse && v - best_chi2 < kAmbiguityChi2) return NAN;
    if (best == 0 || best == n - 1) return NAN;  // at the edge: outside the model's range
    // Parabola through the minimum and its neighbours for sub-step resolution.
    const double cm = chi2(best - 1), cp = chi2(best + 1);
    const double denom = cm - 2 * best_chi2 + cp;
    const double offset = denom > 0 ? 0.5 * (cm - cp) / denom : 0.0;
    const double step = locus_.temperature_c[1] - locus_.temperature_c[0];
    return in_range(locus_.temperature_c[best] + std::clamp(offset, -1.0, 1.0) * step);
  }

 private:
  Locus locus_;
};

// The MLP tabulated over the colour camera's two log ratios, in coordinates that follow the
// locus: u = ln r1 along it and d = ln r2 - v_locus(u) across it. Pixels off the table fall
// back to the network itself, so the answer is the MLP's wherever the table is not exact.
class LutEstimator : public TemperatureEstimator {
 public:
  static constexpr int kNu = 1024, kNd = 48;
  static constexpr double kHalfWidth = 0.35;  // ln-ratio distance from the locus covered

  explicit LutEstimator(const ThermalModel& m) : TemperatureEstimator(m), mlp_(m) {
    const Normalisation& n = m.profile().normalisation;
    if (n.numerators.size() != 2)
      throw InputError(
          "method lut needs a model with exactly two ratios (colour camera); this "
          "model has " +
          std::to_string(n.numerators.size()));
    const Locus locus = make_locus(m.camera, m.min_temperature_c, m.max_temperature_c, 1.0);
    const Eigen::ArrayXd u = locus.ratios.col(0).array().log();
    const Eigen::ArrayXd v = locus.ratios.col(1).array().log();
    u0_ = u.minCoeff() - 0.05;
    const double u1 = u.maxCoeff() + 0.05;
    du_ = (u1 - u0_) / (kNu - 1);
    dd_ = 2 * kHalfWidth / (kNd - 1);
    // v_locus(u) by linear interpolation of the (monotonic in T) locus, sorted by u.
    std::vector<std::pair<double, double>> uv;
    for (Eigen::Index i = 0; i < u.size(); ++i) uv.emplace_back(u[i], v[i]);
    std::sort(uv.begin(), uv.end());
    v_locus_.resize(kNu);
    std::size_t j = 0;
    for (int i = 0; i < kNu; ++i) {
      const double x = u0_ + i * du_;
      while (j + 2 < uv.size() && uv[j + 1].first < x) ++j;
      const double f = std::clamp((x - uv[j].first) / (uv[j + 1].first - uv[j].first), 0.0, 1.0);
      v_locus_[i] = static_cast<float>(uv[j].second + f * (uv[j + 1].second - uv[j].second));
    }
    Eigen::MatrixXd x(kNu * kNd, 2);
    for (int i = 0; i < kNu; ++i)
      for (int k = 0; k < kNd; ++k) {
        x(i * kNd + k, 0) = std::exp(u0_ + i * du_);
        x(i * kNd + k, 1) = std::exp(v_locus_[i] - kHalfWidth + k * dd_);
      }
    const Eigen::VectorXd t = m.mlp.predict(x);
    table_.resize(static_cast<std::size_t>(kNu * kNd));
    for (Eigen::Index i = 0; i < t.size(); ++i)
      table_[static_cast<std::size_t>(i)] = static_cast<float>(t[i]);
    num0_ = n.numerators[0];
    num1_ = n.numerators[1];
    ref_ = n.reference;
  }

  double temperature_c(const double* s) const override {
    if (!all_bands_valid(s)) return NAN;
    double ref = 0;
    for (int b : ref_) ref += s[b];
    ref /= static_cast<double>(ref_.size());
    const double t = lookup(std::log(s[num0_] / ref), std::log(s[num1_] / ref));
    return in_range(std::isfinite(t) ? t : mlp_.temperature_c(s));
  }

 private:
  // Bilinear interpolation; NaN when (u, v) is off the table.
  double lookup(double u, double v) const {
    const double fu = (u - u0_) / du_;
    if (!(fu >= 0) || fu >= kNu - 1) return NAN;
    const int iu = static_cast<int>(fu);
    const double wu = fu - iu;
    const double vl = v_locus_[iu] + wu * (v_locus_[iu + 1] - v_locus_[iu]);
    const double fd = (v - vl + kHalfWidth) / dd_;
    if (!(fd >= 0) || fd >= kNd - 1) return NAN;
    const int id = static_cast<int>(fd);
    const double wd = fd - id;
    // Rows follow the locus, so across-locus cells at u and u+du are aligned by offset d.
    const float* a = &table_[static_cast<std::size_t>(iu * kNd + id)];
    const float* b = a + kNd;
    return (1 - wu) * ((1 - wd) * a[0] + wd * a[1]) + wu * ((1 - wd) * b[0] + wd * b[1]);
  }

  MlpEstimator mlp_;
  double u0_ = 0, du_ = 1, dd_ = 1;
  std::vector<float> v_locus_, table_;
  int num0_ = 0, num1_ = 1;
  std::vector<int> ref_;
};

}  // namespace

Method parse_method(const std::string& name) {
  if (name == "mlp") return Method::kMlp;
  if (name == "lut") return Method::kLut;
  if (name == "likelihood") return Method::kLikelihood;
  throw InputError("unknown method '" + name + "' (use mlp, lut or likelihood)");
}

std::string method_name(Method m) {
  switch (m) {
    case Method::kMlp:
      return "mlp";
    case Method::kLut:
      return "lut";
    case Method::kLikelihood:
      return "likelihood";
  }
  return "?";
}

TemperatureEstimator::TemperatureEstimator(const ThermalModel& model)
    : model_(model),
      bands_(model.profile().band_count()),
      dim_dn_(model.profile().thresholds.inference_dim_dn) {
  if (bands_ > kMaxBands) throw InputError("at most 64 bands are supported");
}

bool TemperatureEstimator::all_bands_valid(const double* s) const {
  for (int b = 0; b < bands_; ++b)
    if (!std::isfinite(s[b]) || s[b] < dim_dn_) return false;
  return true;
}

double TemperatureEstimator::in_range(double t_c) const {
  return t_c >= model_.min_temperature_c && t_c <= model_.max_temperature_c ? t_c : NAN;
}

void TemperatureEstimator::estimate(const float* const* planes, std::size_t n, float* out) const {
  double s[kMaxBands];
  for (std::size_t i = 0; i < n; ++i) {
    for (int b = 0; b < bands_; ++b) s[b] = planes[b][i];
    out[i] = static_cast<float>(temperature_c(s));
  }
}

std::unique_ptr<TemperatureEstimator> make_estimator(const ThermalModel& model, Method method) {
  switch (method) {
    case Method::kMlp:
      return std::make_unique<MlpEstimator>(model);
    case Method::kLikelihood:
      return std::make_unique<LikelihoodEstimator>(model);
    case Method::kLut:
      return std::make_unique<LutEstimator>(model);
  }
  throw InputError("unknown estimator method");
}

double signal_variance_dn2(const CameraProfile& p, int band, double signal_dn, int frames) {
  const double k = p.dn_per_electron()[band];
  const double read = k * p.noise.read_noise_e;
  // Shot noise of the signal, read noise and quantisation of the frame and of its dark.
  const double var = k * std::max(signal_dn, 0.0) + 2 * (read * read + 1.0 / 12);
  return var / std::max(frames, 1);
}

double expanded_uncertainty_c(const TemperatureEstimator& est, const double* signals, double t_c,
                              int frames) {
  if (!std::isfinite(t_c)) return NAN;
  const ThermalModel& m = est.model();
  const int bands = m.profile().band_count();
  double s[kMaxBands];
  for (int b = 0; b < bands; ++b) s[b] = signals[b];
  double var = 0;
  for (int b = 0; b < bands; ++b) {
    if (!std::isfinite(s[b])) continue;
    const double keep = s[b];
    s[b] = keep + 1;
    const double tp = est.temperature_c(s);
    s[b] = keep - 1;
    const double tm = est.temperature_c(s);
    s[b] = keep;
    double dt_ds;
    if (std::isfinite(tp) && std::isfinite(tm))
      dt_ds = (tp - tm) / 2;
    else if (std::isfinite(tp))
      dt_ds = tp - t_c;
    else if (std::isfinite(tm))
      dt_ds = t_c - tm;
    else
      continue;
    var += dt_ds * dt_ds * signal_variance_dn2(m.profile(), b, keep, frames);
  }
  const double sys = m.uncertainty.systematic_u_c(t_c);
  return m.uncertainty.coverage_factor * std::sqrt(var + sys * sys);
}

}  // namespace pyrocam
