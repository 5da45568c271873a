// pbrt-v3's "heightfield" and "nurbs" shapes, made into triangle meshes when the scene is built:
// the height field's grid and (u,v); the NURBS evaluation against the B-spline basis computed
// from its definition, rational patches that lie on circles, pbrt-v3's dicing and its errors.
#include "render/patches.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "pbrt/error.h"
#include "render/build_scene.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {

std::unique_ptr<Scene> world(const std::string& s) {
    return test::scene_from("Camera \"perspective\" WorldBegin " + s + " WorldEnd");
}

std::string error_of(const std::string& s) {
    try {
        world(s);
    } catch (const pbrt::SceneError& e) {
        return e.what();
    }
    return "";
}

// The B-spline basis function N_(i,order)(t) by the Cox–de Boor recursion from its definition
// (t strictly inside a knot span).
double basis(const std::vector<double>& k, int i, int order, double t) {
    if (order == 1) return k[i] <= t && t < k[i + 1] ? 1 : 0;
    double out = 0;
    if (k[i + order - 1] > k[i])
        out += (t - k[i]) / (k[i + order - 1] - k[i]) * basis(k, i, order - 1, t);
    if (k[i + order] > k[i + 1])
        out += (k[i + order] - t) / (k[i + order] - k[i + 1]) * basis(k, i + 1, order - 1, t);
    return out;
}

// The rational surface at (u, v) from the basis: Σ N_i(u) N_j(v) Pw_ij, divided by its weight.
std::array<double, 3> surface(const NurbsPatch& p, double u, double v) {
    double s[4] = {0, 0, 0, 0};
    for (int j = 0; j < p.nv; ++j)
        for (int i = 0; i < p.nu; ++i) {
            const double w = basis(p.uknots, i, p.uorder, u) * basis(p.vknots, j, p.vorder, v);
            for (int c = 0; c < 4; ++c) s[c] += w * p.cp[static_cast<std::size_t>(j * p.nu + i)][c];
        }
    return {s[0] / s[3], s[1] / s[3], s[2] / s[3]};
}

// A clamped knot vector of n + order knots with random interior knots (some repeated).
std::vector<double> knots(int n, int order, std::mt19937& rng) {
    std::uniform_real_distribution<double> U(0, 1);
    std::vector<double> k(static_cast<std::size_t>(order), 0.0);
    std::vector<double> inner;
    for (int i = 0; i < n - order; ++i) inner.push_back(std::round(U(rng) * 8) / 8);
    std::sort(inner.begin(), inner.end());
    k.insert(k.end(), inner.begin(), inner.end());
    k.insert(k.end(), static_cast<std::size_t>(order), 1.0);
    return k;
}

}  // namespace

TEST(Heightfield, IsPbrtV3sGridOverTheUnitSquare) {
    const ShapeMesh m = heightfield_mesh(3, 2, {0, 1, 2, 3, 4, 5});
    ASSERT_EQ(m.positions.size(), 18u);
    EXPECT_TRUE(m.normals.empty());
    // Vertex (i, j) at (i / 2, j, z), its (u,v) the same x and y.
    EXPECT_FLOAT_EQ(m.positions[3 * 4 + 0], 0.5f);
    EXPECT_FLOAT_EQ(m.positions[3 * 4 + 1], 1.0f);
    EXPECT_FLOAT_EQ(m.positions[3 * 4 + 2], 4.0f);
    EXPECT_FLOAT_EQ(m.uvs[2 * 4], 0.5f);
    EXPECT_FLOAT_EQ(m.uvs[2 * 4 + 1], 1.0f);
    // Two cells, two triangles each, wound (i,j) (i+1,j) (i+1,j+1), (i,j) (i+1,j+1) (i,j+1).
    const std::vector<int> want = {0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4};
    EXPECT_EQ(m.indices, want);

    // Through the scene: a ray down onto the middle of the first cell's second triangle meets
    // the plane through its corners, with the (u,v) of its position.
    auto s =
        world("Shape \"heightfield\" \"integer nu\" 3 \"integer nv\" 2 \"float Pz\" [0 1 2 3 4 5]");
    ASSERT_EQ(s->primitives.size(), 1u);
    EXPECT_EQ(s->primitives[0]->indices.size(), 12u);
    const auto h = s->intersect(Vec3(0.1f, 0.6f, 10), Vec3(0, 0, -1), 0, 100);
    ASSERT_TRUE(h.has_value());
    EXPECT_NEAR(h->p.z, 2 * 0.1f + 3 * 0.6f, 1e-5);  // z = 2 x + 3 y over the cell
    EXPECT_NEAR(h->u, 0.1f, 1e-5);
    EXPECT_NEAR(h->v, 0.6f, 1e-5);

    EXPECT_EQ(error_of("Shape \"heightfield\" \"integer nu\" 3 \"integer nv\" 2 \"float Pz\" [0 1 "
                       "2 3 4]"),
              "t.pbrt:1:83: error: Pz has 5 heights; nu x nv = 6");
    EXPECT_EQ(
        error_of("Shape \"heightfield\" \"integer nu\" 1 \"integer nv\" 2 \"float Pz\" [0 1]"),
        "t.pbrt:1:53: error: nu must be at least 2, got 1");
    EXPECT_EQ(error_of("Shape \"heightfield\" \"integer nu\" 2 \"float Pz\" [0 1]"),
              "t.pbrt:1:33: error: \"heightfield\" needs an \"integer nv\" parameter");
}

// Points and both partial derivatives against the surface computed from the basis (derivatives
// by central differences), for orders 2 to 5, random knots with repeats, random weights.
TEST(Nurbs, EvaluationIsTheRationalBSplineSurface) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(0, 1);
    int checked = 0;
    for (int trial = 0; trial < 40; ++trial) {
        NurbsPatch p;
        p.uorder = 2 + trial % 4;
        p.vorder = 2 + (trial / 4) % 4;
        p.nu = p.uorder + trial % 3;
        p.nv = p.vorder + (trial + 1) % 3;
        p.uknots = knots(p.nu, p.uorder, rng);
        p.vknots = knots(p.nv, p.vorder, rng);
        for (int i = 0; i < p.nu * p.nv; ++i) {
            const double w = 0.5 + U(rng);
            p.cp.push_back({w * (U(rng) - 0.5), w * (U(rng) - 0.5), w * U(rng), w});
        }
        ASSERT_FALSE(nurbs_patch_error(p).has_value()) << nurbs_patch_error(p)->message;
        for (int k = 0; k < 20; ++k) {
            const double u = U(rng), v = U(rng), h = 1e-6;
            // Away from knots (where the basis is not smooth and the differences straddle one).
            auto near_knot = [&](const std::vector<double>& kn, double t) {
                for (double x : kn)
                    if (std::abs(t - x) < 1e-4) return true;
                return false;
            };
            if (near_knot(p.uknots, u) || near_knot(p.vknots, v)) continue;
            const NurbsPoint e = nurbs_evaluate(p, u, v);
            const auto want = surface(p, u, v);
            const auto up = surface(p, u + h, v), um = surface(p, u - h, v),
                       vp = surface(p, u, v + h), vm = surface(p, u, v - h);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(e.p[c], want[c], 1e-12) << trial << " " << c;
                EXPECT_NEAR(e.dpdu[c], (up[c] - um[c]) / (2 * h), 1e-5) << trial << " " << c;
                EXPECT_NEAR(e.dpdv[c], (vp[c] - vm[c]) / (2 * h), 1e-5) << trial << " " << c;
            }
            ++checked;
        }
    }
    EXPECT_GT(checked, 600);
}

// A quarter circle in u (quadratic, weights 1, √½, 1) swept linearly in v: every point of the
// mesh lies on the unit cylinder and every normal points out from its axis, which needs the
// homogeneous evaluation and the quotient rule of its derivative.
TEST(Nurbs, RationalPatchesLieOnTheirConics) {
    const double r = std::sqrt(0.5);
    NurbsPatch p;
    p.nu = 3;
    p.nv = 2;
    p.uorder = 3;
    p.vorder = 2;
    p.uknots = {0, 0, 0, 1, 1, 1};
    p.vknots = {0, 0, 1, 1};
    p.cp = {{1, 0, 0, 1}, {r, r, 0, r}, {0, 1, 0, 1}, {1, 0, 2, 1}, {r, r, 2 * r, r}, {0, 1, 2, 1}};
    p.u1 = 1;
    p.v1 = 1;
    const ShapeMesh m = nurbs_mesh(p);
    ASSERT_EQ(m.positions.size(), 3u * kNurbsDice * kNurbsDice);
    ASSERT_EQ(m.indices.size(), 6u * (kNurbsDice - 1) * (kNurbsDice - 1));
    for (std::size_t i = 0; i < m.positions.size(); i += 3) {
        const float x = m.positions[i], y = m.positions[i + 1];
        EXPECT_NEAR(std::hypot(x, y), 1.0f, 1e-6) << i;
        EXPECT_NEAR(m.normals[i] * x + m.normals[i + 1] * y, 1.0f, 1e-5) << i;
        EXPECT_NEAR(m.normals[i + 2], 0.0f, 1e-6) << i;
    }
    // pbrt-v3's (u,v): the parameters, evenly spaced; vertex (i, j) at index j dice + i.
    EXPECT_FLOAT_EQ(m.uvs[2 * 1], 1.0f / (kNurbsDice - 1));
    EXPECT_FLOAT_EQ(m.uvs[2 * kNurbsDice + 1], 1.0f / (kNurbsDice - 1));
    // Facets wound as the normals point.
    for (std::size_t t = 0; t < m.indices.size(); t += 3) {
        auto P = [&](int v) {
            return Vec3(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
        };
        const int a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
        const Vec3 n = cross(P(b) - P(a), P(c) - P(a));
        const Vec3 na(m.normals[3 * a], m.normals[3 * a + 1], m.normals[3 * a + 2]);
        EXPECT_GT(dot(n, na), 0) << t;
    }
}

// A patch whose first row of control points is one point (a pole): dP/du vanishes there, and
// the normal is taken just inside, where it is the surface's limit; every normal is a unit
// vector.
TEST(Nurbs, PolesGetTheNormalFromJustInside) {
    NurbsPatch p;
    p.nu = 3;
    p.nv = 3;
    p.uorder = 3;
    p.vorder = 3;
    p.uknots = {0, 0, 0, 1, 1, 1};
    p.vknots = {0, 0, 0, 1, 1, 1};
    // A dome: the v = 0 row at its apex (0, 0, 1), the others on circles below.
    p.cp = {{0, 0, 1, 1}, {0, 0, 1, 1},  {0, 0, 1, 1},   {1, -1, 1, 1}, {1, 0, 1, 1},
            {1, 1, 1, 1}, {1, -1, 0, 1}, {1.5, 0, 0, 1}, {1, 1, 0, 1}};
    const ShapeMesh m = nurbs_mesh(p);
    for (std::size_t i = 0; i < m.normals.size(); i += 3) {
        const Vec3 n(m.normals[i], m.normals[i + 1], m.normals[i + 2]);
        EXPECT_NEAR(length(n), 1.0f, 1e-5) << i / 3;
    }
    // The apex row's normals are those of the points next to it.
    for (int i = 0; i < kNurbsDice; ++i) {
        const std::size_t a = 3 * static_cast<std::size_t>(i),
                          b = 3 * static_cast<std::size_t>(kNurbsDice + i);
        const float d = m.normals[a] * m.normals[b] + m.normals[a + 1] * m.normals[b + 1] +
                        m.normals[a + 2] * m.normals[b + 2];
        EXPECT_GT(d, 0.9f) << i;
    }
}

TEST(Nurbs, BuildsThroughTheSceneWithPbrtV3sErrors) {
    const std::string bilinear =
        "Shape \"nurbs\" \"integer nu\" 2 \"integer nv\" 2 \"integer uorder\" 2 \"integer "
        "vorder\" 2 \"float uknots\" [0 0 1 1] \"float vknots\" [0 0 1 1] ";
    // A bilinear patch over [0, 2] x [0, 1] at z = 1, its normals +z, its (u,v) the parameters.
    auto s = world(bilinear + "\"point3 P\" [0 0 1 2 0 1 0 1 1 2 1 1]");
    ASSERT_EQ(s->primitives.size(), 1u);
    const auto h = s->intersect(Vec3(0.5f, 0.25f, 5), Vec3(0, 0, -1), 0, 100);
    ASSERT_TRUE(h.has_value());
    EXPECT_NEAR(h->p.z, 1.0f, 1e-6);
    EXPECT_NEAR(h->u, 0.25f, 1e-5);
    EXPECT_NEAR(h->v, 0.25f, 1e-5);
    EXPECT_NEAR(h->ns.z, 1.0f, 1e-6);
    // "u0".."u1" dices part of it: the mesh reaches x = 1 only.
    auto half = world(bilinear + "\"float u1\" 0.5 \"point3 P\" [0 0 1 2 0 1 0 1 1 2 1 1]");
    EXPECT_FALSE(half->intersect(Vec3(1.5f, 0.5f, 5), Vec3(0, 0, -1), 0, 100).has_value());
    EXPECT_TRUE(half->intersect(Vec3(0.5f, 0.5f, 5), Vec3(0, 0, -1), 0, 100).has_value());

    EXPECT_EQ(error_of(bilinear + "\"point3 P\" [0 0 1 2 0 1 0 1 1]"),
              "t.pbrt:1:165: error: \"nurbs\": 3 control points; nu x nv = 4");
    EXPECT_EQ(error_of(bilinear + "\"float Pw\" [0 0 1 1 2 0 1 1 0 1 1 1 2 1 1]"),
              "t.pbrt:1:165: error: Pw needs four numbers (x w, y w, z w, w) per control point, "
              "got 15");
    EXPECT_EQ(error_of(bilinear + "\"float u0\" -1 \"point3 P\" [0 0 1 2 0 1 0 1 1 2 1 1]"),
              "t.pbrt:1:165: error: \"nurbs\": u0 must be within the knots' range [0, 1], got -1");
    EXPECT_EQ(error_of("Shape \"nurbs\" \"integer nu\" 2 \"integer nv\" 2 \"integer uorder\" 2 "
                       "\"integer vorder\" 3 \"float uknots\" [0 0 1 1] \"float vknots\" [0 0 1 "
                       "1 1] \"point3 P\" [0 0 1 2 0 1 0 1 1 2 1 1]"),
              "t.pbrt:1:96: error: \"nurbs\": vorder 3 needs at least as many control points "
              "along v, got nv 2");
    EXPECT_EQ(error_of("Shape \"nurbs\" \"integer nu\" 2 \"integer nv\" 2 \"integer uorder\" 2 "
                       "\"integer vorder\" 2 \"float uknots\" [0 1 0 1] \"float vknots\" [0 0 1 "
                       "1] \"point3 P\" [0 0 1 2 0 1 0 1 1 2 1 1]"),
              "t.pbrt:1:115: error: \"nurbs\": uknots must not decrease");
    EXPECT_EQ(error_of("Shape \"nurbs\" \"integer nu\" 2 \"integer nv\" 2 \"integer uorder\" 2 "
                       "\"integer vorder\" 2 \"float uknots\" [0 0 1] \"float vknots\" [0 0 1 "
                       "1] \"point3 P\" [0 0 1 2 0 1 0 1 1 2 1 1]"),
              "t.pbrt:1:115: error: \"nurbs\": uknots has 3 values; nu 2 and uorder 2 take 4");
    EXPECT_EQ(error_of("Shape \"nurbs\" \"integer nu\" 2 \"integer nv\" 2 \"integer uorder\" 2"),
              "t.pbrt:1:33: error: \"nurbs\" needs an \"integer vorder\" parameter");
}
