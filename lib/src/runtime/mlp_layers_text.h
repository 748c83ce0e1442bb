// An MLP's layers read straight from a model file's text. They are most of the file (a colour
// model's 3 MB holds 2.2 MB of weights), and a JSON parser spends most of a model's load on their
// numbers: std::from_chars reads them several times faster, to the same doubles (both round
// correctly), which shortens every start of ratiotemp and pyrocam-calib.
#pragma once

#include <optional>
#include <string_view>
#include <vector>

#include "pyrocam/runtime/mlp.h"

namespace pyrocam::detail {

// The layers of `text`, the JSON value of an MLP's "layers": an array of objects each holding
// exactly "weights" (an array of arrays of numbers) and "bias" (an array of numbers), in either
// order, with any white space. Nothing when the text is anything else, a number is not a JSON
// number or not finite, or a matrix's rows differ in length: the caller then reads the text
// with the JSON parser, which names what is wrong. Shapes are checked as Mlp's constructor
// checks them, not here.
std::optional<std::vector<MlpLayer>> read_layers_text(std::string_view text);

}  // namespace pyrocam::detail
