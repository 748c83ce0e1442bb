// Estimator selection: auto is the lookup table for the colour model when it passes its check
// against the network, likelihood for the 5x5 model; a table that fails its check, or a method
// that does not fit the model, is refused with the reason.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <utility>

#include "pyrocam/core/error.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "test_support.h"

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

// The table cache records that the table passed its check, which the next run with that cache
// then trusts; an altered cache, another model's, one without the verdict and no cache do not
// spare the check.
class CachedVerdict : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!rgb_lut_passes()) GTEST_SKIP() << "the test model's table does not pass its check";
  }
  std::unique_ptr<EstimatorSelector> select(std::shared_ptr<const ThermalModel> m,
                                            const std::string& cache) {
    auto s = std::make_unique<EstimatorSelector>(std::move(m));
    s->set_table_cache(cache);
    const auto c = s->select(MethodRequest::kLut);
    EXPECT_TRUE(c.problem.empty()) << c.problem;
    return s;
  }
  test::ScratchDir dir{"selection-cache"};
  const std::string file = table_cache_file(*rgb(), dir.path().string());
};

TEST_F(CachedVerdict, a_second_run_trusts_the_verdict_and_reads_the_same) {
  const auto first = select(rgb(), file);
  EXPECT_FALSE(first->lut_check_skipped()) << "no cache yet";
  ASSERT_GT(first->save_table_cache(), 0u);
  const auto second = select(rgb(), file);
  EXPECT_GT(second->cache_blocks_read(), 0u);
  EXPECT_TRUE(second->lut_check_skipped());
  EXPECT_EQ(second->save_table_cache(), 0u) << "nothing new to keep";
  const LocusAgreement a = compare_on_locus(*rgb(), second->estimator(Method::kLut).estimator(),
                                            first->estimator(Method::kLut).estimator());
  EXPECT_EQ(a.max_difference_c, 0.0);
  EXPECT_EQ(a.validity_differs, 0u);
  EXPECT_FALSE(select(rgb(), "")->lut_check_skipped()) << "without a cache";
}

TEST_F(CachedVerdict, an_altered_cache_is_not_trusted_n) {
  ASSERT_GT(select(rgb(), file)->save_table_cache(), 0u);
  {
    std::fstream f(file, std::ios::binary | std::ios::in | std::ios::out);
    f.seekp(static_cast<std::streamoff>(std::filesystem::file_size(file) / 2));
    f.put('\x7f');
  }
  const auto s = select(rgb(), file);
  EXPECT_NE(s->cache_problem().find("truncated or altered"), std::string::npos)
      << s->cache_problem();
  EXPECT_FALSE(s->lut_check_skipped());
}

TEST_F(CachedVerdict, another_models_cache_is_ignored_n) {
  ASSERT_GT(select(rgb(), file)->save_table_cache(), 0u);
  ThermalModel other = *rgb();
  other.fingerprint = "0123456789abcdef";
  const auto other_model = std::make_shared<const ThermalModel>(other);
  const std::string other_file = table_cache_file(other, dir.path().string());
  std::filesystem::copy_file(file, other_file);
  const auto s = select(other_model, other_file);
  EXPECT_NE(s->cache_problem().find("another model"), std::string::npos) << s->cache_problem();
  EXPECT_EQ(s->cache_blocks_read(), 0u);
  EXPECT_FALSE(s->lut_check_skipped());
}

TEST_F(CachedVerdict, a_cache_without_the_verdict_is_checked_then_given_it_n) {
  {
    // Blocks kept by the estimator alone, never checked.
    const PlaneEstimator lut(rgb(), Method::kLut);
    const auto mlp = make_estimator(rgb(), Method::kMlp);
    compare_on_locus(*rgb(), lut.estimator(), *mlp);
    ASSERT_GT(lut.estimator().save_tables(file), 0u);
  }
  const auto checked = select(rgb(), file);
  EXPECT_GT(checked->cache_blocks_read(), 0u);
  EXPECT_FALSE(checked->lut_check_skipped());
  EXPECT_GT(checked->save_table_cache(), 0u) << "the verdict is new";
  EXPECT_TRUE(select(rgb(), file)->lut_check_skipped());
}

}  // namespace
}  // namespace pyrocam
