// render — texture evaluation and BSDFs (pbrt-v3's matte, mirror, glass, plastic).
// Every image lookup goes through lookup_image(): the one place where a footprint and a ray tag
// reach the filtering library.
#pragma once

#include <forward_list>
#include <memory>
#include <optional>

#include "render/footprint/cmam_caches.h"
#include "render/footprint/footprint.h"
#include "render/fourier.h"
#include "render/hair.h"
#include "render/scene.h"

namespace cmam::render {

/// Image lookups per filter (index: texture::FilterKind) plus those made without a footprint.
struct LookupCounts {
    uint64_t by_filter[texture::kFilterKinds] = {};
    uint64_t point_sampled = 0;  // no footprint: bilinear at level 0 whatever the filter
    uint64_t non_finite = 0;     // non-finite uv or footprint: the texture mean was returned
    uint64_t cmam_2d_without_above = 0;  // 2-D CMAM lookups that had no sample above
};

/// What a texture lookup knows about the shading point.
struct TexContext {
    float u = 0, v = 0;  // surface (u,v) of the hit
    Vec3 p{};            // the hit in world space (3-D textures and the non-uv mappings)
    // The footprint producers' footprints at the hit, with the ray's tag and path (the CMAM's).
    HitFootprint footprints;
    LookupCounts* counts = nullptr;     // optional statistics
    uint32_t object = 0;                // the primitive hit (the CMAM's textured object)
    CmamRowState* cmam = nullptr;       // the strip's CMAM caches (null: no CMAM)
    CmamRecord* cmam_record = nullptr;  // optional: what a CMAM lookup filtered
    bool u_periodic = false;            // the surface's u has period 1 (Primitive::u_periodic)
    bool v_periodic = false;            // its v has period 1 (Primitive::v_periodic)
};

/// The texture lookup seam: filtered value of `image` at texture coordinates (s,t), with the
/// footprint mapped through the same (u,v) -> (s,t) scale.
texture::Texel lookup_image(const texture::FilteredTexture& image,
                            const texture::FilterOptions& filter, double s, double t,
                            const texture::Footprint& footprint, LookupCounts* counts);

/// A ray cone's elliptical cross-section with diameters a, b has the second moments of the
/// parallelogram with sides (sqrt 3 / 2) a, (sqrt 3 / 2) b: what the area filter integrates.
inline constexpr double kConeToArea = 0.86602540378443865;

/// The footprint `n` asks for (its lod: differentials, cones or anisotropic cones), scaled by
/// the node's uv mapping like the lookup point; None for point sampling and the CMAM.
texture::Footprint node_footprint(const TextureNode& n, const TexContext& ctx);

/// The footprint an image or checkerboard node's lookup uses, in its (s,t) units: the
/// node_footprint of a uv mapping, or the image of the lod's world-space footprint under a
/// spherical, cylindrical or planar one (none for point sampling and the CMAM).
texture::Footprint lookup_footprint(const TextureNode& n, const TexContext& ctx);

/// A texture node's value at a shading point; float textures return it in all three channels.
Rgb eval_texture_node(const Scene& scene, int node, const TexContext& ctx);

/// Evaluates a texture input (constant or node) at a shading point: a constant inline (most of
/// a material's inputs, such as a matte's sigma, read at every hit), a node through
/// eval_texture_node.
inline Rgb eval_texture(const Scene& scene, const TexInput& in, const TexContext& ctx) {
    return in.node < 0 ? in.value : eval_texture_node(scene, in.node, ctx);
}

/// The shading normal of `hit` under pbrt-v3's bump mapping by the float texture `bump`: the
/// surface displaced by d(u,v) along its normal, d's derivatives taken over half the ray
/// differentials' (u,v) extent (`du`, `dv`; 0: pbrt-v3's 0.0005). On the geometric normal's side.
Vec3 bump_normal(const Scene& scene, const TexInput& bump, const SurfaceHit& hit,
                 const TexContext& ctx, float du, float dv);

/// pbrt-v3's Disney BSDF at a shading point (algorithms.md §24): its lobes' colours and
/// parameters in the shading frame. The lobes present are pbrt-v3's components, whatever their
/// weights: the diffuse group (diffuse, a thin surface's fake subsurface, retro-reflection,
/// sheen) where the diffuse weight is positive, the specular reflection always, the clearcoat
/// where it is positive, a thin surface's diffuse transmission.
struct DisneyModel {
    bool diffuse_group = false, thin = false, has_sheen = false, has_clearcoat = false;
    Rgb base;  // the base colour (the texture AOV's)
    Rgb diffuse, fake_ss, retro, sheen, lambert_t;
    float roughness = 0.5f, ax = 0.25f, ay = 0.25f;  // the specular lobe's distribution
    Rgb cspec0;  // its Fresnel term's colour at normal incidence
    float metallic = 0, eta = 1.5f;
    float clearcoat = 0, gloss = 0.1f;
    // Rough transmission ("spectrans" > 0): weight `transmit`, from air into `eta`, its
    // distribution tax, tay (a thin surface's from the roughness scaled by its index, with
    // pbrt-v3's correlated masking; otherwise the specular lobe's, uncorrelated).
    bool has_transmission = false;
    Rgb transmit;
    float tax = 0.25f, tay = 0.25f;
    /// The diffuse-type components (diffuse, a thin surface's fake subsurface, retro, sheen).
    int diffuse_components() const {
        return diffuse_group ? (thin ? 2 : 1) + 1 + int(has_sheen) : 0;
    }
    int components() const {
        return diffuse_components() + 1 + int(has_clearcoat) + int(has_transmission) + int(thin);
    }
};
/// Its value for directions wo, wi in the shading frame: the reflection lobes where `reflect`
/// (the two on one side of the geometric normal), the transmission lobe otherwise.
Rgb disney_f(const DisneyModel& m, const Vec3& wo, const Vec3& wi, bool reflect);
/// pbrt-v3's density: the mean of its components' densities.
float disney_pdf(const DisneyModel& m, const Vec3& wo, const Vec3& wi);
/// A direction drawn from one component chosen evenly by u0, with (u1, u2); none where it fails.
std::optional<Vec3> disney_sample(const DisneyModel& m, const Vec3& wo, float u0, float u1,
                                  float u2);

/// A BSDF instantiated at a hit (pbrt-v3 BxDF combinations of the supported materials).
struct Bsdf {
    Frame frame;  // shading frame, z = shading normal (s along dp/du when anisotropic)
    Vec3 ng;      // geometric normal
    // Diffuse lobe (Lambertian, or Oren-Nayar when on_b != 0)
    Rgb kd{};
    float on_a = 1, on_b = 0;
    // Microfacet reflection: Trowbridge-Reitz with a dielectric Fresnel term from lobe_eta_i to
    // lobe_eta_t, as pbrt-v3 makes it: plastic's from 1.5 to 1 (so it reaches 1 past about 42
    // degrees), uber's from 1 to its eta.
    Rgb ks{};
    float alpha = 0;    // along the frame's s (the surface's dp/du) when anisotropic
    float alpha_y = 0;  // along t, when anisotropic (pbrt-v3's "uroughness" and "vroughness")
    bool anisotropic = false;
    float lobe_eta_i = 1.5f, lobe_eta_t = 1.0f;
    // Specular lobes
    Rgb kr{}, kt{};
    bool fresnel_noop = false;  // mirror
    float eta = 1.5f;           // glass
    // Metal: the microfacet lobe's Fresnel term is a conductor's of index eta + i k, per channel
    // (ks is then 1), instead of the dielectric's.
    bool conductor = false;
    Rgb conductor_eta{}, conductor_k{};
    // Microfacet transmission (pbrt-v3's rough glass): the glossy lobe's distribution, through the
    // dielectric boundary from lobe_eta_i (on the side the shading normal points to) to
    // lobe_eta_t, weighted by 1 - Fresnel and by kt_rough.
    Rgb kt_rough{};
    // Lambertian transmission (pbrt-v3's translucent): kt_diffuse / pi on the far side.
    Rgb kt_diffuse{};
    // Where a path leaves a subsurface material (pbrt-v3's SeparableBSSRDFAdapter): the diffuse
    // lobe weighted by the transmittance into the material of index sss_eta, kd (1 - F(cos
    // theta_i)) / pi (kd = eta^2 / c, c normalising; 0: an ordinary diffuse lobe).
    float sss_eta = 0;
    // pbrt-v3's FresnelBlend (substrate) in place of the diffuse and glossy lobes: kd the base's
    // colour, ks the coat's reflectance at normal incidence (Schlick's approximation), the glossy
    // lobe's distribution; its value times blend_scale (a mix's weight).
    bool fresnel_blend = false;
    Rgb blend_scale{1, 1, 1};
    // pbrt-v3's Fourier BSDF in place of the other non-specular lobes (its table), its value
    // times fourier_scale (a mix's weight).
    const FourierTable* fourier = nullptr;
    Rgb fourier_scale{1, 1, 1};
    // pbrt-v3's hair BSDF in place of the other non-specular lobes (hair.h; the frame's s along
    // the fibre, dp/du), its value times hair_scale (a mix's weight).
    bool hair = false;
    HairModel hair_model;
    Rgb hair_scale{1, 1, 1};
    // pbrt-v3's Disney BSDF in place of the other non-specular lobes (its model, made per shading
    // point), its value times disney_scale (a mix's weight).
    std::shared_ptr<const DisneyModel> disney;
    Rgb disney_scale{1, 1, 1};
    // Non-specular lobes of a mix's other material that do not fit this Bsdf (add), each Bsdf of
    // the chain in its own frame about the same shading normal: f, pdf and sample take the whole
    // chain, as pbrt-v3's BSDF takes all its components. Null for a single material.
    Bsdf* layer = nullptr;

    bool has_diffuse() const { return fresnel_blend || !kd.is_black(); }
    bool has_glossy() const { return fresnel_blend || !ks.is_black(); }
    bool has_transmission() const { return !kt_rough.is_black(); }
    bool has_diffuse_transmission() const { return !kt_diffuse.is_black(); }
    bool has_nonspecular() const {
        return has_diffuse() || has_glossy() || has_transmission() || has_diffuse_transmission() ||
               fourier || hair || disney || (layer && layer->has_nonspecular());
    }

    /// Every lobe times w, the layers' too (a mix material's weight for one of its materials).
    void scale(const Rgb& w);

    /// Whether add(o) can hold this BSDF plus `o` (both built at one hit): the same shading
    /// normal, and specular lobes that fit one Bsdf (the integrator follows those of this one
    /// only): a mirror's reflection (no Fresnel term) not beside a glass's, one specular index.
    bool takes(const Bsdf& o) const;
    /// This BSDF plus `o` (takes(o) must hold), as pbrt-v3's mix adds its materials' lobes into
    /// one BSDF: into this Bsdf where no kind of lobe is in both with different parameters
    /// (Oren-Nayar's sigma, a microfacet distribution or Fresnel term, two FresnelBlends of
    /// different colours), lobes of one kind with the same parameters adding their weights;
    /// otherwise o's specular lobes are added here and the rest of o becomes a layer, kept in
    /// `layers` (which must outlive this Bsdf). o's own layers go on the chain either way.
    void add(const Bsdf& o, std::forward_list<Bsdf>& layers);

    /// BSDF value for world directions (pbrt-v3 BSDF::f: only non-specular lobes).
    Rgb f(const Vec3& wo, const Vec3& wi) const;

    /// What f computes of the outgoing direction alone, computed once for a shading point's
    /// light samples (f(out, wi) equals f(wo, wi) bit for bit).
    struct Outgoing {
        Vec3 local;         // in the shading frame
        float w_ng;         // w . ng
        float smith_r;      // sqrt(cos^2 + alpha^2 sin^2) of wo: its Smith Lambda is
                            // (smith_r / |cos| - 1) / 2 (microfacet BSDFs only)
        HairOutgoing hair;  // wo's angles and refracted path (hair BSDFs only)
    };
    Outgoing outgoing(const Vec3& wo) const;
    Rgb f(const Outgoing& wo, const Vec3& wi) const;

    /// A direction drawn from the non-specular lobes for the outgoing direction `o`, from three
    /// uniform numbers: the lobe (glossy, diffuse, rough or diffuse transmission, evenly among
    /// those there are, as pbrt-v3 picks among its components), then a cosine-weighted direction
    /// about the shading normal (on wo's side, or the other for the diffuse transmission), or a
    /// reflection or a refraction about a Trowbridge-Reitz microfacet normal.
    /// `pdf` is the density of the whole mixture in solid angle (0: nothing drawn), `f` the BSDF
    /// there.
    using Sample = DirectionSample;
    Sample sample(const Outgoing& o, float u0, float u1, float u2) const;
    /// The density sample() draws wi with (wo, wi in world space).
    float pdf(const Outgoing& o, const Vec3& wi) const;

  private:
    bool fits(const Bsdf& o) const;  // whether o's lobes fit into this Bsdf's (add)
    int own_lobes() const;           // the non-specular lobes of this Bsdf, not its layers'
    // f, pdf and sample of this Bsdf's own lobes (the public ones add the layers').
    Rgb own_f(const Outgoing& o, const Vec3& wi_w) const;
    Sample own_sample(const Outgoing& o, float u0, float u1, float u2) const;
    float pdf_local(const Outgoing& o, const Vec3& wi) const;     // the same in the shading frame
    Rgb blend_f(const Vec3& wo, const Vec3& wi) const;            // FresnelBlend, shading frame
    Rgb transmission_f(const Outgoing& o, const Vec3& wi) const;  // wi in the shading frame
};

/// Builds the BSDF of `material` at `hit`; returns none for material "none" (and "mix", whose
/// materials the integrator builds and adds: Bsdf::add).
std::optional<Bsdf> make_bsdf(const Scene& scene, const Material& material, const SurfaceHit& hit,
                              const TexContext& ctx);

/// Unpolarised Fresnel reflectance of a dielectric interface (pbrt-v3 FrDielectric).
float fresnel_dielectric(float cos_theta_i, float eta_i, float eta_t);

/// Unpolarised Fresnel reflectance of a conductor of complex index eta + i k seen from air, per
/// channel (pbrt-v3 FrConductor); |cos_theta_i| is used.
Rgb fresnel_conductor(float cos_theta_i, const Rgb& eta, const Rgb& k);

/// Refracts `wi` (pointing away from the surface) through normal `n` on its side with relative
/// index eta = eta_i/eta_t; false on total internal reflection.
std::optional<Vec3> refract(const Vec3& wi, const Vec3& n, float eta);

}  // namespace cmam::render
