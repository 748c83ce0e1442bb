#include "pyrocam/calibration/noisy_locus.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

#include "detail/random.h"
#include "pyrocam/core/noise_model.h"

namespace pyrocam {
namespace {

// The likelihood fit runs over the model's range widened by this much on each side, so that a
// copy near an end of the range gets its reading (outside the range, as the estimators would
// then give none) instead of being dropped, which would bias the copies there.
constexpr double kFitMarginC = 300;
constexpr double kLowestFitC = 100;
// Draws per copy before it is dropped.
constexpr int kAttempts = 8;

}  // namespace

NoisyLocus::NoisyLocus(const ThermalModel& model, const Locus& locus,
                       const NoisyLocusOptions& options)
    : locus_(locus), options_(options) {
  if (options.copies < 0) throw InputError("noisy locus: copies must be >= 0");
  if (!(options.min_noise_scale >= 0 && options.min_noise_scale <= options.max_noise_scale)) {
    throw InputError("noisy locus: need 0 <= min_noise_scale <= max_noise_scale");
  }
  auto wide = std::make_shared<ThermalModel>();
  wide->camera = model.camera;
  wide->min_temperature_c = std::max(kLowestFitC, model.min_temperature_c - kFitMarginC);
  wide->max_temperature_c = model.max_temperature_c + kFitMarginC;
  model_ = std::move(wide);
  if (options.target == NoisyLocusTarget::kLikelihoodFit) {
    likelihood_ = make_estimator(model_, Method::kLikelihood);
  }
}

MlpSamples NoisyLocus::sample(const std::vector<Eigen::Index>& rows, std::uint64_t seed,
                              Eigen::VectorXd* drawn_at_c) const {
  const CameraProfile& profile = model_->profile();
  const int bands = profile.band_count();
  const Eigen::Index inputs = static_cast<Eigen::Index>(profile.normalisation.numerators.size());
  const double dim = profile.thresholds.inference_dim_dn;
  // The saturation threshold is of raw values; the signals are dark-subtracted.
  const double bright = profile.thresholds.inference_saturation_dn - profile.dark_offset_dn;
  Random draw(seed);
  MlpSamples out;
  out.inputs.resize(static_cast<Eigen::Index>(rows.size()) * options_.copies, inputs);
  out.targets.resize(out.inputs.rows());
  if (drawn_at_c) drawn_at_c->resize(out.inputs.rows());
  Eigen::Index made = 0;
  Eigen::VectorXd signal(bands), noisy(bands), sigma(bands);
  for (const Eigen::Index row : rows) {
    const Eigen::VectorXd rate = locus_.rates.row(row).transpose();
    // Exposures that put every band inside the window.
    const double shortest = dim / rate.minCoeff(), longest = bright / rate.maxCoeff();
    if (!(shortest < longest)) continue;
    for (int copy = 0; copy < options_.copies; ++copy) {
      for (int attempt = 0; attempt < kAttempts; ++attempt) {
        const double exposure = shortest + draw.uniform() * (longest - shortest);
        const double noise_scale =
            options_.min_noise_scale +
            (options_.max_noise_scale - options_.min_noise_scale) * draw.uniform();
        signal = rate * exposure;
        bool inside = true;
        for (int b = 0; b < bands; ++b) {
          const double prnu = profile.noise.prnu * signal[b];
          sigma[b] = std::sqrt(signal_variance_dn2(profile, b, signal[b]) + prnu * prnu);
          noisy[b] = signal[b] + noise_scale * sigma[b] * draw.normal();
          inside = inside && noisy[b] >= dim && noisy[b] <= bright;
        }
        if (!inside) continue;
        const double target =
            likelihood_ ? likelihood_->temperature_c(noisy.data()) : locus_.temperature_c[row];
        if (!std::isfinite(target)) continue;
        out.inputs.row(made) = normalised_ratios(profile.normalisation, noisy).transpose();
        out.targets[made] = target;
        if (drawn_at_c) (*drawn_at_c)[made] = locus_.temperature_c[row];
        ++made;
        break;
      }
    }
  }
  out.inputs.conservativeResize(made, inputs);
  out.targets.conservativeResize(made);
  if (drawn_at_c) drawn_at_c->conservativeResize(made);
  return out;
}

}  // namespace pyrocam
