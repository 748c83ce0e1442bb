// The model loader's fast reading of the network's layers (mlp_layers_text.h): the same bits
// as the JSON parser's, and nothing (the parser's turn) for any text it is not sure of.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "detail/json_text.h"
#include "pyrocam/runtime/model.h"
#include "runtime/mlp_layers_text.h"

namespace pyrocam {
namespace {

using nlohmann::json;

bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  // memcmp of empty matrices would pass it their null data pointers (undefined behaviour).
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         (a.size() == 0 || std::memcmp(a.data(), b.data(),
                                       sizeof(double) * static_cast<std::size_t>(a.size())) == 0);
}

// What the JSON parser makes of the same layers text.
std::vector<MlpLayer> parsed(const std::string& text) {
  std::vector<MlpLayer> out;
  for (const json& l : json::parse(text)) {
    MlpLayer layer;
    const json& w = l.at("weights");
    layer.weights.resize(static_cast<Eigen::Index>(w.size()),
                         static_cast<Eigen::Index>(w[0].size()));
    for (std::size_t r = 0; r < w.size(); ++r)
      for (std::size_t c = 0; c < w[r].size(); ++c)
        layer.weights(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) =
            w[r][c].get<double>();
    layer.bias.resize(static_cast<Eigen::Index>(l.at("bias").size()));
    for (std::size_t i = 0; i < l.at("bias").size(); ++i)
      layer.bias[static_cast<Eigen::Index>(i)] = l.at("bias")[i].get<double>();
    out.push_back(layer);
  }
  return out;
}

void expect_same_as_the_parser(const std::string& text) {
  const auto fast = detail::read_layers_text(text);
  ASSERT_TRUE(fast.has_value()) << text;
  const std::vector<MlpLayer> slow = parsed(text);
  ASSERT_EQ(fast->size(), slow.size());
  for (std::size_t l = 0; l < slow.size(); ++l) {
    EXPECT_TRUE(same_bits((*fast)[l].weights, slow[l].weights)) << text;
    EXPECT_TRUE(same_bits((*fast)[l].bias, slow[l].bias)) << text;
  }
}

TEST(MlpLayersText, ReadsTheParsersBitsForEveryNumberForm) {
  expect_same_as_the_parser(
      R"([{"bias":[0.1,-2.5e-3,1E+2,-0,0,-0.0,3],"weights":[[1,2],[3.25,-4e-320]]}])");
  expect_same_as_the_parser(
      "[ {\n \"weights\" : [ [ 0.30000000000000004 , 1e308 ] ] ,\n \"bias\" : [ 5e-324 ] } ,"
      "{\"weights\":[[123456789012345678901234567890,-9007199254740993]],\"bias\":[]} ]");
  // Random doubles as the writer writes them (shortest round-trip text).
  std::srand(7);
  json layers = json::array();
  json w = json::array(), b = json::array();
  for (int r = 0; r < 20; ++r) {
    json row = json::array();
    for (int c = 0; c < 13; ++c)
      row.push_back((std::rand() - RAND_MAX / 2) * std::ldexp(1.0, std::rand() % 40 - 50));
    w.push_back(row);
    b.push_back(std::rand() * 1e-9);
  }
  layers.push_back({{"weights", w}, {"bias", b}});
  expect_same_as_the_parser(layers.dump());
  expect_same_as_the_parser(layers.dump(1));
}

TEST(MlpLayersText, LeavesToTheParserWhatItIsNotSureOf) {
  for (const char* text : {
           "[]",                                            // no layer
           R"([{"weights":[[1]],"bias":[inf]}])",           // not JSON
           R"([{"weights":[[01]],"bias":[1]}])",            // leading zero
           R"([{"weights":[[1.]],"bias":[1]}])",            // no digits after the point
           R"([{"weights":[[1e]],"bias":[1]}])",            // no exponent digits
           R"([{"weights":[[+1]],"bias":[1]}])",            // a plus sign
           R"([{"weights":[[1e999]],"bias":[1]}])",         // not finite
           R"([{"weights":[[1,2],[3]],"bias":[1]}])",       // ragged
           R"([{"weights":[],"bias":[1]}])",                // no rows
           R"([{"weights":[[]],"bias":[1]}])",              // an empty row
           R"([{"weights":[[1]]}])",                        // no bias
           R"([{"weights":[[1]],"bias":[1],"bias":[2]}])",  // twice
           R"([{"weights":[[1]],"bias":[1],"note":"x"}])",  // another key
           R"([{"weig\u0068ts":[[1]],"bias":[1]}])",        // an escape
           R"([{"weights":[[1]],"bias":[1]}] x)",           // trailing text
           R"([{"weights":[[1]],"bias":[1]})",              // truncated
           R"([{"weights":[[1]],"bias":[1]},])",            // trailing comma
       })
    EXPECT_FALSE(detail::read_layers_text(text).has_value()) << text;
}

TEST(MlpLayersText, FindsAMemberOnlyWhenItIsThereOnce) {
  const std::string doc = R"({"a": 1, "payload": {"mlp": {"layers": [1, 2]}, "x": "}"}})";
  const auto payload = detail::json_member_span(doc, 0, "payload");
  ASSERT_TRUE(payload);
  const auto mlp = detail::json_member_span(doc, payload->first, "mlp");
  ASSERT_TRUE(mlp);
  const auto layers = detail::json_member_span(doc, mlp->first, "layers");
  ASSERT_TRUE(layers);
  EXPECT_EQ(doc.substr(layers->first, layers->second - layers->first), "[1, 2]");
  EXPECT_FALSE(detail::json_member_span(R"({"k": 1, "k": 2})", 0, "k"));
  EXPECT_FALSE(detail::json_member_span(R"({"k": 1)", 0, "k"));
  EXPECT_FALSE(detail::json_member_span(R"([1])", 0, "k"));
  EXPECT_FALSE(detail::json_member_span(R"({"other": 1})", 0, "k"));
}

// The shipped test model through load_model (the fast path) and through the parser alone.
TEST(MlpLayersText, LoadedModelHasTheParsersWeights) {
  const char* dir = std::getenv("PYROCAM_TEST_MODEL_DIR");
  ASSERT_NE(dir, nullptr);
  for (const char* name : {"test-model-rgb.json", "test-model-nir5x5.json"}) {
    const std::filesystem::path path = std::filesystem::path(dir) / name;
    const ThermalModel m = load_model(path);
    std::ifstream in(path);
    const json file = json::parse(in);
    const Mlp slow = Mlp::from_json(file.at("payload").at("mlp"));
    ASSERT_EQ(m.mlp.layers().size(), slow.layers().size()) << name;
    for (std::size_t l = 0; l < slow.layers().size(); ++l) {
      EXPECT_TRUE(same_bits(m.mlp.layers()[l].weights, slow.layers()[l].weights)) << name;
      EXPECT_TRUE(same_bits(m.mlp.layers()[l].bias, slow.layers()[l].bias)) << name;
    }
  }
}

}  // namespace
}  // namespace pyrocam
