// cmam::texture — convex polygons in texel space: clipping, difference with a convex hull, the
// convex hull itself, and the exact integral of the box-reconstructed texture over a polygon
// (algorithms.md §5). Used by the CMAM's convex hull weighting (paper §4).
#pragma once

#include <cmam/texture/sat.h>
#include <cmam/texture/vec2.h>

#include <vector>

namespace cmam::texture {

/// Vertices in texels, in order; counter-clockwise unless stated.
using Polygon = std::vector<Vec2d>;

/// Signed area (positive for counter-clockwise).
double signed_area(const Polygon& p);
/// The part of `p` on the left of the directed line a -> b (Sutherland-Hodgman).
Polygon clip_left(const Polygon& p, Vec2d a, Vec2d b);
/// Convex pieces, disjoint, whose union is t \ h (t convex, h convex and counter-clockwise).
/// No pieces means t lies inside h.
std::vector<Polygon> difference(const Polygon& t, const Polygon& h);
/// Convex hull, counter-clockwise (Andrew's monotone chain); collinear points dropped.
Polygon convex_hull(std::vector<Vec2d> points);

/// Exact integral of the box-reconstructed texture over `p` (texel space, any orientation gives
/// the integral for its counter-clockwise version), via Green's theorem on the table's row
/// prefixes: O(perimeter in texels). The wrap modes are the table's. A vertex beyond 2^30 texels
/// or not a number gives the mean times the area (0 if that is not finite).
Texel polygon_integral(const SummedAreaTable& sat, const Polygon& p);
/// The same by clipping `p` to every texel cell it covers: O(cells x vertices); a test oracle.
Texel polygon_integral_cells(const Image& image, const Polygon& p);

}  // namespace cmam::texture
