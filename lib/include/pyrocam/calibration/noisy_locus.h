// Noisy copies of locus samples: what single pixels of the camera read near each temperature of
// the synthetic locus, with the reading they should give. The temperature network is trained on
// them beside the noise-free locus (METHOD.md section 5), so that its answer off the locus, where
// every real pixel lies (sensor noise, a unit not exactly its model), is defined by training
// rather than left to whatever the fit of the one-dimensional locus did there.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "pyrocam/calibration/mlp_training.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {

// The reading a noisy copy is trained towards.
enum class NoisyLocusTarget {
  // The likelihood fit of temperature and scale to the copy's signals, weighted by the noise
  // model (the `likelihood` method): a function of the signals, equal to the locus temperature
  // on the noise-free locus, so that the copies never pull the network off the locus.
  kLikelihoodFit,
  // The temperature the copy was drawn at: the network then learns the mean temperature given
  // the ratios, which the spread of temperatures near each point biases.
  kTrueTemperature,
};

struct NoisyLocusOptions {
  int copies = 2;  // per locus sample asked for (0: none)
  NoisyLocusTarget target = NoisyLocusTarget::kLikelihoodFit;
  // Each copy's noise is the profile's single-frame noise at its signal level (EMVA 1288 shot,
  // read and quantisation noise of frame and dark, signal_variance_dn2, and the PRNU) times a
  // factor drawn uniformly in [min_noise_scale, max_noise_scale]: the copies fill the
  // neighbourhood of the locus from ROI means (hardly any noise) out to single pixels.
  double min_noise_scale = 0.0, max_noise_scale = 1.0;
};

class NoisyLocus {
 public:
  // The model's camera, range and noise model; its network is not used (it may be empty).
  NoisyLocus(const ThermalModel& model, const Locus& locus, const NoisyLocusOptions& options);

  // options.copies noisy copies of each given locus row, deterministic for a seed. Each copy's
  // signal level is drawn uniformly over the exposures that put every band inside the inference
  // window (inference_dim_dn to inference_saturation_dn raw), as the estimators require; a copy
  // that the noise takes out of the window is drawn again (a few times, then dropped), as is one
  // whose likelihood fit gives no reading. Rows that no exposure brings into the window get no
  // copies. Inputs are the copies' normalised ratios, targets in degC; drawn_at_c, when given,
  // gets the locus temperature of each copy.
  MlpSamples sample(const std::vector<Eigen::Index>& rows, std::uint64_t seed,
                    Eigen::VectorXd* drawn_at_c = nullptr) const;

 private:
  std::shared_ptr<const ThermalModel> model_;  // the camera, over a wider range for the fit
  std::unique_ptr<TemperatureEstimator> likelihood_;
  Locus locus_;
  NoisyLocusOptions options_;
};

}  // namespace pyrocam
