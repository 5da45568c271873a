// Loop subdivision (pbrt-v3's "loopsubdiv"): closed forms on a regular tetrahedron and a single
// triangle, the counts of each level, the normals' side, and the shape in a scene.
#include "render/subdivide.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "expect_throw.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {

// A regular tetrahedron centred on the origin, wound outwards.
const std::vector<float> kTetraP = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
const std::vector<int> kTetraIdx = {0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2};

Vec3 at(const std::vector<float>& v, std::size_t i) {
    return {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
}

TEST(LoopSubdivision, TetrahedronLimitIsAFifthOfEachVertex) {
    // Valence 3: beta = 3/16, gamma = 1 / (3 + 3 / (8 beta)) = 1/5, and the three neighbours sum
    // to -p: the limit point is 0.4 p + 0.2 (-p) = p / 5. The normal lies along p, pointing in
    // as pbrt-v3's do (against the outward winding).
    const SubdividedMesh m = loop_subdivide(kTetraP, kTetraIdx, 0);
    ASSERT_EQ(m.positions.size(), kTetraP.size());
    ASSERT_EQ(m.indices, kTetraIdx);
    for (std::size_t v = 0; v < 4; ++v) {
        const Vec3 p = at(m.positions, v), p0 = at(kTetraP, v), n = normalize(at(m.normals, v));
        EXPECT_NEAR(length(p - p0 / 5), 0, 1e-6) << v;
        EXPECT_NEAR(dot(n, normalize(p0)), -1, 1e-5) << v;
    }
}

TEST(LoopSubdivision, OneLevelOfTheTetrahedronIsItsMidpointMeshScaledByAQuarter) {
    // Even vertices: (1 - 3 beta) p + beta (-p) = p / 4; odd: 3/8 (a + b) + 1/8 (c + d) =
    // (a + b) / 4. The old vertices keep valence 3, so their limit lies on the ray through
    // them, inside the scaled mesh; every normal points in (pbrt-v3's side).
    const SubdividedMesh m = loop_subdivide(kTetraP, kTetraIdx, 1);
    EXPECT_EQ(m.indices.size(), 4 * kTetraIdx.size());
    EXPECT_EQ(m.positions.size(), 3u * (4 + 6));  // V + E
    for (std::size_t v = 0; v < 4; ++v) {
        const Vec3 p = at(m.positions, v), p0 = at(kTetraP, v);
        EXPECT_NEAR(dot(normalize(p), normalize(p0)), 1, 1e-6) << v;
        EXPECT_LT(length(p), length(p0) / 4 + 1e-6) << v;
        EXPECT_LT(dot(at(m.normals, v), p0), 0) << v;
    }
    for (std::size_t v = 4; v < 10; ++v) EXPECT_LT(dot(at(m.normals, v), at(m.positions, v)), 0);
}

TEST(LoopSubdivision, TrianglesQuadrupleAndAClosedMeshKeepsEulersCharacteristic) {
    for (int levels = 0; levels <= 3; ++levels) {
        const SubdividedMesh m = loop_subdivide(kTetraP, kTetraIdx, levels);
        const std::size_t f = m.indices.size() / 3, v = m.positions.size() / 3;
        EXPECT_EQ(double(f), loop_subdivided_triangles(4, levels));
        EXPECT_EQ(int(v) - int(3 * f / 2) + int(f), 2) << levels;  // V - E + F of a sphere
        EXPECT_EQ(m.normals.size(), m.positions.size());
    }
}

TEST(LoopSubdivision, BoundaryFollowsTheBoundaryRules) {
    // One triangle: every vertex and edge is on the boundary. Level 0 limit: 3/5 p + 1/5 of
    // the two others; one level: corners 3/4 p + 1/8 (q0 + q1), edges at their midpoints, then
    // the limit. The surface stays in the plane, its normals -z, against the winding (+z): pbrt-v3
    // crosses the boundary tangents in the order that gives that side.
    const std::vector<float> P = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const SubdividedMesh m0 = loop_subdivide(P, {0, 1, 2}, 0);
    EXPECT_NEAR(length(at(m0.positions, 0) - Vec3(0.2f, 0.2f, 0)), 0, 1e-6);
    EXPECT_NEAR(length(at(m0.positions, 1) - Vec3(0.6f, 0.2f, 0)), 0, 1e-6);
    const SubdividedMesh m2 = loop_subdivide(P, {0, 1, 2}, 2);
    EXPECT_EQ(m2.indices.size(), 3u * 16);
    for (std::size_t v = 0; v < m2.positions.size() / 3; ++v) {
        EXPECT_EQ(at(m2.positions, v).z, 0);
        const Vec3 n = normalize(at(m2.normals, v));
        EXPECT_NEAR(n.z, -1, 1e-6) << v;
    }
    // Reversed winding: the normals turn with it.
    const SubdividedMesh r = loop_subdivide(P, {0, 2, 1}, 1);
    for (std::size_t v = 0; v < r.normals.size() / 3; ++v) EXPECT_GT(at(r.normals, v).z, 0);
}

TEST(LoopSubdivision, RegularPlanarGridInteriorStaysPut) {
    // A regular triangulated grid (valence 6 inside): interior vertices are the average of a
    // symmetric ring, so the limit of the centre vertex is the vertex itself.
    std::vector<float> P;
    std::vector<int> idx;
    const int n = 5;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) P.insert(P.end(), {float(x) + 0.5f * float(y), float(y), 0});
    for (int y = 0; y + 1 < n; ++y)
        for (int x = 0; x + 1 < n; ++x) {
            const int a = y * n + x, b = a + 1, c = a + n, d = c + 1;
            idx.insert(idx.end(), {a, b, c, b, d, c});
        }
    const SubdividedMesh m = loop_subdivide(P, idx, 0);
    const int centre = 2 * n + 2;
    EXPECT_NEAR(length(at(m.positions, centre) - at(P, centre)), 0, 1e-6);
    EXPECT_NEAR(normalize(at(m.normals, centre)).z, -1, 1e-6);
}

TEST(LoopSubdivision, SceneShapeSubdividesWithNormalsAndNoUv) {
    const std::string tetra =
        "Shape \"loopsubdiv\" \"integer levels\" 2 \"point3 P\" [1 1 1 1 -1 -1 -1 1 -1 -1 -1 1] "
        "\"integer indices\" [0 1 2 0 2 3 0 3 1 1 3 2]";
    auto s = test::scene_from("Camera \"perspective\" WorldBegin " + tetra + " WorldEnd");
    ASSERT_EQ(s->primitives.size(), 1u);
    const Primitive& p = *s->primitives[0];
    EXPECT_EQ(p.indices.size(), 3u * 4 * 16);
    EXPECT_EQ(p.normals.size(), p.positions.size());
    EXPECT_TRUE(p.uvs.empty());
    // Every point of the limit surface lies inside the control tetrahedron's circumsphere.
    for (const Vec3& q : p.positions) EXPECT_LT(length(q), std::sqrt(3.0f));
    EXPECT_THROW_MSG(
        test::scene_from("Camera \"perspective\" WorldBegin Shape \"loopsubdiv\" "
                         "\"integer levels\" -1 \"point3 P\" [0 0 0 1 0 0 0 1 0] WorldEnd"),
        pbrt::SceneError, "t.pbrt:1:52: error: levels must be 0 or more, got -1");
}

TEST(LoopSubdivision, LevelsAreCappedAtTheTriangleLimit) {
    EXPECT_EQ(loop_levels_that_fit(2, 3), 3);
    EXPECT_EQ(loop_levels_that_fit(1, 30), 12);  // 4^12 = 2^24 triangles
    EXPECT_EQ(loop_levels_that_fit(2, 30), 11);
    EXPECT_EQ(loop_levels_that_fit(std::size_t(1) << 25, 2), 0);
}

}  // namespace
