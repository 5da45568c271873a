// pbrt — PLY mesh reader (ASCII and binary, either endianness) for Shape "plymesh".
// Reads vertex positions, normals and texture coordinates (u v, s t, texture_u texture_v,
// texture_s texture_t) and faces (triangles and quads; quads are split along their 0-2 diagonal).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace cmam::pbrt {

struct PlyMesh {
    std::vector<float> positions;  // xyz per vertex
    std::vector<float> normals;    // xyz per vertex, or empty
    std::vector<float> uvs;        // uv per vertex, or empty
    std::vector<int> indices;      // three per triangle
};

/// Error reading a PLY file; what() names the file and the reason.
class PlyError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

PlyMesh read_ply(const std::string& path);

}  // namespace cmam::pbrt
