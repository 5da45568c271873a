// render — Loop subdivision of triangle meshes (pbrt-v3's "loopsubdiv" shape), at load time.
// algorithms.md §16: each level splits every triangle in four with Loop's weights (boundaries
// follow the cubic B-spline of the boundary curve); after the last level every vertex moves to
// its limit position, and the normals are the cross products of the limit surface's tangents.
#pragma once

#include <cstddef>
#include <vector>

namespace cmam::render {

struct SubdividedMesh {
    std::vector<float> positions;  // xyz per vertex
    std::vector<float> normals;  // xyz per vertex, against the triangles' winding (pbrt-v3's side)
    std::vector<int> indices;    // three per triangle, wound as the control mesh
};

/// The control mesh (`positions` xyz per vertex, `indices` three per triangle, each index in
/// range) subdivided `levels` times and pushed to the limit surface. Level 0 gives the control
/// mesh's vertices on the limit surface.
SubdividedMesh loop_subdivide(const std::vector<float>& positions, const std::vector<int>& indices,
                              int levels);

/// The most triangles a "loopsubdiv" shape is subdivided into; fewer levels are used beyond.
inline constexpr double kMaxSubdividedTriangles = double(1 << 24);

/// Triangles after `levels` levels of a mesh of `triangles`: triangles x 4^levels.
double loop_subdivided_triangles(std::size_t triangles, int levels);

/// The most levels, up to `levels`, that keep `triangles` within kMaxSubdividedTriangles.
int loop_levels_that_fit(std::size_t triangles, int levels);

}  // namespace cmam::render
