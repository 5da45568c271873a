#include "render/subdivide.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <unordered_map>
#include <vector>

#include "render/math.h"

namespace cmam::render {

namespace {

using P3 = Vec3d;

uint64_t edge_key(int a, int b) {
    const auto lo = static_cast<uint32_t>(std::min(a, b)),
               hi = static_cast<uint32_t>(std::max(a, b));
    return (uint64_t(lo) << 32) | hi;
}

// An edge of the current level: its faces' third vertices and, while splitting, its new vertex.
struct Edge {
    int a = 0, b = 0;
    int faces = 0;
    int opposite[2] = {-1, -1};
    int split = -1;
};

// The mesh's topology at one level: every edge, and each vertex's neighbours (with, on a
// boundary, the two neighbours along it).
struct Topology {
    std::unordered_map<uint64_t, Edge> edges;
    std::vector<std::vector<int>> neighbours;
    std::vector<std::array<int, 2>> boundary;  // -1 -1: interior; a vertex with other than two
                                               // boundary edges is a corner (kept in place)
    std::vector<int> boundary_edges;

    Topology(std::size_t nv, const std::vector<int>& tris)
        : neighbours(nv), boundary(nv, {-1, -1}), boundary_edges(nv, 0) {
        edges.reserve(tris.size());
        for (std::size_t f = 0; f < tris.size(); f += 3)
            for (int k = 0; k < 3; ++k) {
                const int a = tris[f + k], b = tris[f + (k + 1) % 3], c = tris[f + (k + 2) % 3];
                Edge& e = edges[edge_key(a, b)];
                if (e.faces == 0) {
                    e.a = a;
                    e.b = b;
                    neighbours[a].push_back(b);
                    neighbours[b].push_back(a);
                }
                if (e.faces < 2) e.opposite[e.faces] = c;
                ++e.faces;
            }
        for (const auto& [key, e] : edges) {
            if (e.faces == 2) continue;  // one face: a boundary; more: treated as a crease
            for (const auto& [v, w] : {std::pair{e.a, e.b}, std::pair{e.b, e.a}}) {
                const int n = boundary_edges[v]++;
                if (n < 2) boundary[v][n] = w;
            }
        }
    }

    bool on_boundary(int v) const { return boundary_edges[v] > 0; }
};

double loop_beta(std::size_t valence) {
    return valence == 3 ? 3.0 / 16.0 : 3.0 / (8.0 * double(valence));
}

// (1 - n w) p + w (sum of the neighbours): Loop's interior rule with weight w.
P3 weigh_ring(const std::vector<P3>& p, const std::vector<int>& ring, int v, double w) {
    P3 out = (1 - double(ring.size()) * w) * p[v];
    for (int q : ring) out = out + w * p[q];
    return out;
}

// (1 - 2 w) p + w (its two neighbours along the boundary); corners stay.
P3 weigh_boundary(const std::vector<P3>& p, const Topology& t, int v, double w) {
    if (t.boundary_edges[v] != 2) return p[v];
    return (1 - 2 * w) * p[v] + w * (p[t.boundary[v][0]] + p[t.boundary[v][1]]);
}

// One level: old vertices move by the even rules, each edge gets a vertex by the odd rules, and
// each triangle becomes four, wound as it was.
void subdivide_once(std::vector<P3>& p, std::vector<int>& tris) {
    Topology t(p.size(), tris);
    std::vector<P3> next(p.size());
    for (std::size_t v = 0; v < p.size(); ++v) {
        const int iv = static_cast<int>(v);
        const auto& ring = t.neighbours[v];
        next[v] = t.on_boundary(iv) ? weigh_boundary(p, t, iv, 1.0 / 8.0)
                  : ring.empty()    ? p[v]
                                    : weigh_ring(p, ring, iv, loop_beta(ring.size()));
    }
    // Each edge's new vertex, numbered in the order the triangles first reach the edge.
    auto split = [&](int a, int b) {
        Edge& e = t.edges.at(edge_key(a, b));
        if (e.split >= 0) return e.split;
        e.split = static_cast<int>(next.size());
        if (e.faces == 2)
            next.push_back((3.0 / 8.0) * (p[e.a] + p[e.b]) +
                           (1.0 / 8.0) * (p[e.opposite[0]] + p[e.opposite[1]]));
        else
            next.push_back(0.5 * (p[e.a] + p[e.b]));
        return e.split;
    };
    std::vector<int> out;
    out.reserve(tris.size() * 4);
    for (std::size_t f = 0; f < tris.size(); f += 3) {
        const int a = tris[f], b = tris[f + 1], c = tris[f + 2];
        const int ab = split(a, b), bc = split(b, c), ca = split(c, a);
        for (int v : {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca}) out.push_back(v);
    }
    p = std::move(next);
    tris = std::move(out);
}

// The vertex's neighbours in order around it, following the triangles' winding; on a boundary
// from one boundary neighbour to the other. Empty where the triangles around the vertex do not
// form one fan (a non-manifold vertex).
std::vector<int> ordered_ring(const std::vector<std::pair<int, int>>& fan, bool boundary) {
    // fan: (next, previous) of the vertex in each of its triangles; the triangle after one whose
    // previous vertex is q is the one whose next vertex is q.
    std::unordered_map<int, int> after;
    for (const auto& [n, prev] : fan) after[n] = prev;
    int start = fan.empty() ? -1 : fan.front().first;
    if (boundary) {
        start = -1;
        for (const auto& [n, prev] : fan) {
            bool is_previous = false;
            for (const auto& other : fan) is_previous |= other.second == n;
            if (!is_previous) start = n;
        }
        if (start < 0) return {};
    }
    std::vector<int> ring{start};
    for (int cur = start;;) {
        auto it = after.find(cur);
        if (it == after.end()) break;
        cur = it->second;
        if (cur == start) break;
        ring.push_back(cur);
        if (ring.size() > fan.size() + 1) return {};
    }
    return ring;
}

// Tangents of the limit surface at a vertex of ring `q` (in order): the interior's Fourier pair,
// or the boundary curve's direction and the cross-boundary tangent of Loop's boundary rules.
P3 limit_normal(const std::vector<P3>& p, int v, const std::vector<int>& ring, bool boundary) {
    const std::size_t n = ring.size();
    P3 s, t;
    if (!boundary) {
        for (std::size_t j = 0; j < n; ++j) {
            const double angle = 2 * std::numbers::pi * double(j) / double(n);
            s = s + std::cos(angle) * p[ring[j]];
            t = t + std::sin(angle) * p[ring[j]];
        }
        return cross(s, t);
    }
    s = p[ring[n - 1]] - p[ring[0]];
    if (n == 2) {
        t = p[ring[0]] + p[ring[1]] - 2.0 * p[v];
    } else if (n == 3) {
        t = p[ring[1]] - p[v];
    } else if (n == 4) {
        t = -1.0 * p[ring[0]] + 2.0 * p[ring[1]] + 2.0 * p[ring[2]] - 1.0 * p[ring[3]] - 2.0 * p[v];
    } else {
        const double theta = std::numbers::pi / double(n - 1);
        t = std::sin(theta) * (p[ring[0]] + p[ring[n - 1]]);
        for (std::size_t k = 1; k + 1 < n; ++k)
            t = t + ((2 * std::cos(theta) - 2) * std::sin(double(k) * theta)) * p[ring[k]];
        t = -1.0 * t;
    }
    return cross(s, t);
}

}  // namespace

double loop_subdivided_triangles(std::size_t triangles, int levels) {
    return double(triangles) * std::pow(4.0, std::max(0, levels));
}

int loop_levels_that_fit(std::size_t triangles, int levels) {
    while (levels > 0 && loop_subdivided_triangles(triangles, levels) > kMaxSubdividedTriangles)
        --levels;
    return levels;
}

SubdividedMesh loop_subdivide(const std::vector<float>& positions, const std::vector<int>& indices,
                              int levels) {
    std::vector<P3> p(positions.size() / 3);
    for (std::size_t v = 0; v < p.size(); ++v)
        p[v] = {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]};
    std::vector<int> tris = indices;
    for (int l = 0; l < levels; ++l) subdivide_once(p, tris);

    // The limit positions: Loop's rules with the limit weights (1/5 along a boundary).
    const Topology t(p.size(), tris);
    std::vector<P3> limit(p.size());
    for (std::size_t v = 0; v < p.size(); ++v) {
        const int iv = static_cast<int>(v);
        const auto& ring = t.neighbours[v];
        const double n = double(ring.size());
        limit[v] = t.on_boundary(iv) ? weigh_boundary(p, t, iv, 1.0 / 5.0)
                   : ring.empty()
                       ? p[v]
                       : weigh_ring(p, ring, iv, 1 / (n + 3 / (8 * loop_beta(ring.size()))));
    }

    // Normals from the limit tangents, on the side opposite the triangles' winding (the
    // area-weighted normal of the triangles around the vertex, negated, is also the fallback).
    // That is pbrt-v3's side: it crosses the tangents of a one-ring it walks against the
    // winding, so a mesh wound outwards gets normals pointing in, and as its triangles take a
    // given normal's side for the surface's, a loopsubdiv glass is entered from inside.
    std::vector<std::vector<std::pair<int, int>>> fans(p.size());
    std::vector<P3> winding(p.size());
    for (std::size_t f = 0; f < tris.size(); f += 3) {
        const int a = tris[f], b = tris[f + 1], c = tris[f + 2];
        const P3 fn = cross(limit[b] - limit[a], limit[c] - limit[a]);
        for (const auto& [v, n, prev] :
             {std::array{a, b, c}, std::array{b, c, a}, std::array{c, a, b}}) {
            fans[v].push_back({n, prev});
            winding[v] = winding[v] + fn;
        }
    }
    SubdividedMesh out;
    out.indices = std::move(tris);
    out.positions.reserve(3 * p.size());
    out.normals.reserve(3 * p.size());
    for (std::size_t v = 0; v < p.size(); ++v) {
        const bool boundary = t.on_boundary(static_cast<int>(v));
        const std::vector<int> ring = ordered_ring(fans[v], boundary);
        P3 n = ring.size() >= 2 && ring.size() == t.neighbours[v].size()
                   ? limit_normal(limit, static_cast<int>(v), ring, boundary)
                   : winding[v];
        if (!(dot(n, n) > 0) || !std::isfinite(dot(n, n))) n = winding[v];
        if (dot(n, winding[v]) > 0) n = -1.0 * n;
        for (double x : {limit[v].x, limit[v].y, limit[v].z})
            out.positions.push_back(static_cast<float>(x));
        for (double x : {n.x, n.y, n.z}) out.normals.push_back(static_cast<float>(x));
    }
    return out;
}

}  // namespace cmam::render
