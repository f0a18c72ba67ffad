// A scene that cannot be run: the message names the file, the field, the value and the reason.
#pragma once

#include <stdexcept>

namespace dem {

struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace dem
