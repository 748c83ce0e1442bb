// The network at inference: the input and output transforms, JSON, the prediction paths and the
// gradient, on hand-built models and small ones trained on the colour camera's locus (training
// itself: tests/lib/calibration/test_mlp_training.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "mlp_test_support.h"
#include "pyrocam/calibration/mlp_training.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/runtime/mlp.h"

namespace pyrocam::test {
namespace {

const Locus& colour_locus_every_10c() {
  static const Locus locus = profile_locus("rgb-reference", 500, 3500, 10);
  return locus;
}

// A small network trained briefly on the colour locus with the given transforms (cached).
const Mlp& small_locus_model(MlpInputTransform in = MlpTrainingOptions{}.input_transform,
                             MlpOutputTransform out = MlpTrainingOptions{}.output_transform) {
  static std::map<std::pair<MlpInputTransform, MlpOutputTransform>, Mlp> cache;
  auto it = cache.find({in, out});
  if (it == cache.end()) {
    MlpTrainingOptions options = small_options();
    options.hidden = {32, 32, 16};
    options.epochs = 40;
    options.polish_iterations = 50;
    options.input_transform = in;
    options.output_transform = out;
    const Locus& locus = colour_locus_every_10c();
    it =
        cache
            .emplace(std::make_pair(in, out), train_mlp(locus.ratios, locus.temperature_c, options))
            .first;
  }
  return it->second;
}

const std::pair<MlpInputTransform, MlpOutputTransform> kTransformPairs[] = {
    {MlpInputTransform::kNone, MlpOutputTransform::kNone},
    {MlpInputTransform::kLog, MlpOutputTransform::kLogKelvin},
    {MlpInputTransform::kLog, MlpOutputTransform::kInverseKelvin},
};

// One linear layer y = w x + b after the transforms: small enough to check by hand.
Mlp single_layer_model(MlpInputTransform in, MlpOutputTransform out, double w, double b) {
  Standardizer unit{Eigen::VectorXd::Zero(1), Eigen::VectorXd::Ones(1)};
  MlpLayer layer{Eigen::MatrixXd::Constant(1, 1, w), Eigen::VectorXd::Constant(1, b)};
  return Mlp(in, unit, out, 0.0, 1.0, {layer});
}

// All four prediction paths for one input value; expects them to agree.
double predict_all_paths(const Mlp& model, double x, double* gradient) {
  const double single = model.predict(&x);
  const double batch = model.predict(Eigen::MatrixXd::Constant(1, 1, x))[0];
  double rows = 0;
  model.predict_rows(&x, 1, &rows);
  const double with_gradient = model.predict_with_gradient(&x, gradient);
  if (std::isnan(single)) {
    EXPECT_TRUE(std::isnan(batch) && std::isnan(rows) && std::isnan(with_gradient));
  } else {
    EXPECT_NEAR(batch, single, 1e-9 * std::abs(single) + 1e-9);
    EXPECT_EQ(rows, batch);
    EXPECT_NEAR(with_gradient, single, 1e-4 * std::abs(single) + 1e-9);
  }
  return with_gradient;
}

TEST(Standardizer, maps_columns_to_zero_mean_unit_scale_and_back) {
  Eigen::MatrixXd samples(4, 3);
  samples << 1, 10, 7, 2, 20, 7, 3, 30, 7, 4, 40, 7;
  const Standardizer s = Standardizer::fit(samples);
  const Eigen::MatrixXd z = s.apply(samples);
  EXPECT_NEAR(z.col(0).mean(), 0, 1e-15);
  EXPECT_NEAR(z.col(1).norm() / 2, 1, 1e-12);  // population std over 4 rows
  EXPECT_EQ(s.scale[2], 1.0) << "a constant column keeps scale 1";
  EXPECT_TRUE(z.col(2).isZero());
  EXPECT_TRUE(s.invert(z).isApprox(samples, 1e-14));
}

TEST(MlpTransforms, output_transform_functions_invert_each_other_and_give_their_slope) {
  for (const auto t : {MlpOutputTransform::kNone, MlpOutputTransform::kInverseKelvin,
                       MlpOutputTransform::kLogKelvin}) {
    for (const double target : {-100.0, 500.0, 2000.0, 3500.0}) {
      const double v = to_network_units(t, target);
      EXPECT_NEAR(from_network_units(t, v), target, 1e-9 * std::abs(target)) << to_string(t);
      // Central difference of the inverse against its slope.
      const double h = 1e-6 * std::abs(v);
      const double numeric =
          (from_network_units(t, v + h) - from_network_units(t, v - h)) / (2 * h);
      EXPECT_NEAR(target_slope(t, v), numeric, 1e-5 * std::abs(numeric)) << to_string(t);
    }
  }
  EXPECT_NEAR(to_network_units(MlpOutputTransform::kInverseKelvin, 1000), 1 / 1273.15, 1e-15);
  EXPECT_TRUE(std::isnan(from_network_units(MlpOutputTransform::kInverseKelvin, 0)));
  EXPECT_TRUE(std::isnan(from_network_units(MlpOutputTransform::kInverseKelvin, -1e-3)));
  EXPECT_STREQ(to_string(MlpOutputTransform::kInverseKelvin), "inverse_kelvin");
  EXPECT_STREQ(to_string(MlpOutputTransform::kLogKelvin), "log_kelvin");
  EXPECT_STREQ(to_string(MlpInputTransform::kLog), "log");
  EXPECT_STREQ(to_string(MlpInputTransform::kNone), "none");
}

TEST(MlpTransforms, hand_built_models_apply_them_in_every_prediction_path) {
  double gradient = 0;
  // 1/T in kelvin out: T = 1 / x - 273.15, dT/dx = -1 / x^2.
  const Mlp inverse =
      single_layer_model(MlpInputTransform::kNone, MlpOutputTransform::kInverseKelvin, 1, 0);
  const double x = 1 / 1273.15;
  EXPECT_NEAR(predict_all_paths(inverse, x, &gradient), 1000, 1e-9);
  EXPECT_NEAR(gradient, -1 / (x * x), 1e-9 / (x * x));
  // log in, log of kelvin out, slope 2: T = x^2 - 273.15, dT/dx = 2 x.
  const Mlp square =
      single_layer_model(MlpInputTransform::kLog, MlpOutputTransform::kLogKelvin, 2, 0);
  EXPECT_NEAR(predict_all_paths(square, 40, &gradient), 1600 - 273.15, 1e-9);
  EXPECT_NEAR(gradient, 80, 1e-9);
  // No transforms: an affine map.
  const Mlp affine = single_layer_model(MlpInputTransform::kNone, MlpOutputTransform::kNone, 3, 1);
  EXPECT_NEAR(predict_all_paths(affine, -2, &gradient), -5, 1e-12);
  EXPECT_NEAR(gradient, 3, 1e-12);
}

TEST(MlpTransforms, predicts_nan_outside_their_domain_n) {
  double gradient = 0;
  const Mlp log_input =
      single_layer_model(MlpInputTransform::kLog, MlpOutputTransform::kNone, 1, 0);
  for (const double x : {0.0, -1.0, kNan}) {
    EXPECT_TRUE(std::isnan(predict_all_paths(log_input, x, &gradient))) << x;
    EXPECT_TRUE(std::isnan(gradient)) << x;
  }
  // The network's 1/T reaches 0 or below: hotter than anything, not a temperature.
  const Mlp inverse =
      single_layer_model(MlpInputTransform::kNone, MlpOutputTransform::kInverseKelvin, 1, 0);
  for (const double x : {0.0, -1e-3}) {
    EXPECT_TRUE(std::isnan(predict_all_paths(inverse, x, &gradient))) << x;
    EXPECT_TRUE(std::isnan(gradient)) << x;
  }
  // A bad sample in a batch spoils only itself.
  Eigen::MatrixXd batch(3, 1);
  batch << 2, -1, 3;
  const Eigen::VectorXd t = log_input.predict(batch);
  EXPECT_NEAR(t[0], std::log(2.0), 1e-6);
  EXPECT_TRUE(std::isnan(t[1]));
  EXPECT_NEAR(t[2], std::log(3.0), 1e-6);
}

TEST(MlpJson, round_trip_gives_identical_predictions) {
  for (const auto& [in, out] : kTransformPairs) {
    const Mlp& model = small_locus_model(in, out);
    const Mlp copy = Mlp::from_json(nlohmann::json::parse(model.to_json().dump()));
    EXPECT_TRUE(same_weights(model, copy));
    EXPECT_EQ(copy.input_transform(), in);
    EXPECT_EQ(copy.output_transform(), out);
    const Locus probe = profile_locus("rgb-reference", 510, 3490, 7);
    EXPECT_TRUE((model.predict(probe.ratios).array() == copy.predict(probe.ratios).array()).all());
    for (Eigen::Index i = 0; i < probe.ratios.rows(); i += 37) {
      const double x[2] = {probe.ratios(i, 0), probe.ratios(i, 1)};
      double g1[2], g2[2];
      EXPECT_EQ(model.predict(x), copy.predict(x));
      EXPECT_EQ(model.predict_with_gradient(x, g1), copy.predict_with_gradient(x, g2));
      EXPECT_EQ(g1[0], g2[0]);
    }
  }
}

TEST(MlpJson, reads_version_1_files_as_untransformed) {
  const Mlp affine = single_layer_model(MlpInputTransform::kNone, MlpOutputTransform::kNone, 3, 1);
  nlohmann::json v1 = affine.to_json();
  EXPECT_EQ(v1["version"], kMlpFormatVersion);
  v1["version"] = 1;
  v1.erase("input_transform");
  v1.erase("output_transform");
  const Mlp old = Mlp::from_json(v1);
  EXPECT_EQ(old.input_transform(), MlpInputTransform::kNone);
  EXPECT_EQ(old.output_transform(), MlpOutputTransform::kNone);
  double gradient = 0;
  EXPECT_NEAR(predict_all_paths(old, 2, &gradient), 7, 1e-12);
}

TEST(MlpJson, rejects_unknown_versions_and_transforms_n) {
  const nlohmann::json good = small_locus_model().to_json();
  nlohmann::json j = good;
  j["version"] = 99;
  expect_mlp_error([&] { Mlp::from_json(j); }, {"version", "99"});
  j["version"] = 0;
  expect_mlp_error([&] { Mlp::from_json(j); }, {"version"});
  j["version"] = "2";
  expect_mlp_error([&] { Mlp::from_json(j); }, {"version"});

  j = good;
  j["input_transform"] = "sqrt";
  expect_mlp_error([&] { Mlp::from_json(j); }, {"input_transform", "sqrt"});
  j = good;
  j["output_transform"] = "kelvin";
  expect_mlp_error([&] { Mlp::from_json(j); }, {"output_transform", "kelvin"});
  j = good;
  j["output_transform"] = 1;
  expect_mlp_error([&] { Mlp::from_json(j); }, {"output_transform"});
  j = good;
  j.erase("output_transform");
  expect_mlp_error([&] { Mlp::from_json(j); }, {"missing key", "output_transform"});
  j = good;  // a version 1 file cannot name a transform it would then ignore
  j["version"] = 1;
  expect_mlp_error([&] { Mlp::from_json(j); }, {"version 1", "transform"});
}

TEST(MlpJson, rejects_missing_keys_bad_shapes_and_non_finite_numbers_n) {
  const nlohmann::json good = small_locus_model().to_json();
  EXPECT_NO_THROW(Mlp::from_json(good));

  nlohmann::json j = good;
  j.erase("layers");
  expect_mlp_error([&] { Mlp::from_json(j); }, {"missing key", "layers"});

  j = good;
  j["layers"][1].erase("bias");
  expect_mlp_error([&] { Mlp::from_json(j); }, {"missing key", "bias", "layers[1]"});

  j = good;
  j["layers"] = nlohmann::json::array();
  expect_mlp_error([&] { Mlp::from_json(j); }, {"layers", "non-empty"});

  j = good;  // a ragged weight matrix
  j["layers"][0]["weights"][5].erase(1);
  expect_mlp_error([&] { Mlp::from_json(j); }, {"layers[0].weights[5]", "1 columns"});

  j = good;  // layers that do not chain: drop one output of layer 1 (weights and bias)
  j["layers"][1]["weights"].erase(0);
  j["layers"][1]["bias"].erase(0);
  expect_mlp_error([&] { Mlp::from_json(j); }, {"layers[2].weights", "expected 31"});

  j = good;
  j["layers"][2]["bias"].push_back(0.5);
  expect_mlp_error([&] { Mlp::from_json(j); }, {"layers[2].bias", "17 values"});

  j = good;
  j["input_scale"].push_back(1.0);
  expect_mlp_error([&] { Mlp::from_json(j); }, {"input_scale"});

  j = good;
  j["layers"][1]["weights"][3][4] = kNan;
  expect_mlp_error([&] { Mlp::from_json(j); }, {"layers[1].weights[3][4]", "not finite"});

  j = good;  // how NaN comes back from text: JSON has no NaN, serialisers write null
  j["layers"][0]["bias"][2] = nullptr;
  expect_mlp_error([&] { Mlp::from_json(j); }, {"layers[0].bias[2]", "not a number"});

  j = good;
  j["output_scale"] = 0.0;
  expect_mlp_error([&] { Mlp::from_json(j); }, {"output_scale"});
}

TEST(MlpGradient, matches_central_finite_differences_and_the_locus_slope) {
  const Locus probe = profile_locus("rgb-reference", 520, 3480, 97);
  for (const auto& [in, out] : kTransformPairs) {
    const Mlp& model = small_locus_model(in, out);
    std::vector<double> slopes;
    for (Eigen::Index i = 0; i < probe.ratios.rows(); ++i) {
      const double x[2] = {probe.ratios(i, 0), probe.ratios(i, 1)};
      double grad[2];
      const double value = model.predict_with_gradient(x, grad);
      EXPECT_NEAR(value, model.predict(x), 0.01) << "float path agrees";
      for (int k = 0; k < 2; ++k) {
        // The network is piecewise linear in its transformed input: a small step stays on one
        // piece, where central differences are exact up to rounding and the transforms' own
        // curvature (relative 1e-14 here).
        const double h = 1e-7 * std::abs(x[k]);
        double up[2] = {x[0], x[1]}, down[2] = {x[0], x[1]}, unused[2];
        up[k] += h;
        down[k] -= h;
        const double numeric =
            (model.predict_with_gradient(up, unused) - model.predict_with_gradient(down, unused)) /
            (up[k] - down[k]);
        EXPECT_NEAR(grad[k], numeric, 1e-5 * std::abs(numeric) + 1e-3)
            << "sample " << i << " x" << k;
      }
      // Physics and the transforms' chain rule: along the locus, the predicted temperature
      // rises by about 1 degC per degC (a loosely trained network wavers around 1).
      const Locus step = profile_locus("rgb-reference", probe.temperature_c[i] - 5,
                                       probe.temperature_c[i] + 5, 10);
      const Eigen::RowVectorXd dx_dt = (step.ratios.row(1) - step.ratios.row(0)) / 10;
      slopes.push_back(grad[0] * dx_dt[0] + grad[1] * dx_dt[1]);
    }
    std::nth_element(slopes.begin(), slopes.begin() + slopes.size() / 2, slopes.end());
    EXPECT_NEAR(slopes[slopes.size() / 2], 1.0, 0.1)
        << "median slope, transforms " << static_cast<int>(in) << "/" << static_cast<int>(out);
  }
}

TEST(MlpPredict, single_sample_matches_batch_and_row_major_paths) {
  const Mlp& model = small_locus_model();
  const Locus probe = profile_locus("rgb-reference", 500, 3500, 3);  // several chunks
  const Eigen::VectorXd batch = model.predict(probe.ratios);
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;
  const RowMajor rows = probe.ratios;
  Eigen::VectorXd from_rows(rows.rows());
  model.predict_rows(rows.data(), rows.rows(), from_rows.data());
  EXPECT_TRUE((batch.array() == from_rows.array()).all()) << "same code path, same numbers";
  double worst = 0;
  for (Eigen::Index i = 0; i < rows.rows(); ++i) {
    worst = std::max(worst, std::abs(model.predict(rows.row(i).data()) - batch[i]));
  }
  // Both single precision, summed in different orders: a few thousandths of a degree.
  EXPECT_LT(worst, 0.01);
  EXPECT_THROW(model.predict(Eigen::MatrixXd(3, 5)), MlpError);
}

TEST(MlpPredict, empty_model_predicts_nan) {
  const Mlp empty;
  const double x[2] = {1, 2};
  EXPECT_TRUE(empty.empty());
  EXPECT_EQ(empty.input_size(), 0);
  EXPECT_TRUE(std::isnan(empty.predict(x)));
}

}  // namespace
}  // namespace pyrocam::test
