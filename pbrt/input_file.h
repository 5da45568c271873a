// pbrt — what every input file (scene, Include, PLY) must be before it is read: a regular file.
// A directory reads as nothing, and a device or a pipe (/dev/zero) can be read without end.
#pragma once

#include <cstdint>
#include <string>

namespace cmam::pbrt {

/// Largest scene file (main file or Include) cmam reads into memory.
constexpr std::uintmax_t kMaxSceneFileBytes = std::uintmax_t(1) << 30;

/// Why `path` cannot be read as an input file ("it is a directory", "it is not a regular file"),
/// or "" when it is a regular file or cannot be examined (opening it then says why).
std::string not_a_regular_file(const std::string& path);

}  // namespace cmam::pbrt
