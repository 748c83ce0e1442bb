// What every estimator shares: the methods by name and the model they need. (Each method's own
// tests: test_lut_estimator.cpp, test_likelihood_estimator.cpp; on small hand-made models:
// tests/lib/calibration/test_calibrate.cpp.)
#include <gtest/gtest.h>

#include <memory>

#include "pyrocam/core/error.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/misfit.h"

namespace pyrocam {
namespace {

TEST(Method, names_round_trip) {
  for (Method m : {Method::kMlp, Method::kLut, Method::kLikelihood})
    EXPECT_EQ(parse_method(method_name(m)), m);
  EXPECT_THROW(parse_method("neural"), InputError);
}

TEST(Estimators, refuse_no_model_n) {
  for (Method m : {Method::kMlp, Method::kLut, Method::kLikelihood})
    EXPECT_THROW(make_estimator(nullptr, m), InputError) << method_name(m);
  EXPECT_THROW(make_exhaustive_likelihood_estimator(nullptr), InputError);
  EXPECT_THROW(MisfitCheck(nullptr), InputError);
}

}  // namespace
}  // namespace pyrocam
