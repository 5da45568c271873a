#include "render/tessellate.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cmam::render {

QuadricMesh tessellate(const std::string& type, const QuadricParams& p, int segments) {
    const double phi_max = std::clamp(p.phimax, 0.0, 360.0) * std::numbers::pi / 180;
    const int nu =
        std::max(2, static_cast<int>(std::ceil(segments * phi_max / (2 * std::numbers::pi))));
    // A cylinder's quads are flat rectangles: one row. The others need rows: the paraboloid
    // curves along v, a hyperboloid's quads are twisted (their diagonal leaves the surface),
    // and a cone's taper skews (u,v) across a long facet.
    const int nv = type == "cylinder" ? 1 : std::max(8, segments / 4);
    double a[3] = {p.p1[0], p.p1[1], p.p1[2]}, b[3] = {p.p2[0], p.p2[1], p.p2[2]};
    if (type == "hyperboloid" && b[2] == 0) std::swap(a, b);  // as pbrt-v3 orders them
    const double z0 = std::min(p.zmin, p.zmax), z1 = std::max(p.zmin, p.zmax);

    QuadricMesh m;
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i) {
            const double u = double(i) / nu, v = double(j) / nv, phi = u * phi_max;
            const double c = std::cos(phi), s = std::sin(phi);
            double P[3], N[3];
            if (type == "cylinder") {
                P[0] = p.radius * c, P[1] = p.radius * s, P[2] = z0 + v * (z1 - z0);
                N[0] = c, N[1] = s, N[2] = 0;
            } else if (type == "cone") {
                // Radius shrinks linearly to the apex at z = height (v = z / height).
                const double r = p.radius * (1 - v);
                P[0] = r * c, P[1] = r * s, P[2] = v * p.height;
                N[0] = p.height * c, N[1] = p.height * s, N[2] = p.radius;
            } else if (type == "paraboloid") {
                // x^2 + y^2 = radius^2 z / zmax, v along z from zmin to zmax.
                const double z = z0 + v * (z1 - z0);
                const double r = p.radius * std::sqrt(std::max(0.0, z / z1));
                P[0] = r * c, P[1] = r * s, P[2] = z;
                N[0] = r * c, N[1] = r * s, N[2] = -p.radius * p.radius / (2 * z1);
            } else {
                // The segment from p1 to p2 swept around z: the point at v turned by phi.
                const double q[3] = {(1 - v) * a[0] + v * b[0], (1 - v) * a[1] + v * b[1],
                                     (1 - v) * a[2] + v * b[2]};
                P[0] = q[0] * c - q[1] * s, P[1] = q[0] * s + q[1] * c, P[2] = q[2];
                // dP/du is along (-y, x, 0), dP/dv the turned segment direction.
                const double d[3] = {(b[0] - a[0]) * c - (b[1] - a[1]) * s,
                                     (b[0] - a[0]) * s + (b[1] - a[1]) * c, b[2] - a[2]};
                const double t[3] = {-P[1], P[0], 0};
                N[0] = t[1] * d[2] - t[2] * d[1];
                N[1] = t[2] * d[0] - t[0] * d[2];
                N[2] = t[0] * d[1] - t[1] * d[0];
            }
            for (int k = 0; k < 3; ++k) {
                m.positions.push_back(float(P[k]));
                m.normals.push_back(float(N[k]));
            }
            m.uvs.push_back(float(u));
            m.uvs.push_back(float(v));
        }
    // (u, v), (u+1, v), (u+1, v+1) and (u, v), (u+1, v+1), (u, v+1): facet normals along
    // dP/du x dP/dv, pbrt-v3's orientation of these shapes.
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const int v00 = j * (nu + 1) + i, v10 = v00 + 1, v01 = v00 + nu + 1, v11 = v01 + 1;
            m.indices.insert(m.indices.end(), {v00, v10, v11, v00, v11, v01});
        }
    return m;
}

}  // namespace cmam::render
