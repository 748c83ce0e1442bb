// compare_on_locus: an estimator agrees with itself, and a shifted or blind one is caught with
// the size and place of its error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <memory>

#include "pyrocam/runtime/estimator_check.h"

namespace pyrocam {
namespace {

const std::shared_ptr<const ThermalModel>& test_model() {
  static const auto m = [] {
    const char* dir = std::getenv("PYROCAM_TEST_MODEL_DIR");
    return std::make_shared<const ThermalModel>(
        load_model(std::string(dir ? dir : ".") + "/test-model-rgb.json"));
  }();
  return m;
}

// The network, 10 degC hot from 2000 degC up and blind below 600 degC.
class FaultyEstimator : public TemperatureEstimator {
 public:
  explicit FaultyEstimator(const std::shared_ptr<const ThermalModel>& m)
      : TemperatureEstimator(m), reference_(make_estimator(m, Method::kMlp)) {}
  double temperature_c(const double* s) const override {
    const double t = reference_->temperature_c(s);
    if (t < 600) return NAN;
    return t >= 2000 ? t + 10 : t;
  }

 private:
  std::unique_ptr<TemperatureEstimator> reference_;
};

TEST(EstimatorCheck, an_estimator_agrees_with_itself) {
  const auto mlp = make_estimator(test_model(), Method::kMlp);
  const LocusAgreement r = compare_on_locus(*test_model(), *mlp, *mlp, 5);
  EXPECT_EQ(r.samples, 601u);  // 500..3500 degC every 5
  EXPECT_GT(r.both_valid, 550u);
  EXPECT_EQ(r.validity_differs, 0u);
  EXPECT_EQ(r.max_difference_c, 0.0);
}

TEST(EstimatorCheck, finds_the_size_and_place_of_a_disagreement) {
  const auto mlp = make_estimator(test_model(), Method::kMlp);
  const FaultyEstimator faulty(test_model());
  const LocusAgreement r = compare_on_locus(*test_model(), *mlp, faulty, 5);
  EXPECT_NEAR(r.max_difference_c, 10, 1e-3);  // float temperatures: 1.2e-4 apart at 2000 degC
  EXPECT_GE(r.worst_temperature_c, 1950);     // the network's own error may place 2000 a step off
  // The blind part: the locus samples below about 600 degC that the network reads.
  EXPECT_GE(r.validity_differs, 18u);
  EXPECT_LE(r.validity_differs, 22u);
}

// A network that reads what lies beyond the range's end as a temperature inside it (as one
// trained only up to a narrow range's end does): fold_above_range finds it and the worst case;
// the test model's own network, trained on its whole range, reads nothing beyond it inside.
class FoldingEstimator : public TemperatureEstimator {
 public:
  explicit FoldingEstimator(const std::shared_ptr<const ThermalModel>& m)
      : TemperatureEstimator(m), reference_(make_estimator(m, Method::kLikelihood)) {}
  double temperature_c(const double* s) const override {
    const double t = reference_->temperature_c(s);
    return std::isnan(t) ? 1812 : t;  // beyond the range: some temperature inside it
  }

 private:
  std::unique_ptr<TemperatureEstimator> reference_;
};

TEST(EstimatorCheck, a_network_reading_beyond_the_range_inside_it_is_found) {
  const FoldingEstimator folding(test_model());
  const AboveRangeFold fold = fold_above_range(*test_model(), folding, 1000, 10);
  EXPECT_EQ(fold.samples, 100u);  // 3510..4500 degC
  EXPECT_EQ(fold.read_inside, 100u);
  EXPECT_EQ(fold.worst_true_c, 4500);
  EXPECT_FLOAT_EQ(fold.worst_read_c, 1812);
  const auto mlp = make_estimator(test_model(), Method::kMlp);
  const AboveRangeFold none = fold_above_range(*test_model(), *mlp);
  EXPECT_EQ(none.samples, 50u);  // 3510..4000 degC
  EXPECT_EQ(none.read_inside, 0u) << none.worst_true_c << " read " << none.worst_read_c;
}

}  // namespace
}  // namespace pyrocam
