// eval — the one exception type of the evaluation library.
#pragma once

#include <stdexcept>

namespace cmam::eval {

/// What every throw in eval/ throws: images of different sizes, a report file that cannot be
/// written. Errors of the libraries below (a scene, an image file) keep their own types.
class EvalError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

}  // namespace cmam::eval
