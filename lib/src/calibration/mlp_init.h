// Training's initialisation stage: the network Adam starts from.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "calibration/mlp_network.h"
#include "detail/random.h"

namespace pyrocam::mlp_training {

// He-initialised weights for the ReLU layers (variance 2/fan_in), variance 1/fan_in for the
// linear output, drawn from random row by row; then data-dependent hidden biases: each hidden
// unit's kink passes through a training sample (a column of z_train, standardised inputs) drawn
// from random. Layer widths: input_size, hidden..., 1.
TrainingNetwork initial_network(int input_size, const std::vector<int>& hidden,
                                const TrainingMatrix& z_train, Random& random);

}  // namespace pyrocam::mlp_training
