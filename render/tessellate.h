// render — pbrt-v3's cylinder, cone, paraboloid and hyperboloid as triangle meshes, made when
// the scene is built: vertices on the exact surface with its (u,v) and normals, on a grid fine
// enough that the facets do not show at ordinary sizes. algorithms.md §15.
#pragma once

#include <string>
#include <vector>

namespace cmam::render {

/// A mesh in object space: 3 floats per position and normal, 2 per (u,v), 3 indices per
/// triangle (wound so that the facet normal agrees with the normals). Also the height fields'
/// and NURBS patches' (patches.h).
struct ShapeMesh {
    std::vector<float> positions, normals, uvs;
    std::vector<int> indices;
};

/// The parameters of the four shapes (pbrt-v3's names and defaults; angles in degrees).
struct QuadricParams {
    double radius = 1, zmin = -1, zmax = 1, height = 1, phimax = 360;
    double p1[3] = {0, 0, 0}, p2[3] = {1, 1, 1};  // hyperboloid
};

/// The mesh of `type` ("cylinder", "cone", "paraboloid" or "hyperboloid"); `segments` steps
/// around the full circle (fewer for a partial phimax).
ShapeMesh tessellate(const std::string& type, const QuadricParams& p, int segments = 128);

}  // namespace cmam::render
