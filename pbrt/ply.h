// pbrt — PLY mesh reader (ASCII and binary, either endianness) for Shape "plymesh".
// Reads vertex positions, normals and texture coordinates (u v, s t, texture_u texture_v,
// texture_s texture_t) and faces (triangles and quads; quads are split along their 0-2 diagonal;
// other faces are skipped and counted).
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "pbrt/error.h"

namespace cmam::pbrt {

struct PlyMesh {
    std::vector<float> positions;  // xyz per vertex
    std::vector<float> normals;    // xyz per vertex, or empty
    std::vector<float> uvs;        // uv per vertex, or empty
    std::vector<int> indices;      // three per triangle
    // Faces with other than three or four vertices, skipped as pbrt-v3 skips them: their number
    // and the first one's vertex count.
    std::size_t skipped_faces = 0;
    std::size_t first_skipped_size = 0;
};

/// What a PLY header announces, before any vertex is read.
struct PlyCounts {
    std::size_t vertices = 0, faces = 0;
    bool normals = false, uvs = false;
};
/// Called with the header's counts before the data is read; throws to refuse the file.
using PlyCheck = std::function<void(const PlyCounts&)>;

/// Reads the PLY file at `path`. When it cannot be read or is malformed: a SceneError not tied
/// to a scene location, whose message names the file and the reason ("mesh.ply: PLY header has
/// no end_header"). `check`, if given, sees the header's counts first.
PlyMesh read_ply(const std::string& path, const PlyCheck& check = {});

}  // namespace cmam::pbrt
