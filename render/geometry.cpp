// render — Embree set-up, analytic quadrics (pbrt-v3 sphere and disk) as user geometry, and
// the construction of oriented surface hits.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "render/error.h"
#include "render/scene.h"
#include "render/shading.h"

namespace cmam::render {

namespace {

using D3 = std::array<double, 3>;

D3 xform_point(const std::array<double, 12>& m, const D3& p) {
    return {m[0] * p[0] + m[1] * p[1] + m[2] * p[2] + m[3],
            m[4] * p[0] + m[5] * p[1] + m[6] * p[2] + m[7],
            m[8] * p[0] + m[9] * p[1] + m[10] * p[2] + m[11]};
}
D3 xform_vector(const std::array<double, 12>& m, const D3& v) {
    return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[4] * v[0] + m[5] * v[1] + m[6] * v[2],
            m[8] * v[0] + m[9] * v[1] + m[10] * v[2]};
}
// Normals transform with the inverse transpose: n_world = (object_from_world)^T n_obj.
D3 xform_normal(const std::array<double, 12>& object_from_world, const D3& n) {
    const auto& m = object_from_world;
    return {m[0] * n[0] + m[4] * n[1] + m[8] * n[2], m[1] * n[0] + m[5] * n[1] + m[9] * n[2],
            m[2] * n[0] + m[6] * n[1] + m[10] * n[2]};
}
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
}

void quadric_intersect(const RTCIntersectFunctionNArguments* args) {
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

Vec3 to_vec(const D3& d) {
    return Vec3(float(d[0]), float(d[1]), float(d[2]));
}

// d(n/|n|) = ((n.n) dn - (n.dn) n) / |n|^3 for an unnormalised normal n.
Vec3 unit_derivative(const Vec3& n, const Vec3& dn) {
    float nn = dot(n, n);
    return (nn * dn - dot(n, dn) * n) / (nn * std::sqrt(nn));
}

// A 3x4 row-major affine transform applied to a point, a vector, or (as its inverse transpose,
// given the inverse) a normal.
Vec3 apply_point(const std::array<float, 12>& m, const Vec3& p) {
    return Vec3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
                m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}
Vec3 apply_vector(const std::array<float, 12>& m, const Vec3& v) {
    return Vec3(m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
                m[8] * v.x + m[9] * v.y + m[10] * v.z);
}
Vec3 apply_transpose(const std::array<float, 12>& m, const Vec3& n) {
    return Vec3(m[0] * n.x + m[4] * n.y + m[8] * n.z, m[1] * n.x + m[5] * n.y + m[9] * n.z,
                m[2] * n.x + m[6] * n.y + m[10] * n.z);
}

// The hit on h.prim in the primitive's own space (the world, or an instance's object space).
void local_hit(const Vec3& org, const Vec3& dir, const RTCHit& hit, SurfaceHit* out) {
    const Primitive& prim = *out->prim;
    SurfaceHit& h = *out;
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
                h.ng = faceforward(n, ns);
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
        double phi = phi_of(p[0], p[1]);
        double theta = std::acos(std::clamp(p[2] / prim.radius, -1.0, 1.0));
        h.u = static_cast<float>(phi / prim.phi_max);
        h.v = static_cast<float>((theta - prim.theta_zmin) / (prim.theta_zmax - prim.theta_zmin));
        n_obj = p;  // cross(dpdu, dpdv) points outwards
    } else {
        p[2] = prim.height;
        double r = std::sqrt(p[0] * p[0] + p[1] * p[1]);
        h.u = static_cast<float>(phi_of(p[0], p[1]) / prim.phi_max);
        h.v = static_cast<float>((prim.radius - r) / (prim.radius - prim.inner_radius));
        n_obj = {0, 0, 1};
    }
    if (prim.flip)
        for (double& x : n_obj) x = -x;
    h.p_object = p;
    h.p = to_vec(xform_point(prim.world_from_object, p));
    Vec3 n = normalize(to_vec(xform_normal(prim.object_from_world, n_obj)));
    h.ng = n;
    h.ns = n;
}

}  // namespace

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

void attach(RTCDevice device, RTCScene scene, Primitive& prim, unsigned id, const Scene* owner) {
    RTCGeometry g;
    if (prim.kind == Primitive::Kind::Triangles) {
        g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                                              RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                              prim.positions.size()));
        for (std::size_t i = 0; i < prim.positions.size(); ++i) {
            v[3 * i] = prim.positions[i].x;
            v[3 * i + 1] = prim.positions[i].y;
            v[3 * i + 2] = prim.positions[i].z;
        }
        auto* idx = static_cast<uint32_t*>(
            rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    3 * sizeof(uint32_t), prim.indices.size() / 3));
        std::copy(prim.indices.begin(), prim.indices.end(), idx);
        prim.scene = owner;
        if (prim.has_alpha()) {
            rtcSetGeometryUserData(g, &prim);
            rtcSetGeometryIntersectFilterFunction(g, alpha_intersect_filter);
            rtcSetGeometryOccludedFilterFunction(g, alpha_occluded_filter);
        }
    } else {
        g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(g, 1);
        rtcSetGeometryUserData(g, &prim);
        rtcSetGeometryBoundsFunction(g, quadric_bounds, nullptr);
        rtcSetGeometryIntersectFunction(g, quadric_intersect);
        rtcSetGeometryOccludedFunction(g, quadric_occluded);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene, g, id);
    rtcReleaseGeometry(g);
}

}  // namespace

void Scene::commit() {
    // Objects first: an instance refers to its object's committed scene. Objects that no
    // instance uses are not built.
    std::vector<bool> used(objects.size(), false);
    for (const Instance& in : instances) used[in.object] = true;
    m_object_scenes.assign(objects.size(), nullptr);
    for (std::size_t o = 0; o < objects.size(); ++o) {
        if (!used[o]) continue;
        RTCScene s = rtcNewScene(m_device);
        rtcSetSceneBuildQuality(s, RTC_BUILD_QUALITY_HIGH);
        for (std::size_t id = 0; id < objects[o].primitives.size(); ++id)
            attach(m_device, s, *objects[o].primitives[id], static_cast<unsigned>(id), this);
        rtcCommitScene(s);
        m_object_scenes[o] = s;
    }
    m_scene = rtcNewScene(m_device);
    rtcSetSceneBuildQuality(m_scene, RTC_BUILD_QUALITY_HIGH);
    for (std::size_t id = 0; id < primitives.size(); ++id)
        attach(m_device, m_scene, *primitives[id], static_cast<unsigned>(id), this);
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
}

bool Scene::occluded(const Vec3& org, const Vec3& dir, float tmin, float tmax) const {
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

std::optional<SurfaceHit> Scene::intersect(const Vec3& org, const Vec3& dir, float tmin,
                                           float tmax) const {
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
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;

    std::optional<SurfaceHit> hit(std::in_place);
    SurfaceHit& h = *hit;
    h.t = rh.ray.tfar;
    if (rh.hit.instID[0] == RTC_INVALID_GEOMETRY_ID) {
        h.instance = nullptr;
        h.prim = primitives[rh.hit.geomID].get();
        h.object_id = h.prim->id;
        local_hit(org, dir, rh.hit, &h);
        return hit;
    }
    // In an instance: the hit is found in the object's space, then placed in the world.
    const Instance& in = instances[rh.hit.instID[0] - primitives.size()];
    h.instance = &in;
    h.prim = objects[in.object].primitives[rh.hit.geomID].get();
    h.object_id = in.first_id + rh.hit.geomID;
    local_hit(in.to_object_point(org), in.to_object_vector(dir), rh.hit, &h);
    h.p = in.to_world_point(h.p);
    h.ns_object = h.ns;
    h.ng = normalize(in.to_world_normal(h.ng));
    h.ns = normalize(in.to_world_normal(h.ns));
    return hit;
}

SurfaceSample Primitive::sample_area(float u1, float u2) const {
    SurfaceSample out;
    if (kind == Kind::Triangles) {
        // A triangle by area (area_cdf), then a point uniform in it; u1 is reused within the
        // chosen triangle's span.
        const double total = area_cdf.empty() ? 0 : area_cdf.back();
        if (!(total > 0)) return out;
        const double x = double(u1) * total;
        const auto it = std::upper_bound(area_cdf.begin(), area_cdf.end(), x);
        const std::size_t ntri = area_cdf.size() - 1;
        const std::size_t t = std::min(ntri - 1, static_cast<std::size_t>(std::max<std::ptrdiff_t>(
                                                     0, (it - area_cdf.begin()) - 1)));
        const double span = area_cdf[t + 1] - area_cdf[t];
        const float r = span > 0 ? float(std::clamp((x - area_cdf[t]) / span, 0.0, 1.0)) : 0.5f;
        const float su = std::sqrt(r), b0 = 1 - su, b1 = u2 * su, b2 = 1 - b0 - b1;
        const uint32_t i0 = indices[3 * t], i1 = indices[3 * t + 1], i2 = indices[3 * t + 2];
        const Vec3 &p0 = positions[i0], &p1 = positions[i1], &p2 = positions[i2];
        out.p = b0 * p0 + b1 * p1 + b2 * p2;
        Vec3 ng = normalize(cross(p0 - p2, p1 - p2));
        if (flip) ng = -ng;
        if (!normals.empty()) {  // oriented as intersect() orients hits
            const Vec3 ns = b0 * normals[i0] + b1 * normals[i1] + b2 * normals[i2];
            if (length(ns) > 0) ng = faceforward(ng, flip ? -ns : ns);
        }
        out.n = ng;
        out.pdf = float(1 / total);
        return out;
    }
    // Quadrics: (u1,u2) map to a point uniform by object-space area (Archimedes' z for the
    // sphere, r^2 for the disk, phi for both). The world-space area element is |dP/du1 x
    // dP/du2| after the transform, det(M) M^-T applied to the object-space one, so the density
    // is exact under any transform.
    const double phi = double(u2) * phi_max;
    D3 po, cross_obj;
    if (kind == Kind::Sphere) {
        const double z = zmin + double(u1) * (zmax - zmin);
        const double rho = std::sqrt(std::max(0.0, radius * radius - z * z));
        po = {rho * std::cos(phi), rho * std::sin(phi), z};
        const double k = (zmax - zmin) * phi_max;
        cross_obj = {k * po[0], k * po[1], k * po[2]};  // outwards, |.| = k * radius
    } else {
        const double r2 = inner_radius * inner_radius +
                          double(u1) * (radius * radius - inner_radius * inner_radius);
        const double rho = std::sqrt(r2);
        po = {rho * std::cos(phi), rho * std::sin(phi), height};
        cross_obj = {0, 0, 0.5 * (radius * radius - inner_radius * inner_radius) * phi_max};
    }
    const auto& m = world_from_object;
    const double det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                       m[2] * (m[4] * m[9] - m[5] * m[8]);
    const D3 cw = xform_normal(object_from_world, cross_obj);
    const double area_element =
        std::abs(det) * std::sqrt(cw[0] * cw[0] + cw[1] * cw[1] + cw[2] * cw[2]);
    if (!(area_element > 0) || !std::isfinite(area_element)) return out;
    out.p = to_vec(xform_point(world_from_object, po));
    Vec3 nw = normalize(to_vec(cw));
    out.n = flip ? -nw : nw;
    out.pdf = float(1 / area_element);
    return out;
}

bool Primitive::cut_out(uint32_t tri, float b1, float b2, bool shadow) const {
    const uint32_t i0 = indices[3 * tri], i1 = indices[3 * tri + 1], i2 = indices[3 * tri + 2];
    const float b0 = 1 - b1 - b2;
    TexContext ctx;  // a point lookup: no footprint
    if (!uvs.empty()) {
        ctx.u = b0 * uvs[i0][0] + b1 * uvs[i1][0] + b2 * uvs[i2][0];
        ctx.v = b0 * uvs[i0][1] + b1 * uvs[i1][1] + b2 * uvs[i2][1];
    } else {
        ctx.u = b1 + b2;
        ctx.v = b2;
    }
    ctx.p = b0 * positions[i0] + b1 * positions[i1] + b2 * positions[i2];
    ctx.object = id;
    if (eval_texture(*scene, alpha, ctx).r == 0) return true;
    return shadow && eval_texture(*scene, shadow_alpha, ctx).r == 0;
}

std::optional<SurfaceSample> Primitive::sample_cone(const Vec3& ref, float u1, float u2) const {
    const float R = sphere_radius;
    if (!(R > 0)) return std::nullopt;
    const Vec3 to_c = sphere_center - ref;
    const float d2 = dot(to_c, to_c);
    if (!(d2 > R * R * 1.0001f)) return std::nullopt;
    const float dc = std::sqrt(d2);
    // The cone's half-angle: sin^2 = R^2 / d^2; 1 - cos written as sin^2 / (1 + cos), which
    // keeps its precision for small, distant spheres.
    const float sin2_max = R * R / d2, cos_max = std::sqrt(std::max(0.0f, 1 - sin2_max));
    const float one_minus_cos_max = sin2_max / (1 + cos_max);
    const float cos_t = 1 - u1 * one_minus_cos_max;
    const float sin2_t = std::max(0.0f, u1 * one_minus_cos_max * (1 + cos_t));
    const float phi = 2 * kPi * u2;
    const Frame f = Frame::from_z(to_c / dc);
    const Vec3 wi = f.to_world(
        Vec3(std::sqrt(sin2_t) * std::cos(phi), std::sqrt(sin2_t) * std::sin(phi), cos_t));
    // The nearer intersection along wi: t = d cos - sqrt(R^2 - d^2 sin^2).
    const float t = dc * cos_t - std::sqrt(std::max(0.0f, R * R - d2 * sin2_t));
    SurfaceSample out;
    out.p = ref + wi * t;
    const Vec3 n = normalize(out.p - sphere_center);
    out.n = flip ? -n : n;
    out.pdf = 1 / (2 * kPi * one_minus_cos_max);
    return out;
}

Partials SurfaceHit::local_partials() const {
    const Primitive& pr = *prim;
    if (pr.kind == Primitive::Kind::Triangles) {
        uint32_t i0 = pr.indices[3 * triangle], i1 = pr.indices[3 * triangle + 1],
                 i2 = pr.indices[3 * triangle + 2];
        std::array<float, 2> uv0{0, 0}, uv1{1, 0}, uv2{1, 1};
        if (!pr.uvs.empty()) {
            uv0 = pr.uvs[i0];
            uv1 = pr.uvs[i1];
            uv2 = pr.uvs[i2];
        }
        Vec3 dp02 = pr.positions[i0] - pr.positions[i2], dp12 = pr.positions[i1] - pr.positions[i2];
        float du02 = uv0[0] - uv2[0], dv02 = uv0[1] - uv2[1], du12 = uv1[0] - uv2[0],
              dv12 = uv1[1] - uv2[1];
        float det = du02 * dv12 - dv02 * du12;
        if (std::abs(det) < 1e-12f) {  // degenerate uv: any frame of the plane
            Frame f = Frame::from_z(normalize(cross(dp02, dp12)));
            return {f.s, f.t};
        }
        float inv = 1 / det;
        return {(dv12 * dp02 - dv02 * dp12) * inv, (du02 * dp12 - du12 * dp02) * inv};
    }
    const D3& p = p_object;
    D3 du, dv;
    if (pr.kind == Primitive::Kind::Sphere) {
        double r = pr.radius;
        double zr = std::sqrt(p[0] * p[0] + p[1] * p[1]);
        double cos_phi = zr > 0 ? p[0] / zr : 1, sin_phi = zr > 0 ? p[1] / zr : 0;
        double theta = std::acos(std::clamp(p[2] / r, -1.0, 1.0));
        double dtheta = pr.theta_zmax - pr.theta_zmin;
        du = {-pr.phi_max * p[1], pr.phi_max * p[0], 0};
        dv = {dtheta * p[2] * cos_phi, dtheta * p[2] * sin_phi, -dtheta * r * std::sin(theta)};
    } else {
        double r_hit = std::sqrt(p[0] * p[0] + p[1] * p[1]);
        du = {-pr.phi_max * p[1], pr.phi_max * p[0], 0};
        double k = r_hit > 0 ? (pr.inner_radius - pr.radius) / r_hit : 0;
        dv = {p[0] * k, p[1] * k, 0};
    }
    return {to_vec(xform_vector(pr.world_from_object, du)),
            to_vec(xform_vector(pr.world_from_object, dv))};
}

namespace {
// Barycentric differentials of triangle `tri`: (db1, db2) for a world offset dp in its plane.
std::pair<float, float> barycentric_offsets(const Primitive& pr, uint32_t tri, const Vec3& dp) {
    const Vec3& p0 = pr.positions[pr.indices[3 * tri]];
    Vec3 e1 = pr.positions[pr.indices[3 * tri + 1]] - p0,
         e2 = pr.positions[pr.indices[3 * tri + 2]] - p0;
    Vec3 n = cross(e1, e2);
    Vec3 l1 = cross(e2, n), l2 = cross(e1, n);
    return {dot(l1, dp) / dot(l1, e1), dot(l2, dp) / dot(l2, e2)};
}
}  // namespace

UvDelta SurfaceHit::local_uv_offset(const Vec3& dp) const {
    const Primitive& pr = *prim;
    if (pr.kind == Primitive::Kind::Triangles) {
        // Barycentric differentials: dB_k = L_k . dP, then (u,v) interpolates linearly.
        uint32_t i0 = pr.indices[3 * triangle], i1 = pr.indices[3 * triangle + 1],
                 i2 = pr.indices[3 * triangle + 2];
        const auto [db1, db2] = barycentric_offsets(pr, triangle, dp);
        std::array<float, 2> uv0{0, 0}, uv1{1, 0}, uv2{1, 1};
        if (!pr.uvs.empty()) {
            uv0 = pr.uvs[i0];
            uv1 = pr.uvs[i1];
            uv2 = pr.uvs[i2];
        }
        return {db1 * (uv1[0] - uv0[0]) + db2 * (uv2[0] - uv0[0]),
                db1 * (uv1[1] - uv0[1]) + db2 * (uv2[1] - uv0[1])};
    }
    // Least squares: [dpdu dpdv] (du dv)^T = dP.
    const auto [a, b] = local_partials();
    double aa = dot(a, a), ab = dot(a, b), bb = dot(b, b), ad = dot(a, dp), bd = dot(b, dp);
    double det = aa * bb - ab * ab;
    if (!(std::abs(det) > 0) || !std::isfinite(det)) return {};
    return {static_cast<float>((bb * ad - ab * bd) / det),
            static_cast<float>((aa * bd - ab * ad) / det)};
}

Vec3 SurfaceHit::local_normal_offset(const Vec3& dp) const {
    const Primitive& pr = *prim;
    if (pr.kind == Primitive::Kind::Triangles) {
        if (pr.normals.empty()) return Vec3(0, 0, 0);  // flat: the normal is constant
        uint32_t i0 = pr.indices[3 * triangle], i1 = pr.indices[3 * triangle + 1],
                 i2 = pr.indices[3 * triangle + 2];
        const auto [db1, db2] = barycentric_offsets(pr, triangle, dp);
        float b0 = 1 - b1 - b2;
        Vec3 ni = b0 * pr.normals[i0] + b1 * pr.normals[i1] + b2 * pr.normals[i2];
        Vec3 dn = (-db1 - db2) * pr.normals[i0] + db1 * pr.normals[i1] + db2 * pr.normals[i2];
        Vec3 d = unit_derivative(ni, dn);
        return pr.flip ? -d : d;
    }
    if (pr.kind == Primitive::Kind::Disk) return Vec3(0, 0, 0);
    // Sphere: n_obj = p_obj, so dn_obj = dp_obj; normals map with (object_from_world)^T.
    D3 dpo = xform_vector(pr.object_from_world, {dp.x, dp.y, dp.z});
    Vec3 n = to_vec(xform_normal(pr.object_from_world, p_object));
    Vec3 dn = to_vec(xform_normal(pr.object_from_world, dpo));
    Vec3 d = unit_derivative(n, dn);
    return pr.flip ? -d : d;
}

Partials SurfaceHit::partials() const {
    const Partials local = local_partials();
    if (!instance) return local;
    return {instance->to_world_vector(local.dpdu), instance->to_world_vector(local.dpdv)};
}

UvDelta SurfaceHit::uv_offset(const Vec3& dp) const {
    return local_uv_offset(instance ? instance->to_object_vector(dp) : dp);
}

Vec3 SurfaceHit::normal_offset(const Vec3& dp) const {
    if (!instance) return local_normal_offset(dp);
    // The world normal is normalize(M^-T n_object): its change follows from the object one's.
    const Vec3 dn = local_normal_offset(instance->to_object_vector(dp));
    return unit_derivative(instance->to_world_normal(ns_object), instance->to_world_normal(dn));
}

Vec3 Instance::to_world_point(const Vec3& p) const {
    return apply_point(world_from_object, p);
}
Vec3 Instance::to_world_vector(const Vec3& v) const {
    return apply_vector(world_from_object, v);
}
Vec3 Instance::to_world_normal(const Vec3& n) const {
    return apply_transpose(object_from_world, n);
}
Vec3 Instance::to_object_point(const Vec3& p) const {
    return apply_point(object_from_world, p);
}
Vec3 Instance::to_object_vector(const Vec3& v) const {
    return apply_vector(object_from_world, v);
}

}  // namespace cmam::render
