// Training's Adam stage: mini-batch AdamW with a linear warm-up and a half-cosine decay of the
// learning rate, fresh augmented samples every epoch.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "calibration/mlp_augment.h"
#include "calibration/mlp_network.h"
#include "calibration/mlp_training_data.h"
#include "detail/random.h"
#include "pyrocam/calibration/mlp_training.h"

namespace pyrocam::mlp_training {

// The learning rate at a step (0-based) of total_steps: linear warm-up from 0 to
// o.learning_rate over the first o.warmup_fraction of the steps, then half-cosine decay to
// o.final_learning_rate at the last step.
double learning_rate_at(const MlpTrainingOptions& o, long step, long total_steps);

// One Adam step on a parameter block (AdamW decay when decay > 0).
template <class Param, class Grad, class S>
void adam_step(Param& p, const Grad& g, Param& m, Param& v, S lr, S bias1, S bias2, S decay) {
  constexpr S kBeta1 = S(0.9), kBeta2 = S(0.999), kEpsilon = S(1e-8);
  m.array() = kBeta1 * m.array() + (1 - kBeta1) * g.array();
  v.array() = kBeta2 * v.array() + (1 - kBeta2) * g.array().square();
  if (decay > 0) p.array() *= 1 - lr * decay;
  p.array() -= lr * (m.array() / bias1) / ((v.array() / bias2).sqrt() + kEpsilon);
}

// options.epochs epochs of Adam on net (none for 0), adding a point per epoch to curve. With
// options.augment, augmented is the last epoch's set of augmented samples on return. Draws the
// augmentation seeds and batch orders from random. Throws MlpError when training diverges.
void train_with_adam(TrainingNetwork& net, const TrainingData& data,
                     const MlpTrainingOptions& options, Random& random, AugmentedSamples& augmented,
                     TrainingCurve& curve);

}  // namespace pyrocam::mlp_training
