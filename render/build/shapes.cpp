// render — scene building: shapes (analytic spheres and disks, tessellated quadrics, triangle
// and PLY meshes), object instances, and the area lights their shapes emit.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <utility>

#include "pbrt/parser.h"
#include "render/build/builder.h"
#include "render/memory.h"
#include "render/patches.h"

namespace cmam::render::build_detail {

namespace fs = std::filesystem;

namespace {
// The scale of a 3x4 transform whose linear part is a rotation or reflection times a uniform
// scale (columns orthogonal and of one length, to a relative 1e-6), else 0.
double uniform_scale(const std::array<double, 12>& m) {
    double len2[3], dots[3];
    for (int c = 0; c < 3; ++c) {
        const int d = (c + 1) % 3;
        len2[c] = m[c] * m[c] + m[4 + c] * m[4 + c] + m[8 + c] * m[8 + c];
        dots[c] = m[c] * m[d] + m[4 + c] * m[4 + d] + m[8 + c] * m[8 + d];
    }
    for (int c = 0; c < 3; ++c)
        if (!(std::abs(len2[c] - len2[0]) <= 1e-6 * len2[0] && std::abs(dots[c]) <= 1e-6 * len2[0]))
            return 0;
    return std::sqrt(len2[0]);
}
}  // namespace

// pbrt-v3's sphere and disk, intersected analytically in object space.
bool Builder::analytic_quadric(const pbrt::ShapeDesc& s, Primitive& prim) {
    const Entity& e = s.entity;
    const Mat4 wo = world_from(s);
    const Mat4 ow = inverse_or_error(wo, e.loc, "the shape's transform is singular");
    prim.world_from_object = to34(wo);
    prim.object_from_world = to34(ow);
    prim.uniform_scale = uniform_scale(prim.world_from_object);
    double r = finite_float(e, "radius", 1, true);
    prim.radius = r;
    double phimax = std::clamp(finite_float(e, "phimax", 360), 0.0, 360.0);
    prim.phi_max = phimax * std::numbers::pi / 180;
    prim.u_periodic = phimax == 360;
    if (e.type == "sphere") {
        prim.kind = Primitive::Kind::Sphere;
        double z0 = std::clamp(finite_float(e, "zmin", -r), -r, r);
        double z1 = std::clamp(finite_float(e, "zmax", r), -r, r);
        prim.zmin = std::min(z0, z1);
        prim.zmax = std::max(z0, z1);
        prim.theta_zmin = std::acos(std::clamp(prim.zmin / r, -1.0, 1.0));
        prim.theta_zmax = std::acos(std::clamp(prim.zmax / r, -1.0, 1.0));
        if (prim.theta_zmin == prim.theta_zmax) throw SceneError(e.loc, "sphere has zmin == zmax");
    } else {
        prim.kind = Primitive::Kind::Disk;
        prim.height = finite_float(e, "height", 0);
        prim.inner_radius = finite_float(e, "innerradius", 0);
        if (prim.inner_radius < 0 || prim.inner_radius >= r)
            throw SceneError(e.params.find("innerradius")->loc,
                             "innerradius must be in [0, radius)");
    }
    e.params.check_unused("shape " + in_quotes(e.type), m_warn, {"alpha", "shadowalpha"});
    return true;
}

// A triangle mesh's primitive, with pbrt-v3's cut-out masks (float textures or constants), read
// before the parameters are checked.
void Builder::mesh_primitive(const pbrt::ShapeDesc& s, Primitive& prim) {
    const Entity& e = s.entity;
    prim.kind = Primitive::Kind::Triangles;
    if (e.params.find("alpha")) prim.alpha = float_input(e, s.scope, "alpha", 1);
    if (e.params.find("shadowalpha")) prim.shadow_alpha = float_input(e, s.scope, "shadowalpha", 1);
}

// pbrt-v3's cylinder, cone, paraboloid and hyperboloid, as triangle meshes (tessellate.h).
bool Builder::tessellated_quadric(const pbrt::ShapeDesc& s, Primitive& prim) {
    const Entity& e = s.entity;
    mesh_primitive(s, prim);
    const QuadricParams params = quadric_params(e);
    prim.u_periodic = params.phimax >= 360;
    // pbrt-v3 decides sides with the hyperboloid's own normal, wherever it points (§15).
    prim.normals_geometric = e.type == "hyperboloid";
    const ShapeMesh mesh = tessellate(e.type, params);
    e.params.check_unused("shape " + in_quotes(e.type), m_warn, {"alpha", "shadowalpha"});
    return place_mesh(s, mesh.positions, mesh.normals, mesh.uvs, mesh.indices, prim,
                      NormalSide::Quadric);
}

// A mesh of `c.vertices` vertices and `c.faces` faces takes, once read and placed: its arrays
// twice (as read, and placed in the scene: 12 bytes a position, 12 a normal, 8 a texture
// coordinate, 12 a triangle's indices) and the acceleration structure Embree builds over it,
// about 110 bytes a triangle (measured: 2 million triangles with texture coordinates take
// 313 MB). A face is counted as one triangle (quads are two), so this is a lower bound.
double Builder::mesh_memory_need(const pbrt::PlyCounts& c) {
    const double per_vertex = 12 + (c.normals ? 12 : 0) + (c.uvs ? 8 : 0);
    return 2 * per_vertex * double(c.vertices) + (2 * 12 + 110) * double(c.faces);
}

void Builder::check_mesh_memory(const pbrt::FileLoc& loc, const std::string& name,
                                const pbrt::PlyCounts& c, bool reserve) {
    const double need = mesh_memory_need(c);
    const std::size_t limit = m_opts.max_memory.value_or(memory_limit()), have = resident_memory();
    std::unique_lock<std::mutex> lock(m_mesh_memory_mutex);
    const double left =
        std::max(0.0, (have < limit ? double(limit - have) : 0) - m_mesh_memory_reserved);
    if (need <= left) {
        if (reserve) m_mesh_memory_reserved += need;
        return;
    }
    lock.unlock();
    throw SceneError(
        loc, name + ": " + std::to_string(c.vertices) + " vertices and " + std::to_string(c.faces) +
                 " faces need about " +
                 format_bytes(static_cast<std::size_t>(std::min(need, 1e18))) + ", over the " +
                 format_bytes(static_cast<std::size_t>(left)) + " left of the limit of " +
                 format_bytes(limit) +
                 (m_opts.max_memory ? " set by --max-memory" : " (what this process may use)"));
}

// pbrt-v3's "discarddegenerateUVs" (trianglemesh and plymesh): with normals given, a mesh one of
// whose triangles (of area 1e-7 or more) has two vertices at the same (u,v) loses all its (u,v),
// with a warning; the surface then takes the default parameterisation.
bool Builder::degenerate_uvs(const Entity& e, const std::vector<float>& P,
                             const std::vector<float>& N, const std::vector<float>& UV,
                             const std::vector<int>& idx) {
    if (!e.params.get_bool("discarddegenerateUVs", false) || UV.empty() || N.empty()) return false;
    auto p = [&](int v) { return Vec3(P[3 * v], P[3 * v + 1], P[3 * v + 2]); };
    auto same = [&](int a, int b) {
        return UV[2 * a] == UV[2 * b] && UV[2 * a + 1] == UV[2 * b + 1];
    };
    for (std::size_t i = 0; i + 2 < idx.size(); i += 3) {
        const int a = idx[i], b = idx[i + 1], c = idx[i + 2];
        if (0.5f * length(cross(p(a) - p(b), p(c) - p(b))) < 1e-7f) continue;
        if (same(a, b) || same(b, c) || same(c, a)) {
            warn(loc_of(e, "discarddegenerateUVs"),
                 "a triangle has two vertices at the same (u,v): all of the mesh's (u,v) are "
                 "discarded, as pbrt-v3's discarddegenerateUVs does");
            return true;
        }
    }
    return false;
}

bool Builder::ply_mesh(const pbrt::ShapeDesc& s, Primitive& prim) {
    const Entity& e = s.entity;
    mesh_primitive(s, prim);
    const auto* fp = e.params.find("filename");
    if (!fp) throw SceneError(e.loc, "plymesh needs a \"string filename\" parameter");
    std::string path =
        pbrt::resolve_path(m_desc.base_dir, fp->loc, e.params.get_string("filename", ""));
    // Each file is read once, however many shapes name it; refused before its data is read
    // when what its header announces would not fit.
    auto& mesh = m_ply[path];
    if (!mesh) {
        const std::string name = in_quotes(fs::path(path).filename().string());
        auto check = [&](const pbrt::PlyCounts& c) { check_mesh_memory(fp->loc, name, c); };
        try {
            if (auto read = take_read_ahead(m_read_plys, path)) {
                mesh = std::move(read->mesh);
            } else {
                mesh = std::make_unique<pbrt::PlyMesh>(pbrt::read_ply(path, check));
            }
        } catch (const SceneError& err) {
            throw SceneError(fp->loc, err.message());
        }
        if (const std::size_t k = mesh->skipped_faces)
            warn(fp->loc, name + ": " + std::to_string(k) + (k == 1 ? " face" : " faces") +
                              " with neither three nor four vertices skipped (the first has " +
                              std::to_string(mesh->first_skipped_size) +
                              "), as pbrt-v3 skips them");
    }
    // The shared mesh's (u,v), or none: a reference either way, the arrays are not copied.
    static const std::vector<float> kNoUv;
    const std::vector<float>& uvs =
        degenerate_uvs(e, mesh->positions, mesh->normals, mesh->uvs, mesh->indices) ? kNoUv
                                                                                    : mesh->uvs;
    e.params.check_unused("shape \"plymesh\"", m_warn,
                          {"alpha", "shadowalpha", "displacement", "edgelength"});
    return place_mesh(s, mesh->positions, mesh->normals, uvs, mesh->indices, prim);
}

// pbrt-v3's "curve" (algorithms.md §20): control points "P" of a degree 2 or 3 curve with a
// Bezier or uniform B-spline basis, each segment made a cubic Bezier curve as pbrt-v3 makes it;
// "width" (or "width0" and "width1", from the curve's start to its end) across it; "type" flat
// (facing each ray), cylinder (flat, shaded as a cylinder) or ribbon (oriented by the normals
// "N" at the segments' ends). The errors pbrt-v3 reports and skips the curve for are errors here.
bool Builder::curve(const pbrt::ShapeDesc& s, Primitive& prim) {
    const Entity& e = s.entity;
    prim.kind = Primitive::Kind::Curves;
    const double width = finite_float(e, "width", 1);
    const double width0 = finite_float(e, "width0", width),
                 width1 = finite_float(e, "width1", width);
    if (width0 < 0 || width1 < 0) throw SceneError(e.loc, "curve widths must not be negative");
    const int degree = e.params.get_int("degree", 3);
    if (degree != 2 && degree != 3)
        throw SceneError(loc_of(e, "degree"),
                         "curve degree must be 2 or 3, got " + std::to_string(degree));
    const std::string basis = e.params.get_string("basis", "bezier");
    if (basis != "bezier" && basis != "bspline")
        throw SceneError(loc_of(e, "basis"),
                         "curve basis must be \"bezier\" or \"bspline\", got " + in_quotes(basis));
    const auto p = e.params.get_point3s("P");
    if (!p) throw SceneError(e.loc, "\"curve\" needs a \"point3 P\" parameter");
    const auto& pv = finite_values(e, "P", *p);
    const int ncp = static_cast<int>(pv.size() / 3);
    int segments;
    if (basis == "bezier") {
        if (ncp < degree + 1 || (ncp - 1 - degree) % degree != 0)
            throw SceneError(loc_of(e, "P"), std::to_string(ncp) + " control points: a degree " +
                                                 std::to_string(degree) + " Bezier curve takes " +
                                                 std::to_string(degree + 1) + " + n * " +
                                                 std::to_string(degree) + " of them");
        segments = (ncp - 1) / degree;
    } else {
        if (ncp < degree + 1)
            throw SceneError(loc_of(e, "P"), std::to_string(ncp) + " control points: a degree " +
                                                 std::to_string(degree) +
                                                 " B-spline curve takes at least " +
                                                 std::to_string(degree + 1));
        segments = ncp - degree;
    }
    const std::string type = e.params.get_string("type", "flat");
    if (type == "flat") {
        prim.curve_type = Primitive::CurveType::Flat;
    } else if (type == "ribbon") {
        prim.curve_type = Primitive::CurveType::Ribbon;
    } else if (type == "cylinder") {
        prim.curve_type = Primitive::CurveType::Cylinder;
    } else {
        warn(loc_of(e, "type"), "unknown curve type " + in_quotes(type) +
                                    " (pbrt-v3 has \"flat\", \"ribbon\" and \"cylinder\"): "
                                    "\"cylinder\" is used, as pbrt-v3 uses it");
        prim.curve_type = Primitive::CurveType::Cylinder;
    }
    const bool ribbon = prim.curve_type == Primitive::CurveType::Ribbon;
    std::vector<Vec3> normals;
    if (const auto n = e.params.get_point3s("N")) {
        if (!ribbon) {
            warn(loc_of(e, "N"),
                 "curve normals are used by \"ribbon\" curves only, as in "
                 "pbrt-v3; they are ignored");
        } else {
            const auto& nv = finite_values(e, "N", *n);
            if (nv.size() / 3 != static_cast<std::size_t>(segments) + 1)
                throw SceneError(loc_of(e, "N"),
                                 std::to_string(nv.size() / 3) + " normals: a ribbon curve of " +
                                     std::to_string(segments) + " segments takes " +
                                     std::to_string(segments + 1) + ", one at each segment's ends");
            const Mat4 inv_t =
                inverse_or_error(world_from(s), e.loc, "the shape's transform is singular")
                    .transposed();
            for (std::size_t i = 0; i + 2 < nv.size(); i += 3) {
                const auto w = inv_t.apply_vector({nv[i], nv[i + 1], nv[i + 2]});
                const Vec3 v = to_vec(w);
                if (!(length(v) > 0))
                    throw SceneError(loc_of(e, "N"), "a ribbon curve's normal has no length");
                normals.push_back(normalize(v));
            }
        }
    } else if (ribbon) {
        throw SceneError(e.loc, "a \"ribbon\" curve needs normals \"N\" at its segments' ends");
    }
    // Widths are in the object's space: scaled by the transform's mean scale (exact for a
    // uniform one).
    const Mat4 m = world_from(s);
    const double scale = std::cbrt(std::abs(m.linear_determinant()));
    auto cp = [&](int i) {
        return Vec3(float(pv[3 * i]), float(pv[3 * i + 1]), float(pv[3 * i + 2]));
    };
    auto lerp = [](float t, const Vec3& a, const Vec3& b) { return (1 - t) * a + t * b; };
    for (int seg = 0; seg < segments; ++seg) {
        Vec3 b[4];  // the segment's cubic Bezier control points, as pbrt-v3 computes them
        if (basis == "bezier") {
            const int i = seg * degree;
            if (degree == 2) {
                b[0] = cp(i);
                b[1] = lerp(2.f / 3.f, cp(i), cp(i + 1));
                b[2] = lerp(1.f / 3.f, cp(i + 1), cp(i + 2));
                b[3] = cp(i + 2);
            } else {
                for (int k = 0; k < 4; ++k) b[k] = cp(i + k);
            }
        } else if (degree == 2) {  // a uniform B-spline's segment, by blossoming
            const Vec3 p11 = lerp(0.5f, cp(seg), cp(seg + 1)), p12 = cp(seg + 1),
                       p22 = lerp(0.5f, cp(seg + 1), cp(seg + 2));
            b[0] = p11;
            b[1] = lerp(2.f / 3.f, p11, p12);
            b[2] = lerp(1.f / 3.f, p12, p22);
            b[3] = p22;
        } else {
            const Vec3 p122 = lerp(2.f / 3.f, cp(seg), cp(seg + 1)),
                       p223 = lerp(1.f / 3.f, cp(seg + 1), cp(seg + 2)),
                       p233 = lerp(2.f / 3.f, cp(seg + 1), cp(seg + 2)),
                       p334 = lerp(1.f / 3.f, cp(seg + 2), cp(seg + 3));
            b[0] = lerp(0.5f, p122, p223);
            b[1] = p223;
            b[2] = p233;
            b[3] = lerp(0.5f, p233, p334);
        }
        const float w0 = float(scale * (width0 + (width1 - width0) * seg / segments)),
                    w1 = float(scale * (width0 + (width1 - width0) * (seg + 1) / segments));
        prim.curve_first.push_back(static_cast<uint32_t>(prim.curve_points.size()));
        prim.curve_widths.push_back({w0, w1});
        Vec3 wp[4];
        for (int k = 0; k < 4; ++k) {
            wp[k] = to_vec(m.apply_point({b[k].x, b[k].y, b[k].z}));
            // A linear width along the segment: its Bezier control values are evenly spaced.
            prim.curve_points.push_back(
                {wp[k].x, wp[k].y, wp[k].z, 0.5f * (w0 + (w1 - w0) * k / 3.0f)});
        }
        // pbrt-v3's refinement makes 2^r pieces, r = log4(sqrt(2) 6 L0 / (8 eps)), L0 the
        // largest second difference of the control points, eps a twentieth of the width; four
        // times as many quads here: Embree's are chords of the curve, where pbrt-v3 measures
        // the distance to the curve itself at the chord's parameter.
        float l0 = 0;
        for (int i = 0; i < 2; ++i) {
            const Vec3 d = wp[i] - 2 * wp[i + 1] + wp[i + 2];
            l0 = std::max({l0, std::abs(d.x), std::abs(d.y), std::abs(d.z)});
        }
        const float eps = 0.05f * std::max(w0, w1);
        if (eps > 0)
            prim.curve_tessellation = std::clamp(4 * std::sqrt(1.41421356f * 6 * l0 / (8 * eps)),
                                                 prim.curve_tessellation, 64.0f);
        if (ribbon) {
            prim.curve_end_normals.push_back({normals[seg], normals[seg + 1]});
        }
    }
    // pbrt-v3's "splitdepth" splits a segment before it refines each piece to a twentieth of
    // the width; the pieces above are refined to that bound from the start: read, unneeded.
    if (const pbrt::Param* sd = e.params.find("splitdepth")) sd->used = true;
    e.params.check_unused("shape \"curve\"", m_warn);
    return !prim.curve_first.empty();
}

// pbrt-v3's "trianglemesh", and "loopsubdiv": its control mesh subdivided at load
// (algorithms.md §16).
bool Builder::triangle_mesh(const pbrt::ShapeDesc& s, Primitive& prim) {
    const Entity& e = s.entity;
    mesh_primitive(s, prim);
    std::vector<float> P, N, UV;
    std::vector<int> idx;
    const std::string what = in_quotes(e.type);
    auto p = e.params.get_point3s("P");
    if (!p) throw SceneError(e.loc, what + " needs a \"point3 P\" parameter");
    for (double x : finite_values(e, "P", *p)) P.push_back(float(x));
    std::size_t nv = P.size() / 3;
    if (auto i = e.params.get_ints("indices")) {
        idx = *i;
    } else if (nv == 3) {
        idx = {0, 1, 2};
    } else {
        throw SceneError(e.loc, what + " needs an \"integer indices\" parameter");
    }
    if (idx.size() % 3 != 0)
        throw SceneError(e.params.find("indices")->loc,
                         "indices count " + std::to_string(idx.size()) + " is not a multiple of 3");
    for (int i : idx)
        if (i < 0 || static_cast<std::size_t>(i) >= nv)
            throw SceneError(e.params.find("indices")->loc, "index " + std::to_string(i) +
                                                                " out of range (" +
                                                                std::to_string(nv) + " vertices)");
    if (e.type == "loopsubdiv") return subdivided_mesh(s, P, idx, prim);
    if (auto n = e.params.get_point3s("N")) {
        if (n->size() != P.size())
            throw SceneError(e.params.find("N")->loc, "N must have one normal per vertex of P");
        for (double x : finite_values(e, "N", *n)) N.push_back(float(x));
    }
    const char* uvname = e.params.find("uv") ? "uv" : "st";
    if (auto uv = e.params.get_point2s(uvname)) {
        if (uv->size() != 2 * nv)
            throw SceneError(e.params.find(uvname)->loc,
                             std::string(uvname) + " must have one (u,v) pair per vertex of P");
        for (double x : finite_values(e, uvname, *uv)) UV.push_back(float(x));
    }
    if (degenerate_uvs(e, P, N, UV, idx)) UV.clear();
    e.params.check_unused("shape " + what, m_warn, {"alpha", "shadowalpha", "S", "faceIndices"});
    return place_mesh(s, P, N, UV, idx, prim);
}

// pbrt-v3's "heightfield" (algorithms.md §22): "nu" x "nv" heights "Pz" over the unit square,
// a triangle mesh with (u,v) and no normals. pbrt-v3 stops on the errors here; it takes no
// cut-out masks for it ("alpha" is unused).
bool Builder::heightfield(const pbrt::ShapeDesc& s, Primitive& prim) {
    const Entity& e = s.entity;
    prim.kind = Primitive::Kind::Triangles;
    for (const char* name : {"nu", "nv"}) {
        if (!e.params.find(name))
            throw SceneError(
                e.loc, std::string("\"heightfield\" needs an \"integer ") + name + "\" parameter");
        if (e.params.get_int(name, 0) < 2)
            throw SceneError(loc_of(e, name), std::string(name) + " must be at least 2, got " +
                                                  std::to_string(e.params.get_int(name, 0)));
    }
    const int nu = e.params.get_int("nu", 2), nv = e.params.get_int("nv", 2);
    const auto z = e.params.get_floats("Pz");
    if (!z) throw SceneError(e.loc, "\"heightfield\" needs a \"float Pz\" parameter");
    const std::size_t n = static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv);
    if (z->size() != n)
        throw SceneError(loc_of(e, "Pz"), "Pz has " + std::to_string(z->size()) +
                                              " heights; nu x nv = " + std::to_string(n));
    const ShapeMesh mesh = heightfield_mesh(nu, nv, finite_values(e, "Pz", *z));
    e.params.check_unused("shape \"heightfield\"", m_warn);
    return place_mesh(s, mesh.positions, mesh.normals, mesh.uvs, mesh.indices, prim);
}

// pbrt-v3's "nurbs" (algorithms.md §22): a NURBS surface of "nu" x "nv" control points ("P", or
// homogeneous "Pw"), orders "uorder" and "vorder" and knot vectors "uknots" and "vknots", diced
// over "u0".."u1" x "v0".."v1" (by default the knots' whole range) into a 30 x 30 grid with
// the surface's normals and its parameters as (u,v), as pbrt-v3 makes it. What pbrt-v3 stops on
// or reports and skips the shape for is an error here.
bool Builder::nurbs(const pbrt::ShapeDesc& s, Primitive& prim) {
    const Entity& e = s.entity;
    prim.kind = Primitive::Kind::Triangles;
    NurbsPatch p;
    for (const char* name : {"nu", "nv", "uorder", "vorder"})
        if (!e.params.find(name))
            throw SceneError(e.loc,
                             std::string("\"nurbs\" needs an \"integer ") + name + "\" parameter");
    p.nu = e.params.get_int("nu", 0);
    p.nv = e.params.get_int("nv", 0);
    p.uorder = e.params.get_int("uorder", 0);
    p.vorder = e.params.get_int("vorder", 0);
    for (const char* name : {"uknots", "vknots"}) {
        const auto k = e.params.get_floats(name);
        if (!k)
            throw SceneError(e.loc,
                             std::string("\"nurbs\" needs a \"float ") + name + "\" parameter");
        (name[0] == 'u' ? p.uknots : p.vknots) = finite_values(e, name, *k);
    }
    // The parameter ranges' defaults: knots order - 1 and n, the knots' whole range.
    auto knot = [](const std::vector<double>& k, int i) {
        return i >= 0 && static_cast<std::size_t>(i) < k.size() ? k[static_cast<std::size_t>(i)]
                                                                : 0.0;
    };
    p.u0 = finite_float(e, "u0", knot(p.uknots, p.uorder - 1));
    p.u1 = finite_float(e, "u1", knot(p.uknots, p.nu));
    p.v0 = finite_float(e, "v0", knot(p.vknots, p.vorder - 1));
    p.v1 = finite_float(e, "v1", knot(p.vknots, p.nv));
    const char* points = e.params.find("P") ? "P" : "Pw";
    if (const auto P = e.params.get_point3s("P")) {
        for (std::size_t i = 0; i + 2 < P->size(); i += 3)
            p.cp.push_back({(*P)[i], (*P)[i + 1], (*P)[i + 2], 1});
    } else if (const auto Pw = e.params.get_floats("Pw")) {
        if (Pw->size() % 4 != 0)
            throw SceneError(loc_of(e, "Pw"),
                             "Pw needs four numbers (x w, y w, z w, w) per "
                             "control point, got " +
                                 std::to_string(Pw->size()));
        for (std::size_t i = 0; i + 3 < Pw->size(); i += 4)
            p.cp.push_back({(*Pw)[i], (*Pw)[i + 1], (*Pw)[i + 2], (*Pw)[i + 3]});
    } else {
        throw SceneError(e.loc, "\"nurbs\" needs control points, \"point3 P\" or \"float Pw\"");
    }
    if (const auto err = nurbs_patch_error(p)) {
        const std::string name = err->parameter == "P" ? points : err->parameter;
        throw SceneError(e.params.find(name) ? e.params.find(name)->loc : e.loc,
                         "\"nurbs\": " + err->message);
    }
    const ShapeMesh mesh = nurbs_mesh(p);
    for (float x : mesh.positions)
        if (!std::isfinite(x))
            throw SceneError(e.params.find(points)->loc,
                             "\"nurbs\": the surface is not finite where it is diced (a weight "
                             "of 0 where the knots make it count alone)");
    e.params.check_unused("shape \"nurbs\"", m_warn);
    return place_mesh(s, mesh.positions, mesh.normals, mesh.uvs, mesh.indices, prim);
}

// pbrt-v3's "loopsubdiv" after its control mesh is read: "levels" (or "nlevels") of Loop
// subdivision, then the limit surface with its normals and no (u,v), as pbrt-v3 makes it.
bool Builder::subdivided_mesh(const pbrt::ShapeDesc& s, const std::vector<float>& P,
                              const std::vector<int>& idx, Primitive& prim) {
    const Entity& e = s.entity;
    const char* name = e.params.find("levels") || !e.params.find("nlevels") ? "levels" : "nlevels";
    int levels = e.params.get_int(name, 3);
    if (levels < 0)
        throw SceneError(loc_of(e, name),
                         "levels must be 0 or more, got " + std::to_string(levels));
    const std::size_t triangles = idx.size() / 3;
    const int fit = loop_levels_that_fit(triangles, levels);
    if (fit < levels)
        warn(loc_of(e, name),
             "shape \"loopsubdiv\": " + std::to_string(levels) + " levels would make " +
                 pbrt::number_text(loop_subdivided_triangles(triangles, levels), 3) +
                 " triangles; " + std::to_string(fit) + " are used");
    const std::string scheme = e.params.get_string("scheme", "loop");
    if (scheme != "loop")
        warn(loc_of(e, "scheme"), "shape \"loopsubdiv\": scheme " + in_quotes(scheme) +
                                      " is not pbrt-v3's; Loop subdivision is used");
    e.params.check_unused("shape \"loopsubdiv\"", m_warn, {"nlevels"});
    const SubdividedMesh mesh = loop_subdivide(P, idx, fit);
    return place_mesh(s, mesh.positions, mesh.normals, {}, mesh.indices, prim);
}

// Places an object-space mesh (3 floats per position and normal, 2 per (u,v), 3 indices per
// triangle) in the world as `prim`'s triangles; false when no triangle has an area.
//
// Normals map as normals (the inverse transpose) and are then flipped with the primitive
// (`flip`, ReverseOrientation xor a transform that swaps handedness), which is how pbrt-v3
// orients a quadric's normal and so the tessellated quadrics' (NormalSide::Quadric). Normals a
// mesh was given (trianglemesh "N", a PLY's, loopsubdiv's limit normals) pbrt-v3 flips for
// ReverseOrientation alone (its triangle negates the shading bitangent then, nothing for the
// handedness): under a mirroring transform they are stored negated, so that `flip` restores them.
bool Builder::place_mesh(const pbrt::ShapeDesc& s, const std::vector<float>& P,
                         const std::vector<float>& N, const std::vector<float>& UV,
                         const std::vector<int>& idx, Primitive& prim, NormalSide side) {
    std::size_t nv = P.size() / 3;
    prim.positions.resize(nv);
    const Mat4 wo = world_from(s);
    for (std::size_t i = 0; i < nv; ++i) {
        auto w = wo.apply_point({P[3 * i], P[3 * i + 1], P[3 * i + 2]});
        prim.positions[i] = Vec3(float(w[0]), float(w[1]), float(w[2]));
    }
    if (!N.empty()) {
        const Mat4 inv_t =
            inverse_or_error(wo, s.entity.loc, "the shape's transform is singular").transposed();
        const float sign = side == NormalSide::Given && wo.swaps_handedness() ? -1.0f : 1.0f;
        prim.normals.resize(nv);
        for (std::size_t i = 0; i < nv; ++i) {
            auto w = inv_t.apply_vector({N[3 * i], N[3 * i + 1], N[3 * i + 2]});
            prim.normals[i] = sign * Vec3(float(w[0]), float(w[1]), float(w[2]));
        }
    }
    if (!UV.empty()) {
        prim.uvs.resize(nv);
        for (std::size_t i = 0; i < nv; ++i) prim.uvs[i] = {UV[2 * i], UV[2 * i + 1]};
    }
    // Drop degenerate triangles (pbrt-v3 cannot hit them either).
    for (std::size_t t = 0; t + 2 < idx.size(); t += 3) {
        Vec3 a = prim.positions[idx[t]], b = prim.positions[idx[t + 1]],
             c = prim.positions[idx[t + 2]];
        if (length(cross(b - a, c - a)) == 0) continue;
        prim.indices.insert(prim.indices.end(),
                            {uint32_t(idx[t]), uint32_t(idx[t + 1]), uint32_t(idx[t + 2])});
    }
    return !prim.indices.empty();
}

// pbrt-v3 makes every shape in an AreaLightSource's scope emit; one light per shape
// here, sampled uniformly by area over all its triangles.
void Builder::emit_area_light(const pbrt::ShapeDesc& s, Primitive& prim) {
    if (prim.kind == Primitive::Kind::Curves) {
        warn(s.entity.loc,
             "a curve in an AreaLightSource's scope does not emit (pbrt-v3 cannot sample a "
             "curve's area, and stops); it is rendered as a surface that does not emit");
        return;
    }
    Light l = m_area_lights[static_cast<std::size_t>(s.area_light)];
    l.prim = static_cast<int>(prim.id);
    if (prim.kind == Primitive::Kind::Triangles) {
        prim.area_cdf.assign(1, 0.0);
        for (std::size_t t = 0; t < prim.indices.size(); t += 3) {
            const Vec3 a = prim.positions[prim.indices[t]], b = prim.positions[prim.indices[t + 1]],
                       c = prim.positions[prim.indices[t + 2]];
            prim.area_cdf.push_back(prim.area_cdf.back() +
                                    0.5 * double(length(cross(b - a, c - a))));
        }
    }
    if (prim.kind == Primitive::Kind::Sphere) round_sphere(prim);
    if (!l.intensity.is_black()) {
        prim.area_light = static_cast<int>(m_scene->lights.size());
        m_scene->lights.push_back(l);
    }
}

// Appends the shape's primitive (if it has any surface) to `out`.
void Builder::shape(const pbrt::ShapeDesc& s, std::vector<std::unique_ptr<Primitive>>& out) {
    static constexpr TypeBuilder<ShapeBuild> kShapes[] = {
        {"sphere", &Builder::analytic_quadric},
        {"disk", &Builder::analytic_quadric},
        {"cylinder", &Builder::tessellated_quadric},
        {"cone", &Builder::tessellated_quadric},
        {"paraboloid", &Builder::tessellated_quadric},
        {"hyperboloid", &Builder::tessellated_quadric},
        {"trianglemesh", &Builder::triangle_mesh},
        {"plymesh", &Builder::ply_mesh},
        {"loopsubdiv", &Builder::triangle_mesh},
        {"curve", &Builder::curve},
        {"heightfield", &Builder::heightfield},
        {"nurbs", &Builder::nurbs}};
    const Entity& e = s.entity;
    auto prim = std::make_unique<Primitive>();
    prim->material = s.material;
    prim->medium_inside = medium(s.medium_inside);
    prim->medium_outside = medium(s.medium_outside);
    finite_transform(s.world_from_object, e.loc, "shape");
    prim->flip = s.reverse_orientation ^ world_from(s).swaps_handedness();
    if (!(this->*builder_for(kShapes, e, "shape"))(s, *prim)) return;
    prim->id = static_cast<uint32_t>(out.size());
    // (Shapes of objects do not emit, placed in instances or in place, as in pbrt-v3.)
    if (s.area_light >= 0 && &out == &m_scene->primitives && !m_placement)
        emit_area_light(s, *prim);
    out.push_back(std::move(prim));
}

QuadricParams Builder::quadric_params(const Entity& e) {
    QuadricParams p;
    if (e.type == "hyperboloid") {
        auto a = finite_point(e, "p1", {0, 0, 0});
        auto b = finite_point(e, "p2", {1, 1, 1});
        std::copy(a.begin(), a.end(), p.p1);
        std::copy(b.begin(), b.end(), p.p2);
        if (a[2] == b[2]) throw SceneError(e.loc, "hyperboloid p1 and p2 must differ in z");
    } else {
        p.radius = finite_float(e, "radius", 1, true);
    }
    if (e.type == "cone") p.height = finite_float(e, "height", 1, true);
    if (e.type == "cylinder" || e.type == "paraboloid") {
        p.zmin = finite_float(e, "zmin", e.type == "cylinder" ? -1 : 0);
        p.zmax = finite_float(e, "zmax", 1);
        if (p.zmin == p.zmax) throw SceneError(e.loc, e.type + " has zmin == zmax");
        if (e.type == "paraboloid" &&
            (std::min(p.zmin, p.zmax) < 0 || std::max(p.zmin, p.zmax) <= 0))
            throw SceneError(e.loc, "paraboloid zmin and zmax must be at least 0");
    }
    p.phimax = finite_float(e, "phimax", 360);
    return p;
}

// A whole sphere whose transform is a rotation, reflection or uniform scale plus a
// translation stays a sphere: its centre and radius let area lights sample its cone.
void Builder::round_sphere(Primitive& prim) {
    if (prim.zmin > -prim.radius || prim.zmax < prim.radius || prim.phi_max < 2 * std::numbers::pi)
        return;
    if (!(prim.uniform_scale > 0)) return;
    const auto& m = prim.world_from_object;
    prim.sphere_center = Vec3(float(m[3]), float(m[7]), float(m[11]));
    prim.sphere_radius = float(prim.radius * prim.uniform_scale);
}

// pbrt-v3's "diffuse" area light: radiance L (times scale) leaving the surface.
Light Builder::area_light(const Entity& e) {
    Light l;
    l.type = Light::Type::Area;
    if (e.type != "diffuse" && e.type != "area") {  // pbrt-v3 warns and goes on
        warn(e.loc, "unknown AreaLightSource " + in_quotes(e.type) +
                        " (pbrt-v3 has \"diffuse\", also named \"area\"): the shapes in "
                        "its scope do not emit");
        return l;  // black: no light is made
    }
    l.intensity = light_intensity(e, "L", light_scale(e));
    l.two_sided = e.params.get_bool("twosided", false);
    l.samples = light_samples(e);
    e.params.check_unused("AreaLightSource \"diffuse\"", m_warn, {"nsamples", "samples"});
    return l;
}

// Each object an instance uses is built once, in its own space; each instance places it
// (algorithms.md §7.1). Textured-object ids (the CMAM's caches) are per instance.
//
// Where a copy is cheap, an instance is built in place instead: its object's shapes go into the
// scene's own primitives, each placed by the instance's transform composed with its own, as if
// the file had written them there (BuildOptions::flatten_instances: an object used once, or
// whose uses come to few triangles). A ray then crosses one level of Embree's hierarchy, not two,
// and its hits need no instance's transform (docs/performance.md, "Instancing").
void Builder::instances() {
    const auto& objects = m_desc.objects;
    std::vector<std::size_t> uses(objects.size(), 0);
    for (const pbrt::InstanceDesc& d : m_desc.instances) ++uses[d.object];
    // Per object: the index in Scene::objects, or one of these.
    constexpr int kUnbuilt = -1, kInPlace = -2;
    std::vector<int> built(objects.size(), kUnbuilt);
    std::size_t budget = m_opts.flatten_instances;
    for (const pbrt::InstanceDesc& d : m_desc.instances) {
        const pbrt::ObjectDesc& obj = objects[d.object];
        int& o = built[d.object];
        if (o == kUnbuilt) {
            // A curve's width follows an instance's transform, but only the mean scale of a
            // shape's own (Builder::curve): objects with curves stay instances.
            const bool placeable =
                m_opts.flatten_instances > 0 &&
                std::none_of(obj.shapes.begin(), obj.shapes.end(),
                             [](const pbrt::ShapeDesc& s) { return s.entity.type == "curve"; });
            if (placeable && uses[d.object] == 1) {
                o = kInPlace;  // no copy at all
            } else {
                std::vector<std::unique_ptr<Primitive>> prims;
                for (const auto& s : obj.shapes) shape(s, prims);
                PrimitiveCounts counts;
                count_primitives(prims, counts);
                const std::size_t n = counts.elements(), all = n * uses[d.object];
                if (placeable && n > 0 && all / uses[d.object] == n && all <= budget) {
                    budget -= all;
                    o = kInPlace;
                } else {
                    o = static_cast<int>(m_scene->objects.size());
                    m_scene->objects.emplace_back().primitives = std::move(prims);
                }
            }
            if (o == kInPlace) ++m_scene->objects_in_place;
        }
        if (o != kInPlace || obj.shapes.empty()) continue;
        finite_transform(d.world_from_instance, d.loc, "object instance");
        inverse_or_error(d.world_from_instance, d.loc, "the instance's transform is singular");
        // The object's shapes here, placed by this instance. An object used more than once was
        // built above to be counted, which gave its warnings: its placements give none.
        struct Placing {
            Builder& b;
            pbrt::WarningSink warn;
            Placing(Builder& builder, const Mat4& m, bool quiet) : b(builder) {
                b.m_placement = &m;
                if (quiet) warn = std::exchange(b.m_warn, {});
            }
            ~Placing() {
                b.m_placement = nullptr;
                if (warn) b.m_warn = std::move(warn);
            }
        } placing(*this, d.world_from_instance, uses[d.object] > 1);
        for (const auto& s : obj.shapes) shape(s, m_scene->primitives);
        ++m_scene->instances_in_place;
    }
    std::size_t next_id = m_scene->primitives.size();
    for (const pbrt::InstanceDesc& d : m_desc.instances) {
        const int o = built[d.object];
        if (o == kInPlace) continue;
        const std::size_t n = m_scene->objects[o].primitives.size();
        if (n == 0) continue;  // an empty object places nothing
        finite_transform(d.world_from_instance, d.loc, "object instance");
        const Mat4 inv =
            inverse_or_error(d.world_from_instance, d.loc, "the instance's transform is singular");
        Instance in;
        in.object = static_cast<uint32_t>(o);
        const auto w = to34(d.world_from_instance), iw = to34(inv);
        for (int k = 0; k < 12; ++k) {
            in.world_from_object[k] = static_cast<float>(w[k]);
            in.object_from_world[k] = static_cast<float>(iw[k]);
        }
        in.curvature_scale =
            static_cast<float>(std::cbrt(std::abs(d.world_from_instance.linear_determinant())));
        in.uniform = uniform_scale(w) > 0;
        if (next_id + n > std::numeric_limits<uint32_t>::max())
            throw SceneError(d.loc, "more than 2^32 instanced primitives");
        in.first_id = static_cast<uint32_t>(next_id);
        next_id += n;
        m_scene->instances.push_back(in);
    }
}

}  // namespace cmam::render::build_detail
