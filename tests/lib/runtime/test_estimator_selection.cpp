// Estimator selection: auto is the lookup table for the colour model when it passes its check
// against the network, likelihood for the 5x5 model; a table that fails its check, or a method
// that does not fit the model, is refused with the reason.
#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <memory>
#include <utility>

#include "pyrocam/core/error.h"
#include "pyrocam/runtime/estimator_selection.h"

namespace pyrocam {
namespace {

std::shared_ptr<const ThermalModel> model(const std::string& file) {
  static std::map<std::string, std::shared_ptr<const ThermalModel>> models;
  auto it = models.find(file);
  if (it == models.end()) {
    const char* dir = std::getenv("PYROCAM_TEST_MODEL_DIR");
    it = models
             .emplace(file, std::make_shared<const ThermalModel>(
                                load_model(std::string(dir ? dir : ".") + "/" + file)))
             .first;
  }
  return it->second;
}
std::shared_ptr<const ThermalModel> rgb() { return model("test-model-rgb.json"); }
std::shared_ptr<const ThermalModel> nir() { return model("test-model-nir5x5.json"); }

// The rule written out: the table where it is within 1 degC of the network everywhere on the
// locus and reads where the network does at all but 1 % of the samples.
bool rgb_lut_passes() {
  const auto lut = make_estimator(rgb(), Method::kLut);
  const auto mlp = make_estimator(rgb(), Method::kMlp);
  const LocusAgreement a = compare_on_locus(*rgb(), *lut, *mlp);
  return a.max_difference_c <= 1.0 && a.validity_differs * 100 <= a.samples;
}

TEST(EstimatorSelection, method_requests_parse_and_print) {
  for (const char* name : {"auto", "mlp", "lut", "likelihood"})
    EXPECT_EQ(method_request_name(parse_method_request(name)), name);
  EXPECT_THROW(parse_method_request("fast"), InputError);
}

TEST(EstimatorSelection, auto_takes_the_checked_table_for_the_colour_model) {
  EstimatorSelector selector(rgb());
  const auto c = selector.select(MethodRequest::kAuto);
  EXPECT_TRUE(c.problem.empty()) << c.problem;
  if (rgb_lut_passes()) {
    EXPECT_EQ(c.method, Method::kLut);
    EXPECT_TRUE(c.fallback.empty()) << c.fallback;
  } else {
    EXPECT_EQ(c.method, Method::kLikelihood);
    EXPECT_NE(c.fallback.find("lookup table differs"), std::string::npos) << c.fallback;
  }
  // The estimator is built once and kept.
  PlaneEstimator& first = selector.estimator(c.method);
  EXPECT_EQ(&selector.estimator(selector.select(MethodRequest::kAuto).method), &first);
  EXPECT_EQ(choose_method(rgb(), MethodRequest::kAuto), c.method);
}

TEST(EstimatorSelection, auto_is_likelihood_for_the_5x5_model_without_a_fallback_note) {
  EstimatorSelector selector(nir());
  const auto c = selector.select(MethodRequest::kAuto);
  EXPECT_EQ(c.method, Method::kLikelihood);
  EXPECT_TRUE(c.problem.empty()) << c.problem;
  EXPECT_TRUE(c.fallback.empty()) << c.fallback;  // the table was never an option
}

TEST(EstimatorSelection, explicit_methods_are_what_they_say) {
  EstimatorSelector selector(nir());
  for (const auto& [request, method] :
       {std::pair{MethodRequest::kMlp, Method::kMlp},
        std::pair{MethodRequest::kLikelihood, Method::kLikelihood}}) {
    const auto c = selector.select(request);
    EXPECT_EQ(c.method, method);
    EXPECT_TRUE(c.problem.empty()) << c.problem;
  }
}

TEST(EstimatorSelection, a_table_for_the_5x5_model_is_refused_with_the_reason_n) {
  EstimatorSelector selector(nir());
  const auto c = selector.select(MethodRequest::kLut);
  EXPECT_EQ(c.method, Method::kLut);
  EXPECT_FALSE(c.problem.empty());
  EXPECT_THROW(selector.estimator(Method::kLut), std::logic_error);
  EXPECT_THROW(choose_method(nir(), MethodRequest::kLut), InputError);
}

TEST(EstimatorSelection, the_check_refuses_a_table_off_by_more_than_1_degc_or_1_percent_n) {
  LocusAgreement a;
  a.samples = 3001;
  a.both_valid = 2990;
  a.max_difference_c = 1.0;
  a.worst_temperature_c = 2100;
  a.validity_differs = 30;
  EXPECT_EQ(lut_disagreement(a), "");  // at both limits
  a.max_difference_c = 1.25;
  EXPECT_EQ(lut_disagreement(a),
            "its lookup table differs from its network by up to 1.2 degC (at 2100 degC on the "
            "model's locus; one reads where the other does not at 30 of 3001 samples)");
  a.max_difference_c = 0.5;
  a.validity_differs = 31;
  EXPECT_NE(lut_disagreement(a), "");
}

}  // namespace
}  // namespace pyrocam
