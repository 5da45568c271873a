// render — pbrt-v3's "heightfield" and "nurbs" shapes as the triangle meshes pbrt-v3 makes of
// them when the scene is built: a height field's grid of heights over the unit square, and a
// NURBS surface evaluated on a 30 x 30 grid of its parameters with its normals and (u,v).
// algorithms.md §22.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "render/tessellate.h"

namespace cmam::render {

/// pbrt-v3's height field: nu x nv heights `z` (u fastest) at (x, y) = (i / (nu - 1),
/// j / (nv - 1)), which are the vertices' (u,v) too; no normals. nu, nv >= 2 and
/// z.size() == nu nv (the builder's checks).
ShapeMesh heightfield_mesh(int nu, int nv, const std::vector<double>& z);

/// A NURBS surface as pbrt-v3's "nurbs" shape gives it: nu x nv control points (u fastest) in
/// homogeneous form (x w, y w, z w, w: "Pw", or a "P" point with w = 1), the orders (degree + 1)
/// and knot vectors along u and v, and the parameter ranges [u0, u1] x [v0, v1] to dice.
struct NurbsPatch {
    int nu = 0, nv = 0, uorder = 0, vorder = 0;
    std::vector<double> uknots, vknots;  // nu + uorder and nv + vorder, non-decreasing
    std::vector<std::array<double, 4>> cp;
    double u0 = 0, u1 = 1, v0 = 0, v1 = 1;
};

/// What is wrong with a patch, if anything: the counts, orders from 2 to the control points'
/// count (and 32), non-decreasing finite knots spanning a range, the parameter ranges within the
/// knots' (knot t_(order-1) to t_n), finite control points. `parameter` is the pbrt-v3
/// parameter at fault ("P" for the control points).
struct NurbsPatchError {
    std::string parameter, message;
};
std::optional<NurbsPatchError> nurbs_patch_error(const NurbsPatch& p);

/// The surface point and its partial derivatives at (u, v) (within the patch's ranges).
struct NurbsPoint {
    std::array<double, 3> p, dpdu, dpdv;
};
NurbsPoint nurbs_evaluate(const NurbsPatch& p, double u, double v);

/// pbrt-v3's dicing: `dice` x `dice` points at evenly spaced (u, v) over [u0, u1] x [v0, v1]
/// (their (u,v) the parameters), normals dP/du x dP/dv, facets wound (i, j), (i+1, j),
/// (i+1, j+1) and (i, j), (i+1, j+1), (i, j+1). Positions may be non-finite where a weight
/// vanishes (the builder's check).
inline constexpr int kNurbsDice = 30;
ShapeMesh nurbs_mesh(const NurbsPatch& p, int dice = kNurbsDice);

}  // namespace cmam::render
