// render — the built scene: camera, film, textures, materials, lights and Embree geometry.
// Built from a pbrt::SceneDesc by build_scene() (build_scene.h); rendering reads it from many
// threads.
#pragma once

#include <cmam/texture/cmam.h>
#include <cmam/texture/filter.h>
#include <cmam/texture/footprint.h>
#include <cmam/texture/image.h>
#include <embree3/rtcore.h>

#include <array>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "render/envmap.h"
#include "render/footprint/method.h"
#include "render/huge_pages.h"
#include "render/math.h"
#include "render/medium.h"
#include "render/pixel_filter.h"

namespace cmam::render {

/// A camera ray: its origin and unit direction, and the weight of its sample (a realistic
/// camera's: 0 where the lens blocks the ray, whose origin and direction are then the camera's
/// position and axis).
struct CameraRay {
    Vec3 org, dir;
    float weight = 1;
};

class RealisticLens;

/// A Film's resolution where the scene gives none: pbrt-v3's (its CreateFilm), 1280x720.
constexpr int kDefaultFilmWidth = 1280, kDefaultFilmHeight = 720;

/// pbrt-v3 perspective camera (fov spans the shorter image axis; left-handed camera space), its
/// orthographic camera (the screen window is the view in camera units, rays along +z), or its
/// environment camera (the whole sphere in lat-long: theta = pi y / yres from camera +y,
/// phi = 2 pi x / xres from +x towards +z).
struct Camera {
    std::array<float, 12> world_from_camera{};  // 3x4
    bool orthographic = false;
    bool environment = false;
    float tan_half_fov = 1;            // perspective; 1 for orthographic
    float screen[4] = {-1, 1, -1, 1};  // xmin, xmax, ymin, ymax
    int xres = kDefaultFilmWidth, yres = kDefaultFilmHeight;
    // The perspective camera's thin lens (pbrt-v3's "lensradius" and "focaldistance", in camera
    // units): rays leave a point of the lens disc towards where the pinhole ray meets the plane
    // of focus. Radius 0 is the pinhole; the scene builder gives a lens to perspective cameras
    // only, so a camera with one is a perspective camera.
    float lens_radius = 0, focal_distance = 1e6f;
    // pbrt-v3's realistic camera (lens.h): rays traced through its lens system from a point of
    // its exit pupil, each with a weight. Its tan_half_fov is the paraxial one (ray cones' spread).
    std::shared_ptr<const RealisticLens> realistic;

    bool has_lens() const {
        return realistic || (lens_radius > 0 && !orthographic && !environment);
    }
    /// Primary ray through raster position (px, py) (pixels, y down). Direction is unit length.
    /// The pinhole's: with a lens, the ray from the lens's centre (a realistic camera's from
    /// the middle of its exit pupil's bound, which may be blocked: weight 0).
    CameraRay generate_ray(float px, float py) const;
    /// The ray through (px, py) from the lens point that the sample (lu, lv) in [0,1)^2 maps to
    /// (pbrt-v3's concentric mapping of the square onto the disc); generate_ray's without a lens.
    CameraRay generate_ray(float px, float py, float lu, float lv) const;
    /// The environment camera's directions through (px, py), (px + 1, py) and (px, py + 1),
    /// each generate_ray's bit for bit: the first two share theta's sine and cosine, the first
    /// and the last phi's (four of them where three rays apart take six).
    void environment_directions(float px, float py, Vec3 (&dirs)[3]) const;
};

/// Limits on the film and the samples a scene (or --spp) may ask for, checked in 64 bits before
/// anything is allocated; beyond them building the scene is an error naming the values.
constexpr int kMaxFilmSide = 65536;              // xresolution, yresolution
constexpr long long kMaxFilmPixels = 1LL << 28;  // xresolution x yresolution (16384^2)
constexpr long long kMaxSamplesPerPixel = 1LL << 20;
constexpr long long kMaxSamplesPerRow = 1LL << 26;  // samples per pixel x the film's larger side

/// Largest coordinate of a camera ray's origin (Embree's limit on ray coordinates is 1.8e18).
constexpr float kMaxRayCoordinate = 1e18f;

struct FilmSettings {
    int xres = kDefaultFilmWidth, yres = kDefaultFilmHeight;
    // The cropped pixel bounds [x0,x1) x [y0,y1).
    int x0 = 0, y0 = 0, x1 = kDefaultFilmWidth, y1 = kDefaultFilmHeight;
    std::string filename = "pbrt.exr";
    float scale = 1;     // pbrt-v3's Film "scale": every pixel's radiance is multiplied by it
    PixelFilter filter;  // PixelFilter (pbrt-v3's default: the box of radius 0.5)
    // pbrt-v3's Film "maxsampleluminance": a sample's radiance whose luminance (y of its RGB)
    // exceeds it is scaled down to it before it reaches the film (no limit by default).
    float max_sample_luminance = std::numeric_limits<float>::infinity();
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
};

struct SamplerSettings {
    int xsamples = 4, ysamples = 4;
    bool jitter = true;
    int spp() const { return xsamples * ysamples; }
};

/// A material or texture input: a constant, or the index of a texture node.
struct TexInput {
    int node = -1;
    Rgb value{};
};

struct TextureNode {
    enum class Kind {
        Constant,
        Image,
        Checkerboard,
        Scale,
        Mix,
        Bilerp,
        Uv,
        Dots,
        Checkerboard3D,
        Fbm,
        Wrinkled,
        Windy,
        Marble
    };
    /// pbrt-v3's 2-D texture mappings: (u,v) scaled and offset; the direction from the texture
    /// space origin as (theta / pi, phi / 2 pi) or as (angle, height) around z; or projections
    /// of the world-space point on two vectors.
    enum class Mapping { Uv, Spherical, Cylindrical, Planar };
    Kind kind = Kind::Constant;
    bool is_float = false;
    Rgb constant{};
    Mapping mapping = Mapping::Uv;
    float su = 1, sv = 1, du = 0, dv = 0;  // uv mapping (du, dv: planar's offsets too)
    Vec3 v1{1, 0, 0}, v2{0, 1, 0};         // planar mapping
    // Spherical and cylindrical mappings and the 3-D textures: world -> texture space (3x4).
    std::array<float, 12> texture_from_world{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    Rgb corners[4]{};                                 // Bilerp: v00, v01, v10, v11
    int octaves = 8;                                  // Fbm, Wrinkled, Marble
    float omega = 0.5f, scale = 1, variation = 0.2f;  // Fbm, Wrinkled (omega), Marble
    const texture::FilteredTexture* image = nullptr;  // Image: linear, scale applied
    texture::FilterOptions filter{};                  // Image: pbrt-v3's trilinear / maxanisotropy
    FootprintMethod lod = FootprintMethod::Differentials;  // Image, Checkerboard: footprint source
    bool closed_form = true;                               // Checkerboard: aamode "closedform"
    TexInput tex1, tex2, amount;                           // Checkerboard, Scale, Mix
};

/// Texture evaluation recurses through the nodes a texture names (scale, mix, checkerboard and
/// dots inputs) on a render thread's stack: a texture nesting more is an error where it is
/// declared (a chain of 6000 crashed a render thread).
constexpr int kMaxTextureDepth = 256;

struct FourierTable;  // render/fourier.h
struct BssrdfTable;   // render/subsurface.h

struct Material {
    enum class Type {
        Matte,
        Mirror,
        Glass,
        Plastic,
        Uber,
        Metal,
        Substrate,
        Translucent,
        Fourier,
        Hair,
        Disney,
        Subsurface,
        KdSubsurface,
        None,
        Mix
    };
    Type type = Type::Matte;
    TexInput kd{-1, Rgb(0.5f)}, ks, kr, kt, sigma, roughness, eta;
    TexInput k;  // metal: the conductor's absorption (eta is its index of refraction)
    // The microfacet roughness along v where it differs from `roughness` (along u): pbrt-v3's
    // "vroughness" beside "uroughness", an anisotropic distribution (equal to `roughness` else).
    TexInput vroughness;
    bool anisotropic = false;
    // Mix: pbrt-v3's blend, amount x the first material + (1 - amount) x the second (indices
    // into Scene::materials; -1 is the default matte).
    int mix[2] = {-1, -1};
    TexInput amount;
    // Fourier: pbrt-v3's tabulated BSDF (shared by the materials that name one file).
    std::shared_ptr<const FourierTable> fourier;
    bool remap_roughness = true;
    // Hair (pbrt-v3's): its absorption from sigma_a, from the colour it should have, or from its
    // melanin concentrations (eumelanin, pheomelanin), the first given; its roughnesses beta_m
    // and beta_n and the scales' tilt alpha in degrees (its index is `eta`).
    enum class HairAbsorption { SigmaA, Colour, Concentration };
    HairAbsorption hair_absorption = HairAbsorption::Concentration;
    TexInput hair_sigma_a, hair_colour, eumelanin{-1, Rgb(1.3f)}, pheomelanin;
    TexInput beta_m{-1, Rgb(0.3f)}, beta_n{-1, Rgb(0.3f)}, hair_alpha{-1, Rgb(2)};
    // Disney (pbrt-v3's "disney"): its base colour in `kd`, roughness in `roughness`, index in
    // `eta`, and the rest here (pbrt-v3's names and defaults); `thin` its thin-surface form.
    TexInput metallic, specular_tint, disney_anisotropic, sheen, sheen_tint{-1, Rgb(0.5f)},
        clearcoat, clearcoat_gloss{-1, Rgb(1)}, flatness, diff_trans{-1, Rgb(1)}, spec_trans;
    bool thin = false;
    // Subsurface (pbrt-v3's "subsurface" and "kdsubsurface", algorithms.md §26): a glass's BSDF
    // (kr, kt, eta, roughness) over a BSSRDF of absorption and scattering sss_sigma_a and
    // sss_sigma_s times sss_scale, or (kdsubsurface) those whose profile has the diffuse
    // reflectance kd and mean free path mfp times sss_scale; its profile's table for its phase
    // asymmetry and index (shared by the materials that have the same).
    TexInput sss_sigma_a, sss_sigma_s, mfp;
    // Uber (without specular lobes): its opacity, every lobe times it and the rest passed through
    // (node -1 and 1: opaque).
    TexInput opacity{-1, Rgb(1)};
    float sss_scale = 1;
    std::shared_ptr<const BssrdfTable> bssrdf;
    bool subsurface() const { return type == Type::Subsurface || type == Type::KdSubsurface; }
    // pbrt-v3's "bumpmap": a float texture displacing the surface along its shading normal;
    // node -1 and a constant: none (a constant displacement leaves the normal as it is here).
    TexInput bump;

    /// Whether shading it evaluates a texture node (a mix evaluates its amount and one of two
    /// materials): only then does a hit need its footprints in (u,v).
    bool reads_textures() const {
        if (type == Type::Mix || type == Type::Hair) return true;  // (hair reads v, too)
        for (const TexInput* in : {&kd,
                                   &ks,
                                   &kr,
                                   &kt,
                                   &sigma,
                                   &roughness,
                                   &vroughness,
                                   &eta,
                                   &k,
                                   &amount,
                                   &bump,
                                   &hair_sigma_a,
                                   &hair_colour,
                                   &eumelanin,
                                   &pheomelanin,
                                   &beta_m,
                                   &beta_n,
                                   &hair_alpha,
                                   &metallic,
                                   &specular_tint,
                                   &disney_anisotropic,
                                   &sheen,
                                   &sheen_tint,
                                   &clearcoat,
                                   &clearcoat_gloss,
                                   &flatness,
                                   &diff_trans,
                                   &spec_trans,
                                   &sss_sigma_a,
                                   &sss_sigma_s,
                                   &mfp,
                                   &opacity})
            if (in->node >= 0) return true;
        return false;
    }
};

struct Light {
    enum class Type { Point, Spot, Distant, Infinite, Area, Goniometric, Projection };
    Type type = Type::Point;
    Rgb intensity{};   // I for point/spot, L for distant/infinite/area (scale applied)
    Vec3 position{};   // point, spot
    Vec3 direction{};  // distant: towards the light; spot: axis (from -> to)
    float cos_total = 0, cos_falloff_start = 0;
    std::shared_ptr<const EnvironmentMap> env;  // infinite: its map ("mapname"), times intensity
    bool env_footprint = false;  // escaping rays look the map up over their differentials
    int prim = -1;               // area: the emitting primitive (index in Scene::primitives)
    bool two_sided = false;      // area: emits on both sides (otherwise along its normal only)
    std::shared_ptr<const LightImage> image;  // goniometric, projection: I times the image
    int samples = 1;  // infinite, area: shadow rays per shading point (averaged)
};

class Scene;

/// A point sampled on a surface: position, oriented geometric normal, and density (0: none).
struct SurfaceSample {
    Vec3 p, n;
    float pdf = 0;
};

/// Surface partial derivatives dP/du and dP/dv.
struct Partials {
    Vec3 dpdu, dpdv;
};

/// A change of surface (u,v).
struct UvDelta {
    float du = 0, dv = 0;
};

/// A ribbon curve's normal at u between the unit normals n0 and n1 at its segment's ends,
/// interpolated as pbrt-v3 interpolates them: spherically over the angle acos(clamp(n0 . n1, 0,
/// 1)) (linearly where that angle is 0).
inline Vec3 curve_normal(const Vec3& n0, const Vec3& n1, float u) {
    const float angle = std::acos(std::clamp(dot(n0, n1), 0.0f, 1.0f)), s = std::sin(angle);
    if (!(s > 1e-6f)) return (1 - u) * n0 + u * n1;
    return (std::sin((1 - u) * angle) / s) * n0 + (std::sin(u * angle) / s) * n1;
}

/// Everything the shading code needs about a geometry (indexed by Embree geomID).
struct Primitive {
    enum class Kind { Triangles, Sphere, Disk, Curves };
    Kind kind = Kind::Triangles;
    uint32_t id = 0;    // index in Scene::primitives (the textured object for the CMAM)
    int material = -1;  // -1 is the default matte
    bool flip = false;  // reverse_orientation xor transform swaps handedness
    // Triangles with normals: the interpolated normal is also the geometric normal (which side a
    // direction is on, where rays leave from, which plane carries the differentials), not the
    // facet's. pbrt-v3's hyperboloid, whose normal is that of the swept segment's
    // parameterisation and up to 80 degrees off the surface it intersects (algorithms.md §15).
    bool normals_geometric = false;
    // Triangles (world space)
    // (Large meshes are read at random by every hit: their arrays on 2 MiB pages.)
    HugeVector<Vec3> positions, normals;
    HugeVector<std::array<float, 2>> uvs;
    HugeVector<uint32_t> indices;
    // Triangles whose material reads textures: per triangle, the gradients of u and of v within
    // its plane, so that an offset dP in the plane moves (u,v) by (g[0] . dP, g[1] . dP) with no
    // division (made by make_uv_gradients; empty otherwise). algorithms.md §7.
    HugeVector<std::array<Vec3, 2>> uv_gradients;
    /// Makes uv_gradients (in double, rounded once to float): the barycentric differentials'
    /// basis divided through and combined with the vertices' (u,v), which local_uv_offsets
    /// otherwise does per hit (in float, for triangles without gradients).
    void make_uv_gradients();
    // Triangles read by the CMAM: per triangle, its (u,v) chart, a set of triangles joined
    // through edges whose two ends have the same position and the same (u,v) on both sides, so
    // that (u,v) is continuous across them; empty when the mesh is one chart. The CMAM takes
    // no neighbour from another chart (algorithms.md §6.3: across a seam (u,v) jumps).
    std::vector<uint32_t> uv_charts;
    /// Makes uv_charts (made by Scene::commit when a texture reads the CMAM).
    void make_uv_charts();
    uint32_t uv_chart(uint32_t tri) const { return uv_charts.empty() ? 0 : uv_charts[tri]; }
    // Curves (pbrt-v3's "curve" shape, algorithms.md §20): cubic Bezier segments, four control
    // points each (x, y, z and the radius, half the width, in the primitive's space: Embree's
    // vertex buffer, read where it is), the segment's widths at u = 0 and 1, and for ribbons the
    // normals at its ends (interpolated spherically, as pbrt-v3 does).
    enum class CurveType { Flat, Cylinder, Ribbon };
    CurveType curve_type = CurveType::Flat;
    std::vector<std::array<float, 4>> curve_points;
    std::vector<uint32_t> curve_first;  // each segment's first control point
    std::vector<std::array<float, 2>> curve_widths;
    std::vector<std::array<Vec3, 2>> curve_end_normals;
    // Embree's flat curves are ray-facing quads, this many per segment: four times as many as
    // pbrt-v3's refinement splits the most bent segment into (Builder::curve).
    float curve_tessellation = 4;
    // Quadrics: object_from_world / world_from_object as 3x4, double precision
    std::array<double, 12> object_from_world{}, world_from_object{};
    double radius = 1, zmin = -1, zmax = 1, theta_zmin = 0, theta_zmax = 0, phi_max = 0;
    // Its u is a longitude round the whole circle, period 1 (a sphere, disk, cylinder, cone,
    // paraboloid or hyperboloid with phimax 360, or a mesh whose charts meet themselves only
    // where u moves by whole units: make_uv_charts): the CMAM takes its neighbours across the
    // seam the short way round (algorithms.md §6.3). v_periodic: the same of v (a mesh's).
    bool u_periodic = false, v_periodic = false;
    double height = 0, inner_radius = 0;
    // Quadrics: the scale of a transform that keeps them round (a rotation, reflection or
    // uniform scale plus a translation), 0 for any other.
    double uniform_scale = 0;
    // Area light ("AreaLightSource" in the shape's scope): its index in Scene::lights, and for
    // triangles the cumulative areas that pick one by area.
    int area_light = -1;
    // Its MediumInterface: the media inside and outside the surface (indices into
    // Scene::media; -1: vacuum). Only where they differ is it a boundary between media; a ray
    // crossing any other surface stays in its medium (pbrt-v3).
    int medium_inside = -1, medium_outside = -1;
    bool medium_boundary() const { return medium_inside != medium_outside; }
    /// The medium of a ray leaving this surface along w (ng: the hit's geometric normal), the
    /// ray that reached it having been in `current`.
    int medium_after(int current, const Vec3& ng, const Vec3& w) const {
        if (!medium_boundary()) return current;
        return dot(w, ng) > 0 ? medium_outside : medium_inside;
    }
    std::vector<double> area_cdf;

    // Triangles: pbrt-v3's cut-out masks, float inputs; where one is 0 the surface is not there
    // (for every ray, and "shadowalpha" for shadow rays too). -1 with value 1: no mask.
    TexInput alpha{-1, Rgb(1)}, shadow_alpha{-1, Rgb(1)};
    const Scene* scene = nullptr;  // for evaluating the masks (set by Scene::commit)
    bool has_alpha() const {
        return alpha.node >= 0 || alpha.value.r != 1 || shadow_alpha.node >= 0 ||
               shadow_alpha.value.r != 1;
    }
    /// True when the masks remove the point at barycentrics (b1, b2) of triangle `tri` (for a
    /// shadow ray when `shadow`).
    bool cut_out(uint32_t tri, float b1, float b2, bool shadow) const;

    // A whole sphere under a transform that keeps it round: its world centre and radius
    // (0: not such a sphere), for sampling the cone it subtends.
    Vec3 sphere_center{};
    float sphere_radius = 0;

    /// A point on the surface, uniform by area, from uniform numbers in [0,1): its position,
    /// oriented geometric normal and density with respect to area (0 when none).
    SurfaceSample sample_area(float u1, float u2) const;
    /// For a point `ref` outside a whole round sphere: a point on it seen from `ref`, uniform in
    /// the cone of directions the sphere subtends, with its density with respect to solid angle.
    /// Nothing for other shapes and for points inside.
    std::optional<SurfaceSample> sample_cone(const Vec3& ref, float u1, float u2) const;
    /// The densities those give the point `p` of the surface (world space): sample_area's with
    /// respect to area, and sample_cone's from `ref` with respect to solid angle (nothing where
    /// sample_cone gives nothing).
    float area_pdf(const Vec3& p) const;
    std::optional<float> cone_pdf(const Vec3& ref) const;
};

/// An object's primitives, in the object's own space, with their own Embree scene, which every
/// instance of the object shares.
struct Object {
    std::vector<std::unique_ptr<Primitive>> primitives;
};

/// What primitives hold: triangles, quadrics (spheres and disks) and curve segments.
struct PrimitiveCounts {
    std::size_t triangles = 0, quadrics = 0, curve_segments = 0;
    std::size_t elements() const { return triangles + quadrics + curve_segments; }
};
/// Adds what `prims` hold to `counts`.
void count_primitives(const std::vector<std::unique_ptr<Primitive>>& prims,
                      PrimitiveCounts& counts);

/// An ObjectInstance: an object placed in the world by a transform (3x4, row-major).
struct Instance {
    uint32_t object = 0;  // index in Scene::objects
    std::array<float, 12> world_from_object{}, object_from_world{};
    /// World curvature = object curvature / curvature_scale (the cube root of the transform's
    /// determinant: exact for rotations with uniform scale).
    float curvature_scale = 1;
    /// Whether the transform keeps shapes round (a rotation, reflection or uniform scale plus a
    /// translation): then curvature_scale is exact, else a mean.
    bool uniform = true;
    uint32_t first_id = 0;  // the textured-object id of the object's first primitive here

    Vec3 to_world_point(const Vec3& p) const;
    Vec3 to_world_vector(const Vec3& v) const;
    Vec3 to_world_normal(const Vec3& n) const;  // not normalised
    Vec3 to_object_point(const Vec3& p) const;
    Vec3 to_object_vector(const Vec3& v) const;
};

/// A surface hit, in world space, oriented as pbrt-v3 orients it.
struct SurfaceHit {
    Vec3 p;
    Vec3 ng;  // geometric normal
    Vec3 ns;  // shading normal (same side as ng)
    float u = 0, v = 0;
    float t = 0;
    const Primitive* prim = nullptr;
    const Instance* instance = nullptr;  // the instance hit; nullptr outside objects
    uint32_t object_id = 0;              // the textured object (the CMAM's cache key): per instance
    Vec3 ns_object;                      // instances: the shading normal in the object's space
    uint32_t triangle = 0;               // triangles: the triangle index
    float b1 = 0, b2 = 0;                // triangles: barycentrics of vertices 1 and 2
    std::array<double, 3> p_object{};    // quadrics: the hit in object space
    Partials curve_partials;             // curves: dP/du and dP/dv in the primitive's space
    // A curve's error bound, pbrt-v3's: twice its width along each axis (world space). Rays
    // leave the hit that much further along the normal n, offset (|n_x| + |n_y| + |n_z|), as
    // pbrt-v3 offsets them: a curve's ray-facing pieces turn to face each new ray, and would be
    // met again by rays leaving it. 0 for other shapes.
    float offset = 0;
    bool uv_pending = false;  // quadrics: u, v not computed yet (ensure_uv)

    /// Computes u and v when the hit was found without them (a quadric's cost an atan2 and an
    /// acos, which a hit whose shading reads no texture does without).
    void ensure_uv() {
        if (uv_pending) compute_quadric_uv();
    }
    void compute_quadric_uv();

    /// Surface partial derivatives dP/du and dP/dv in world space.
    Partials partials() const;
    /// (du, dv) for a world-space offset dP in the tangent plane (barycentric differentials on
    /// triangles, least squares on dP/du, dP/dv elsewhere).
    UvDelta uv_offset(const Vec3& dp) const;
    /// Change of the (unit) shading normal for a world-space offset dP along the surface.
    Vec3 normal_offset(const Vec3& dp) const;
    /// uv_offset and normal_offset of two offsets at once (a footprint's two axes): what they
    /// share (the triangle's barycentric basis, the quadric's partials or normal) is computed
    /// once. The results equal the single calls' bit for bit.
    std::array<UvDelta, 2> uv_offsets(const Vec3& dp1, const Vec3& dp2) const;
    std::array<Vec3, 2> normal_offsets(const Vec3& dp1, const Vec3& dp2) const;
    /// The same written into `o1`, `o2` (a returned pair, stored by the caller as two halves and
    /// read back whole, stalled on its stores). A triangle with (u,v) gradients outside an
    /// instance (most textured hits) takes their four dot products here, inline: through the
    /// general path's calls and returned arrays they cost 5% of a 64-spp render of a textured
    /// floor.
    void uv_offsets(const Vec3& dp1, const Vec3& dp2, UvDelta& o1, UvDelta& o2) const {
        if (!instance && prim->kind == Primitive::Kind::Triangles && !prim->uv_gradients.empty()) {
            const std::array<Vec3, 2>& g = prim->uv_gradients[triangle];
            o1 = gradient_uv_offset(g, dp1);
            o2 = gradient_uv_offset(g, dp2);
            return;
        }
        general_uv_offsets(dp1, dp2, o1, o2);
    }
    /// The (u,v) offset of dP on a triangle with gradients g (Primitive::uv_gradients).
    static UvDelta gradient_uv_offset(const std::array<Vec3, 2>& g, const Vec3& dp) {
        return {dot(g[0], dp), dot(g[1], dp)};
    }
    /// uv_offsets' other cases: instances, triangles without gradients, quadrics.
    void general_uv_offsets(const Vec3& dp1, const Vec3& dp2, UvDelta& o1, UvDelta& o2) const;
    void normal_offsets(const Vec3& dp1, const Vec3& dp2, Vec3& o1, Vec3& o2) const;

    // The same in the primitive's own space (an instance's object space; else the world).
    Partials local_partials() const;
    UvDelta local_uv_offset(const Vec3& dp) const;
    Vec3 local_normal_offset(const Vec3& dp) const;
    template <std::size_t N>
    std::array<UvDelta, N> local_uv_offsets(const std::array<Vec3, N>& dp) const;
    template <std::size_t N>
    std::array<Vec3, N> local_normal_offsets(const std::array<Vec3, N>& dp) const;
};

struct RenderStats;

/// The deepest specular recursion a scene may ask for ("integer maxdepth"): the integrator
/// recurses on the stack, so a larger maxdepth is used at this limit, with a warning.
constexpr int kMaxDepthLimit = 100;

class Scene {
  public:
    Scene();
    ~Scene();
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    Camera camera;
    FilmSettings film;
    SamplerSettings sampler;
    int max_depth = 5;  // at most kMaxDepthLimit
    // pbrt-v3's "path" integrator: at every non-specular hit one more bounce drawn from the BSDF
    // (algorithms.md §18), continued past three bounces by Russian roulette below rr_threshold.
    bool path_tracing = false;
    float rr_threshold = 1;
    // pbrt-v3's "bdpt" and "mlt" integrators (lighttrace.h, algorithms.md §27): the path tracer,
    // and light paths from the point, spot, goniometric, projection and distant lights whose
    // first bounce is specular, joined to the camera at their non-specular hits (the caustics no
    // camera path reaches). Set only where light_tracing_camera accepts the camera and the scene
    // has no media; path_tracing is set too.
    bool light_tracing = false;
    // pbrt-v3's "ambientocclusion" integrator (algorithms.md §23): at each camera ray's first
    // hit, `ao_samples` directions over the hemisphere of the geometric normal on the viewer's
    // side, cosine-weighted (`ao_cosine`) or uniform; a pixel's value is pi times the weighted
    // share that nothing occludes. Nothing else is rendered: no lights, no reflections.
    bool ambient_occlusion = false;
    int ao_samples = 64;
    bool ao_cosine = true;
    // pbrt-v3's "sppm" integrator, stochastic progressive photon mapping (sppm.h, algorithms.md
    // §25): `iterations` passes, each a visible point per pixel and `photons` photons (0: one
    // per pixel of the cropped film), gathered within a radius per pixel that starts at
    // `radius` and shrinks as photons arrive. path_tracing stays set: an AOV render, which
    // reads no photons, traces paths.
    struct Sppm {
        bool on = false;
        int iterations = 64;
        long long photons = 0;
        float radius = 1;
    } sppm;
    // Participating media (pbrt-v3's volpath, bdpt and mlt integrators render them; the others
    // do not): `volumetric` when the integrator does and the scene has some.
    std::vector<Medium> media;
    int camera_medium = -1;  // the medium the camera is in (-1: vacuum)
    bool volumetric = false;
    // The radius of the sphere about the world's bounding box (pbrt-v3's worldRadius), set by
    // commit(): a distant or infinite light's shadow ray through media ends 2 world_radius away,
    // where pbrt-v3 puts the light's point.
    float world_radius = 0;
    Vec3 world_center{};  // that sphere's centre (pbrt-v3's worldCenter)
    std::vector<TextureNode> textures;
    std::vector<Material> materials;
    std::vector<Light> lights;
    std::vector<std::unique_ptr<Primitive>> primitives;  // outside objects
    std::vector<Object> objects;                         // ObjectBegin ... ObjectEnd
    std::vector<Instance> instances;                     // ObjectInstance
    /// Object instances built in place (their shapes in `primitives`, placed by the instance's
    /// transform) rather than instanced, and the objects they place (BuildOptions::
    /// flatten_instances).
    std::size_t instances_in_place = 0, objects_in_place = 0;
    std::map<std::string, std::unique_ptr<texture::FilteredTexture>>
        images;  // loaded once per settings
    Material default_material;
    TagPolicy tags = TagPolicy::Scanline;  // CMAM ray tagging
    // The footprint methods some texture (or environment map) uses: the tracer runs only
    // their producers.
    FootprintMethods footprint_methods;
    texture::CmamOptions cmam;  // CMAM policies (the filter comes from each texture)

    /// Creates the Embree scene from `primitives` and `instances` (one Embree scene per object,
    /// shared by its instances); call once after filling them.
    void commit();
    /// Nearest hit along org + t dir, t in (tmin, tmax); nothing when the ray hits nothing. A
    /// ray whose origin or direction is not finite (NaN or infinite parameters or texels upstream)
    /// is never given to Embree: it hits nothing here and is occluded below. Without `uv` a
    /// quadric's (u,v) is left to SurfaceHit::ensure_uv.
    std::optional<SurfaceHit> intersect(const Vec3& org, const Vec3& dir, float tmin, float tmax,
                                        bool uv = true) const;
    /// The nearest hits of up to kPacketSize rays along org[i] + t dir[i], t in (0, infinity),
    /// found together (Embree's packet traversal: a node's test is shared by the rays that reach
    /// it, which pays for coherent rays such as a camera's). hits[i] is what intersect(org[i],
    /// dir[i], 0, infinity) would give, not finite rays included.
    static constexpr int kPacketSize = 16;
    void intersect_packet(const Vec3* org, const Vec3* dir, int n, std::optional<SurfaceHit>* hits,
                          bool uv = true) const;
    /// Rays Embree traces as one packet within intersect_packet and occluded_packet: 16 where
    /// Embree has native 16-ray packets (AVX-512), else 8 where it has native 8-ray ones (AVX2),
    /// two packets per kPacketSize rays. The hits are the same either way; set_packet_width (8
    /// or 16) chooses one, for tests and comparisons.
    int packet_width() const { return m_packet_width; }
    void set_packet_width(int width);
    /// True when anything lies along org + t dir, t in (tmin, tmax).
    bool occluded(const Vec3& org, const Vec3& dir, float tmin, float tmax) const;
    /// occluded(org[i], dir[i], 0, tmax[i]) into occluded[i] for up to kPacketSize rays, traced
    /// together as one packet.
    void occluded_packet(const Vec3* org, const Vec3* dir, const float* tmax, int n,
                         bool* occluded) const;
    RTCScene embree_scene() const { return m_scene; }
    std::size_t texture_memory_bytes() const;

  private:
    // The surface hit of a ray from Embree's hit record and distance, written into `h`, a
    // default SurfaceHit in the caller's slot (a returned hit was copied there, and the copy
    // waited on the stores that had just written it). Without `uv` a quadric's u and v are left
    // to SurfaceHit::ensure_uv.
    void surface_hit(const Vec3& org, const Vec3& dir, float t, const RTCHit& hit, bool uv,
                     SurfaceHit& h) const;

    template <int K>
    void intersect_lanes(const Vec3* org, const Vec3* dir, int n, std::optional<SurfaceHit>* hits,
                         bool uv) const;
    template <int K>
    void occluded_lanes(const Vec3* org, const Vec3* dir, const float* tmax, int n,
                        bool* occluded) const;

    RTCDevice m_device = nullptr;
    int m_packet_width = 16;  // rays Embree traces as one packet: 16, or 8 (two per kPacketSize)
    RTCScene m_scene = nullptr;
    std::vector<RTCScene> m_object_scenes;
};

}  // namespace cmam::render
