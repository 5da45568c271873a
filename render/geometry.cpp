// render — Embree set-up, analytic quadrics (pbrt-v3 sphere and disk) as user geometry, and
// the construction of oriented surface hits.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "render/error.h"
#include "render/scene.h"
#include "render/shading.h"
#include "render/transform3x4.h"

namespace cmam::render {

void count_primitives(const std::vector<std::unique_ptr<Primitive>>& prims,
                      PrimitiveCounts& counts) {
    for (const auto& p : prims) {
        if (p->kind == Primitive::Kind::Triangles)
            counts.triangles += p->indices.size() / 3;
        else if (p->kind == Primitive::Kind::Curves)
            counts.curve_segments += p->curve_first.size();
        else
            ++counts.quadrics;
    }
}

using namespace xform;

namespace {

double phi_of(double x, double y) {
    double phi = std::atan2(y, x);
    return phi < 0 ? phi + 2 * std::numbers::pi : phi;
}

/// Nearest object-space hit parameter in (tmin, tmax) for a quadric; returns false on a miss.
bool quadric_hit(const Primitive& prim, const D3& o, const D3& d, double tmin, double tmax,
                 double* t_out) {
    if (prim.kind == Primitive::Kind::Sphere) {
        double r = prim.radius;
        double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        double b = 2 * (d[0] * o[0] + d[1] * o[1] + d[2] * o[2]);
        double c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - r * r;
        double disc = b * b - 4 * a * c;
        if (disc < 0 || a == 0) return false;
        double sq = std::sqrt(disc);
        double q = b < 0 ? -0.5 * (b - sq) : -0.5 * (b + sq);
        double t0 = q / a, t1 = q != 0 ? c / q : t0;
        if (t0 > t1) std::swap(t0, t1);
        for (double t : {t0, t1}) {
            if (!(t > tmin && t < tmax)) continue;
            D3 p = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
            if (p[0] == 0 && p[1] == 0) p[0] = 1e-5 * r;
            if ((prim.zmin > -r && p[2] < prim.zmin) || (prim.zmax < r && p[2] > prim.zmax))
                continue;
            if (prim.phi_max < 2 * std::numbers::pi && phi_of(p[0], p[1]) > prim.phi_max) continue;
            *t_out = t;
            return true;
        }
        return false;
    }
    // Disk at z = height.
    if (d[2] == 0) return false;
    double t = (prim.height - o[2]) / d[2];
    if (!(t > tmin && t < tmax)) return false;
    double x = o[0] + t * d[0], y = o[1] + t * d[1];
    double dist2 = x * x + y * y;
    if (dist2 > prim.radius * prim.radius || dist2 < prim.inner_radius * prim.inner_radius)
        return false;
    if (prim.phi_max < 2 * std::numbers::pi && phi_of(x, y) > prim.phi_max) return false;
    *t_out = t;
    return true;
}

// A quadric is one user primitive, and Embree's BVH over a single one is a leaf without a box:
// every ray that reaches the scene's user geometry would call quadric_intersect, and a scene
// with one mirror ball spent 9% of its time there rejecting rays far from it. So the lone
// quadric of an Embree scene is given a second primitive, a point at the centre of its box that
// nothing ever hits: with two primitives Embree's builder makes a node, and its box test (over a
// packet's rays at once) keeps away the rays that miss the quadric's box. The point lies inside
// the box, so the scene's bounds, and an instance's, are unchanged.
constexpr unsigned kBoxOnly = 1;  // the second primitive's id

void quadric_bounds(const RTCBoundsFunctionArguments* args) {
    const auto* prim = static_cast<const Primitive*>(args->geometryUserPtr);
    double r = prim->radius;
    double z0 = prim->kind == Primitive::Kind::Sphere ? prim->zmin : prim->height;
    double z1 = prim->kind == Primitive::Kind::Sphere ? prim->zmax : prim->height;
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (int c = 0; c < 8; ++c) {
        D3 p =
            xform_point(prim->world_from_object, {c & 1 ? r : -r, c & 2 ? r : -r, c & 4 ? z1 : z0});
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], p[k]);
            hi[k] = std::max(hi[k], p[k]);
        }
    }
    RTCBounds* b = args->bounds_o;
    auto pad = [](double x, bool up) {
        float f = static_cast<float>(x);
        return std::nextafter(std::nextafter(f, up ? 1e30f : -1e30f), up ? 1e30f : -1e30f);
    };
    b->lower_x = pad(lo[0], false);
    b->lower_y = pad(lo[1], false);
    b->lower_z = pad(lo[2], false);
    b->upper_x = pad(hi[0], true);
    b->upper_y = pad(hi[1], true);
    b->upper_z = pad(hi[2], true);
    if (args->primID == kBoxOnly) {
        b->lower_x = b->upper_x = 0.5f * (b->lower_x + b->upper_x);
        b->lower_y = b->upper_y = 0.5f * (b->lower_y + b->upper_y);
        b->lower_z = b->upper_z = 0.5f * (b->lower_z + b->upper_z);
    }
}

void quadric_intersect(const RTCIntersectFunctionNArguments* args) {
    if (args->primID == kBoxOnly) return;
    const auto* prim = static_cast<const Primitive*>(args->geometryUserPtr);
    RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
    RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        D3 o = {RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i),
                RTCRayN_org_z(ray, args->N, i)};
        D3 d = {RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i),
                RTCRayN_dir_z(ray, args->N, i)};
        double t;
        if (!quadric_hit(*prim, xform_point(prim->object_from_world, o),
                         xform_vector(prim->object_from_world, d), RTCRayN_tnear(ray, args->N, i),
                         RTCRayN_tfar(ray, args->N, i), &t))
            continue;
        RTCRayN_tfar(ray, args->N, i) = static_cast<float>(t);
        RTCHitN_Ng_x(hit, args->N, i) = 0;
        RTCHitN_Ng_y(hit, args->N, i) = 0;
        RTCHitN_Ng_z(hit, args->N, i) = 1;
        RTCHitN_u(hit, args->N, i) = 0;
        RTCHitN_v(hit, args->N, i) = 0;
        RTCHitN_primID(hit, args->N, i) = args->primID;
        RTCHitN_geomID(hit, args->N, i) = args->geomID;
        RTCHitN_instID(hit, args->N, i, 0) = args->context->instID[0];
    }
}

void quadric_occluded(const RTCOccludedFunctionNArguments* args) {
    if (args->primID == kBoxOnly) return;
    const auto* prim = static_cast<const Primitive*>(args->geometryUserPtr);
    RTCRayN* ray = args->ray;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        D3 o = {RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i),
                RTCRayN_org_z(ray, args->N, i)};
        D3 d = {RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i),
                RTCRayN_dir_z(ray, args->N, i)};
        double t;
        if (quadric_hit(*prim, xform_point(prim->object_from_world, o),
                        xform_vector(prim->object_from_world, d), RTCRayN_tnear(ray, args->N, i),
                        RTCRayN_tfar(ray, args->N, i), &t))
            RTCRayN_tfar(ray, args->N, i) = -std::numeric_limits<float>::infinity();
    }
}

void alpha_filter(const RTCFilterFunctionNArguments* args, bool shadow) {
    const auto* prim = static_cast<const Primitive*>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        if (prim->cut_out(RTCHitN_primID(args->hit, args->N, i), RTCHitN_u(args->hit, args->N, i),
                          RTCHitN_v(args->hit, args->N, i), shadow))
            args->valid[i] = 0;  // not there: Embree goes on to the next hit
    }
}
// Where a ribbon curve is: pbrt-v3 intersects it as the flat curve facing the ray, its width
// scaled by |n(u) . d| (n the ends' normals interpolated spherically, not renormalised: seen
// along its normal a ribbon is as wide as its width, edge-on it is not there). Embree's flat
// curve is as wide as the width; this keeps the hits within the scaled width.
struct CurvePoint {
    Vec3 centre, dpdu;
    float width;
};
CurvePoint curve_point(const Primitive& prim, uint32_t seg, float u) {
    const std::array<float, 4>* q = &prim.curve_points[prim.curve_first[seg]];
    const Vec3 c0(q[0][0], q[0][1], q[0][2]), c1(q[1][0], q[1][1], q[1][2]),
        c2(q[2][0], q[2][1], q[2][2]), c3(q[3][0], q[3][1], q[3][2]);
    auto lerp = [u](const Vec3& a, const Vec3& b) { return (1 - u) * a + u * b; };
    const Vec3 a0 = lerp(c0, c1), a1 = lerp(c1, c2), a2 = lerp(c2, c3);
    const Vec3 b0 = lerp(a0, a1), b1 = lerp(a1, a2);
    const Vec3 db = b1 - b0;
    const std::array<float, 2>& ws = prim.curve_widths[seg];
    return {lerp(b0, b1), dot(db, db) > 0 ? 3 * db : c3 - c0,  // (pbrt-v3's fallback at a cusp)
            (1 - u) * ws[0] + u * ws[1]};
}
// The hit's distance from the curve across the ray (in the plane facing it), signed by pbrt-v3's
// edge function: (dP/du x (p - c)) . d, which is (p - c) . (d x dP/du).
float across_ray(const Vec3& off, const Vec3& dir, const Vec3& dpdu) {
    const Vec3 side = cross(dir, dpdu);
    const float len = length(side);
    return len > 0 ? dot(off, side) / len : 0.0f;
}
float ribbon_scale(const Primitive& prim, uint32_t seg, float u, const Vec3& dir) {
    const auto& n = prim.curve_end_normals[seg];
    return std::abs(dot(curve_normal(n[0], n[1], u), dir)) / length(dir);
}
void ribbon_filter(const RTCFilterFunctionNArguments* args) {
    const auto* prim = static_cast<const Primitive*>(args->geometryUserPtr);
    RTCRayN* ray = args->ray;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const uint32_t seg = RTCHitN_primID(args->hit, args->N, i);
        const float u = std::clamp(RTCHitN_u(args->hit, args->N, i), 0.0f, 1.0f);
        const Vec3 o(RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i),
                     RTCRayN_org_z(ray, args->N, i)),
            d(RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i),
              RTCRayN_dir_z(ray, args->N, i));
        const CurvePoint c = curve_point(*prim, seg, u);
        const Vec3 off = o + d * RTCRayN_tfar(ray, args->N, i) - c.centre;
        if (!(2 * std::abs(across_ray(off, d, c.dpdu)) <= c.width * ribbon_scale(*prim, seg, u, d)))
            args->valid[i] = 0;  // beyond the ribbon's width as seen along the ray
    }
}

void alpha_intersect_filter(const RTCFilterFunctionNArguments* args) {
    alpha_filter(args, false);
}
void alpha_occluded_filter(const RTCFilterFunctionNArguments* args) {
    alpha_filter(args, true);
}

void embree_error(void*, RTCError code, const char* str) {
    throw RenderError(std::string("Embree error ") + std::to_string(code) + ": " +
                      (str ? str : ""));
}

// A hit on a curve segment (algorithms.md §20): Embree gives the curve parameter u and the
// distance; the rest is pbrt-v3's. dP/du is the Bezier curve's tangent; dP/dv spans the width
// (w = the width at u) across it: for flat and cylinder curves in the plane facing the ray,
// pbrt-v3's (-dp/du.y, dp/du.x, 0) in the ray's frame, which is normalize(d x dP/du), for a
// ribbon normalize(n(u) x dP/du); a cylinder's turned about dP/du by -(v - 1/2) 180 degrees so
// that its normal rounds across the width. v is where the hit lies across the width, 1/2 on
// the curve (pbrt-v3's side of it by the edge function, the same sign as (dP/du x (p - c)) . d).
void curve_hit(const Vec3& org, const Vec3& dir, const RTCHit& hit, SurfaceHit& h) {
    const Primitive& prim = *h.prim;
    const uint32_t seg = hit.primID;
    const float u = std::clamp(hit.u, 0.0f, 1.0f);
    CurvePoint c = curve_point(prim, seg, u);
    if (!(dot(c.dpdu, c.dpdu) > 0)) c.dpdu = Frame::from_z(normalize(dir)).s;  // no length
    const bool ribbon = prim.curve_type == Primitive::CurveType::Ribbon;
    const float width = ribbon ? c.width * ribbon_scale(prim, seg, u, dir) : c.width;
    h.p = org + dir * h.t;
    const float across = across_ray(h.p - c.centre, dir, c.dpdu);
    const float v = width > 0 ? std::clamp(0.5f + across / width, 0.0f, 1.0f) : 0.5f;
    Vec3 dpdv;
    if (ribbon) {
        const auto& n = prim.curve_end_normals[seg];
        dpdv = normalize(cross(curve_normal(n[0], n[1], u), c.dpdu)) * width;
    } else {
        dpdv = normalize(cross(dir, c.dpdu)) * width;
        if (prim.curve_type == Primitive::CurveType::Cylinder) {
            const float theta = (v - 0.5f) * kPi;
            dpdv = std::cos(theta) * dpdv - std::sin(theta) * cross(normalize(c.dpdu), dpdv);
        }
    }
    Vec3 n = normalize(cross(c.dpdu, dpdv));
    if (prim.flip) n = -n;
    h.u = u;
    h.v = v;
    h.ng = n;
    h.ns = n;
    h.triangle = seg;
    h.curve_partials = {c.dpdu, dpdv};
    h.offset = 2 * width;
    h.uv_pending = false;
}

// The hit on h.prim in the primitive's own space (the world, or an instance's object space).
void local_hit(const Vec3& org, const Vec3& dir, const RTCHit& hit, bool uv, SurfaceHit* out) {
    const Primitive& prim = *out->prim;
    SurfaceHit& h = *out;
    h.offset = 0;
    if (prim.kind == Primitive::Kind::Curves) {
        curve_hit(org, dir, hit, h);
        return;
    }
    if (prim.kind == Primitive::Kind::Triangles) {
        uint32_t i0 = prim.indices[3 * hit.primID], i1 = prim.indices[3 * hit.primID + 1],
                 i2 = prim.indices[3 * hit.primID + 2];
        float b1 = hit.u, b2 = hit.v, b0 = 1 - b1 - b2;
        h.triangle = hit.primID;
        h.b1 = b1;
        h.b2 = b2;
        const Vec3 &p0 = prim.positions[i0], &p1 = prim.positions[i1], &p2 = prim.positions[i2];
        h.p = b0 * p0 + b1 * p1 + b2 * p2;
        if (!prim.uvs.empty()) {
            h.u = b0 * prim.uvs[i0][0] + b1 * prim.uvs[i1][0] + b2 * prim.uvs[i2][0];
            h.v = b0 * prim.uvs[i0][1] + b1 * prim.uvs[i1][1] + b2 * prim.uvs[i2][1];
        } else {  // pbrt-v3 default parameterization (0,0), (1,0), (1,1)
            h.u = b1 + b2;
            h.v = b2;
        }
        Vec3 n = normalize(cross(p0 - p2, p1 - p2));
        if (prim.flip) n = -n;
        h.ng = n;
        h.ns = n;
        if (!prim.normals.empty()) {
            Vec3 ns = b0 * prim.normals[i0] + b1 * prim.normals[i1] + b2 * prim.normals[i2];
            float l = length(ns);
            if (l > 0) {
                ns = ns / l;
                if (prim.flip) ns = -ns;
                h.ns = ns;
                h.ng = prim.normals_geometric ? ns : faceforward(n, ns);
            }
        }
        return;
    }
    // Quadric: recompute the hit in object space (double precision).
    D3 o = xform_point(prim.object_from_world, {org.x, org.y, org.z});
    D3 d = xform_vector(prim.object_from_world, {dir.x, dir.y, dir.z});
    double t = h.t;
    D3 p = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
    D3 n_obj;
    if (prim.kind == Primitive::Kind::Sphere) {
        double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (double& x : p) x *= prim.radius / len;
        if (p[0] == 0 && p[1] == 0) p[0] = 1e-5 * prim.radius;
        n_obj = p;  // cross(dpdu, dpdv) points outwards
    } else {
        p[2] = prim.height;
        n_obj = {0, 0, 1};
    }
    if (prim.flip)
        for (double& x : n_obj) x = -x;
    h.p_object = p;
    h.uv_pending = true;
    if (uv) h.compute_quadric_uv();
    h.p = to_vec(xform_point(prim.world_from_object, p));
    Vec3 n = normalize(to_vec(xform_normal(prim.object_from_world, n_obj)));
    h.ng = n;
    h.ns = n;
}

}  // namespace

void SurfaceHit::compute_quadric_uv() {
    const Primitive& pr = *prim;
    const D3& p = p_object;
    if (pr.kind == Primitive::Kind::Sphere) {
        double phi = phi_of(p[0], p[1]);
        double theta = std::acos(std::clamp(p[2] / pr.radius, -1.0, 1.0));
        u = static_cast<float>(phi / pr.phi_max);
        v = static_cast<float>((theta - pr.theta_zmin) / (pr.theta_zmax - pr.theta_zmin));
    } else {
        double r = std::sqrt(p[0] * p[0] + p[1] * p[1]);
        u = static_cast<float>(phi_of(p[0], p[1]) / pr.phi_max);
        v = static_cast<float>((pr.radius - r) / (pr.radius - pr.inner_radius));
    }
    uv_pending = false;
}

Scene::Scene() {
#ifdef CMAM_STD_THREADS
    // Builds for ThreadSanitizer: Embree builds its hierarchies on the calling thread (its
    // oneTBB workers' hand-offs are invisible to the sanitizer).
    m_device = rtcNewDevice("threads=1");
#else
    m_device = rtcNewDevice(nullptr);
#endif
    if (!m_device) throw RenderError("cannot create the Embree device");
    rtcSetDeviceErrorFunction(m_device, embree_error, nullptr);
    // Packets of 16 where Embree traces 16 rays as one (AVX-512); where it has no native
    // 16-ray packets but 8-ray ones (AVX2), two packets of 8 took 0.6-1.5% less CPU time.
    m_packet_width =
        !rtcGetDeviceProperty(m_device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) &&
                rtcGetDeviceProperty(m_device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED)
            ? 8
            : 16;
}

void Scene::set_packet_width(int width) {
    if (width != 8 && width != 16) throw RenderError("packet width must be 8 or 16");
    m_packet_width = width;
}

Scene::~Scene() {
    if (m_scene) rtcReleaseScene(m_scene);
    for (RTCScene s : m_object_scenes)
        if (s) rtcReleaseScene(s);
    if (m_device) rtcReleaseDevice(m_device);
}

std::size_t Scene::texture_memory_bytes() const {
    std::size_t n = 0;
    for (const auto& [k, img] : images) n += img->memory_bytes();
    return n;
}

namespace {

// Attaches prim to scene as geometry `id`; `lone` when it is the scene's only quadric.
void attach(RTCDevice device, RTCScene scene, Primitive& prim, unsigned id, const Scene* owner,
            bool lone) {
    RTCGeometry g;
    if (prim.kind == Primitive::Kind::Triangles) {
        g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        // Embree reads the primitive's own arrays (no copy of them, and on the large pages they
        // are on). It may read a vertex as 16 bytes: the array has room for one more.
        static_assert(sizeof(Vec3) == 3 * sizeof(float));
        prim.positions.reserve(prim.positions.size() + 1);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                   prim.positions.data(), 0, sizeof(Vec3), prim.positions.size());
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                   prim.indices.data(), 0, 3 * sizeof(uint32_t),
                                   prim.indices.size() / 3);
        prim.scene = owner;
        if (prim.has_alpha()) {
            rtcSetGeometryUserData(g, &prim);
            rtcSetGeometryIntersectFilterFunction(g, alpha_intersect_filter);
            rtcSetGeometryOccludedFilterFunction(g, alpha_occluded_filter);
        }
    } else if (prim.kind == Primitive::Kind::Curves) {
        // Embree's flat (ray-facing) Bezier curves, as pbrt-v3 intersects all three types; a
        // ribbon's hits are kept within its width as the ray sees it (ribbon_filter). Embree
        // reads the primitive's own buffers.
        g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                   prim.curve_points.data(), 0, 4 * sizeof(float),
                                   prim.curve_points.size());
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT,
                                   prim.curve_first.data(), 0, sizeof(uint32_t),
                                   prim.curve_first.size());
        rtcSetGeometryTessellationRate(g, prim.curve_tessellation);
        if (prim.curve_type == Primitive::CurveType::Ribbon) {
            rtcSetGeometryUserData(g, &prim);
            rtcSetGeometryIntersectFilterFunction(g, ribbon_filter);
            rtcSetGeometryOccludedFilterFunction(g, ribbon_filter);
        }
    } else {
        g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(g, lone ? 2 : 1);  // kBoxOnly when lone
        rtcSetGeometryUserData(g, &prim);
        rtcSetGeometryBoundsFunction(g, quadric_bounds, nullptr);
        rtcSetGeometryIntersectFunction(g, quadric_intersect);
        rtcSetGeometryOccludedFunction(g, quadric_occluded);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene, g, id);
    rtcReleaseGeometry(g);
}

// True when exactly one of `prims` is a quadric.
bool one_quadric(const std::vector<std::unique_ptr<Primitive>>& prims) {
    return std::count_if(prims.begin(), prims.end(), [](const auto& p) {
               return p->kind == Primitive::Kind::Sphere || p->kind == Primitive::Kind::Disk;
           }) == 1;
}
}  // namespace

namespace {
// Embree's SAH build (its default quality). The high quality's spatial splits made no render
// measurably faster (the bundled mesh scene at 64 spp, pbrt-v3-scenes' breakfast, coffee-splash,
// caustic-glass and buddha-fractal at 16 spp) and cost up to a third more CPU time in loading a
// large mesh (breakfast: 533k triangles). docs/performance.md, "Loading".
constexpr RTCBuildQuality kBuildQuality = RTC_BUILD_QUALITY_MEDIUM;
}  // namespace

void Scene::commit() {
    // The (u,v) gradients of the triangles whose material reads textures, for the footprint
    // producers that turn offsets on the surface into (u,v) (ray differentials and anisotropic
    // cones); 24 bytes a triangle, so not made when nothing reads them.
    const bool offsets = footprint_methods.has(FootprintMethod::Differentials) ||
                         footprint_methods.has(FootprintMethod::ConesAniso);
    // Their (u,v) charts for the CMAM, which takes no neighbour across a seam (a closed
    // quadric's tessellation has its own seam, taken the short way round instead).
    const bool charts = footprint_methods.has(FootprintMethod::Cmam);
    auto triangle_tables = [this, offsets, charts](Primitive& pr) {
        if (pr.kind != Primitive::Kind::Triangles || pr.material < 0 ||
            pr.material >= static_cast<int>(materials.size()) ||
            !materials[pr.material].reads_textures())
            return;
        if (offsets) pr.make_uv_gradients();
        if (charts && !pr.u_periodic && !pr.v_periodic) pr.make_uv_charts();
    };
    for (auto& pr : primitives) triangle_tables(*pr);
    for (Object& o : objects)
        for (auto& pr : o.primitives) triangle_tables(*pr);
    // Objects first: an instance refers to its object's committed scene. Objects that no
    // instance uses are not built.
    std::vector<bool> used(objects.size(), false);
    for (const Instance& in : instances) used[in.object] = true;
    m_object_scenes.assign(objects.size(), nullptr);
    for (std::size_t o = 0; o < objects.size(); ++o) {
        if (!used[o]) continue;
        RTCScene s = rtcNewScene(m_device);
        rtcSetSceneBuildQuality(s, kBuildQuality);
        const bool lone = one_quadric(objects[o].primitives);
        for (std::size_t id = 0; id < objects[o].primitives.size(); ++id)
            attach(m_device, s, *objects[o].primitives[id], static_cast<unsigned>(id), this, lone);
        rtcCommitScene(s);
        m_object_scenes[o] = s;
    }
    m_scene = rtcNewScene(m_device);
    rtcSetSceneBuildQuality(m_scene, kBuildQuality);
    const bool lone = one_quadric(primitives);
    for (std::size_t id = 0; id < primitives.size(); ++id)
        attach(m_device, m_scene, *primitives[id], static_cast<unsigned>(id), this, lone);
    // Instances take the geometry ids after the primitives outside objects.
    for (std::size_t i = 0; i < instances.size(); ++i) {
        RTCGeometry g = rtcNewGeometry(m_device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(g, m_object_scenes[instances[i].object]);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR,
                                instances[i].world_from_object.data());
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(m_scene, g, static_cast<unsigned>(primitives.size() + i));
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(m_scene);
    RTCBounds b;
    rtcGetSceneBounds(m_scene, &b);
    const Vec3 lo(b.lower_x, b.lower_y, b.lower_z), hi(b.upper_x, b.upper_y, b.upper_z);
    const bool bounded = lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z;
    world_radius = bounded ? 0.5f * length(hi - lo) : 0.0f;
    world_center = bounded ? 0.5f * (lo + hi) : Vec3();
}

bool Scene::occluded(const Vec3& org, const Vec3& dir, float tmin, float tmax) const {
    if (!finite(org) || !finite(dir) || std::isnan(tmin) || std::isnan(tmax)) return true;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay ray{};
    ray.org_x = org.x;
    ray.org_y = org.y;
    ray.org_z = org.z;
    ray.dir_x = dir.x;
    ray.dir_y = dir.y;
    ray.dir_z = dir.z;
    ray.tnear = tmin;
    ray.tfar = tmax;
    ray.mask = 0xffffffffu;
    rtcOccluded1(m_scene, &ctx, &ray);
    return ray.tfar < 0;
}

namespace {
// Lane i of a packet (RTCRay8 or RTCRay16): the ray o + t d, t in (0, tfar).
template <class RayK>
void set_lane(RayK& r, int i, const Vec3& o, const Vec3& d, float tfar) {
    r.org_x[i] = o.x;
    r.org_y[i] = o.y;
    r.org_z[i] = o.z;
    r.dir_x[i] = d.x;
    r.dir_y[i] = d.y;
    r.dir_z[i] = d.z;
    r.tnear[i] = 0;
    r.tfar[i] = tfar;
    r.time[i] = 0;
    r.mask[i] = 0xffffffffu;
    r.id[i] = 0;
    r.flags[i] = 0;
}

// Embree's packet types of K (8 or 16) rays.
template <int K>
using RayOf = std::conditional_t<K == 8, RTCRay8, RTCRay16>;
template <int K>
using RayHitOf = std::conditional_t<K == 8, RTCRayHit8, RTCRayHit16>;
}  // namespace

void Scene::occluded_packet(const Vec3* org, const Vec3* dir, const float* tmax, int n,
                            bool* occluded) const {
    if (m_packet_width == 16) return occluded_lanes<16>(org, dir, tmax, n, occluded);
    for (int f = 0; f < n; f += 8)
        occluded_lanes<8>(org + f, dir + f, tmax + f, std::min(8, n - f), occluded + f);
}

template <int K>
void Scene::occluded_lanes(const Vec3* org, const Vec3* dir, const float* tmax, int n,
                           bool* occluded) const {
    alignas(64) RayOf<K> ray;
    alignas(64) int valid[K];
    for (int i = 0; i < K; ++i) {
        // As occluded(): a ray that is not finite is occluded without tracing.
        const bool ok = i < n && finite(org[i]) && finite(dir[i]) && !std::isnan(tmax[i]);
        valid[i] = ok ? -1 : 0;
        set_lane(ray, i, ok ? org[i] : Vec3(), ok ? dir[i] : Vec3(0, 0, 1), ok ? tmax[i] : 0);
    }
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    // Coherent rays, Embree's hint, but not through instances: Embree 3.13's coherent packet
    // traversal of instances did not return (an occlusion packet on an instanced sphere).
    if (instances.empty()) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    if constexpr (K == 8)
        rtcOccluded8(valid, m_scene, &ctx, &ray);
    else
        rtcOccluded16(valid, m_scene, &ctx, &ray);
    for (int i = 0; i < n; ++i) occluded[i] = !valid[i] || ray.tfar[i] < 0;
}

std::optional<SurfaceHit> Scene::intersect(const Vec3& org, const Vec3& dir, float tmin, float tmax,
                                           bool uv) const {
    std::optional<SurfaceHit> out;  // every return is this one, constructed in the caller's slot
    if (!finite(org) || !finite(dir) || std::isnan(tmin) || std::isnan(tmax)) return out;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh{};
    rh.ray.org_x = org.x;
    rh.ray.org_y = org.y;
    rh.ray.org_z = org.z;
    rh.ray.dir_x = dir.x;
    rh.ray.dir_y = dir.y;
    rh.ray.dir_z = dir.z;
    rh.ray.tnear = tmin;
    rh.ray.tfar = tmax;
    rh.ray.mask = 0xffffffffu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(m_scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return out;
    surface_hit(org, dir, rh.ray.tfar, rh.hit, uv, out.emplace());
    return out;
}

void Scene::intersect_packet(const Vec3* org, const Vec3* dir, int n,
                             std::optional<SurfaceHit>* hits, bool uv) const {
    if (m_packet_width == 16) return intersect_lanes<16>(org, dir, n, hits, uv);
    for (int f = 0; f < n; f += 8)
        intersect_lanes<8>(org + f, dir + f, std::min(8, n - f), hits + f, uv);
}

template <int K>
void Scene::intersect_lanes(const Vec3* org, const Vec3* dir, int n,
                            std::optional<SurfaceHit>* hits, bool uv) const {
    alignas(64) RayHitOf<K> rh;
    alignas(64) int valid[K];
    for (int i = 0; i < K; ++i) {
        valid[i] = i < n && finite(org[i]) && finite(dir[i]) ? -1 : 0;
        set_lane(rh.ray, i, valid[i] ? org[i] : Vec3(), valid[i] ? dir[i] : Vec3(0, 0, 1),
                 std::numeric_limits<float>::infinity());
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    }
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    // As in occluded_lanes.
    if (instances.empty()) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    if constexpr (K == 8)
        rtcIntersect8(valid, m_scene, &ctx, &rh);
    else
        rtcIntersect16(valid, m_scene, &ctx, &rh);
    for (int i = 0; i < n; ++i) {
        hits[i].reset();
        if (!valid[i] || rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
        RTCHit h{};
        h.Ng_x = rh.hit.Ng_x[i];
        h.Ng_y = rh.hit.Ng_y[i];
        h.Ng_z = rh.hit.Ng_z[i];
        h.u = rh.hit.u[i];
        h.v = rh.hit.v[i];
        h.primID = rh.hit.primID[i];
        h.geomID = rh.hit.geomID[i];
        h.instID[0] = rh.hit.instID[0][i];
        surface_hit(org[i], dir[i], rh.ray.tfar[i], h, uv, hits[i].emplace());
    }
}

void Scene::surface_hit(const Vec3& org, const Vec3& dir, float t, const RTCHit& hit, bool uv,
                        SurfaceHit& h) const {
    h.t = t;
    if (hit.instID[0] == RTC_INVALID_GEOMETRY_ID) {
        h.instance = nullptr;
        h.prim = primitives[hit.geomID].get();
        h.object_id = h.prim->id;
        local_hit(org, dir, hit, uv, &h);
        return;
    }
    // In an instance: the hit is found in the object's space, then placed in the world.
    const Instance& in = instances[hit.instID[0] - primitives.size()];
    h.instance = &in;
    h.prim = objects[in.object].primitives[hit.geomID].get();
    h.object_id = in.first_id + hit.geomID;
    local_hit(in.to_object_point(org), in.to_object_vector(dir), hit, uv, &h);
    h.p = in.to_world_point(h.p);
    h.offset *= in.curvature_scale;  // (a curve's: its width, scaled as the instance scales)
    h.ns_object = h.ns;
    h.ng = normalize(in.to_world_normal(h.ng));
    h.ns = normalize(in.to_world_normal(h.ns));
}

}  // namespace cmam::render
