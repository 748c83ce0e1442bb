// The thermal model that the runtime's estimators and checks share (not installed).
#pragma once

#include <memory>
#include <string>

#include "pyrocam/core/error.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {

// *model; throws InputError naming `user` when there is none.
inline const ThermalModel& require_model(const std::shared_ptr<const ThermalModel>& model,
                                         const char* user) {
  if (!model) throw InputError(std::string(user) + ": no thermal model");
  return *model;
}

}  // namespace pyrocam
