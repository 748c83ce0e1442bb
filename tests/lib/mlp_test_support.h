// Helpers shared by the network's tests (inference in runtime/, training in calibration/).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <initializer_list>
#include <limits>
#include <string>

#include "pyrocam/calibration/mlp_training.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/mlp.h"

namespace pyrocam::test {

inline constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// The noise-free locus of a shipped camera profile with its datasheet QE: normalised ratios
// (2 for the colour camera, 25 for the 5x5 one) for T in [low_c, high_c] every step_c.
inline Locus profile_locus(const std::string& profile_name, double low_c, double high_c,
                           double step_c) {
  const CameraProfile profile = load_profile_by_name(profile_name);
  const CameraModel camera{profile, profile.system_qe(),
                           Eigen::VectorXd::Ones(profile.band_count())};
  return make_locus(camera, low_c, high_c, step_c);
}

// A small network, briefly trained: for tests that need a model, not a good one.
inline MlpTrainingOptions small_options(std::uint64_t seed = 1) {
  MlpTrainingOptions options;
  options.hidden = {16, 12};
  options.epochs = 4;
  options.polish_iterations = 10;
  options.seed = seed;
  return options;
}

// Runs f, which must throw MlpError whose message contains every one of the fragments.
template <class F>
void expect_mlp_error(F f, std::initializer_list<const char*> fragments) {
  try {
    f();
    ADD_FAILURE() << "no MlpError thrown";
  } catch (const MlpError& e) {
    const std::string message = e.what();
    for (const char* fragment : fragments) {
      EXPECT_NE(message.find(fragment), std::string::npos)
          << "message \"" << message << "\" lacks \"" << fragment << "\"";
    }
  }
}

inline bool same_weights(const Mlp& a, const Mlp& b) {
  if (a.layers().size() != b.layers().size()) return false;
  for (std::size_t l = 0; l < a.layers().size(); ++l) {
    const auto &la = a.layers()[l], &lb = b.layers()[l];
    if (la.weights.rows() != lb.weights.rows() || la.weights.cols() != lb.weights.cols()) {
      return false;
    }
    // Bitwise: == on doubles would also be what we want (no NaNs after training).
    if (!(la.weights.array() == lb.weights.array()).all()) return false;
    if (!(la.bias.array() == lb.bias.array()).all()) return false;
  }
  return true;
}

}  // namespace pyrocam::test
