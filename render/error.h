// render — the library's exception for everything that is not a problem of the scene file:
// image files that cannot be read or written, a render that does not fit in memory, the ray
// tracing device. `what()` is the complete message. Problems located in a scene file are
// pbrt::SceneError ("file:line:col: error: …"), which the scene builder shares with the parser.
#pragma once

#include <stdexcept>

namespace cmam::render {

class RenderError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

}  // namespace cmam::render
