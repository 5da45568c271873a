// Object instancing: an object's primitives are built once in its own space and placed by each
// instance's transform; images match the same shapes written out with composed transforms.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/integrator.h"
#include "render/scene.h"

using namespace cmam;
using namespace cmam::render;

namespace {

const std::string kHeader = R"(
LookAt 0 1.2 4  0 0.8 0  0 1 0
Camera "perspective" "float fov" 60
Film "image" "integer xresolution" 96 "integer yresolution" 64
Integrator "whitted"
WorldBegin
LightSource "distant" "point from" [1 3 2] "point to" [0 0 0] "color L" [2 2 2]
LightSource "infinite" "color L" [0.3 0.3 0.3]
Texture "bricks" "spectrum" "imagemap" "string filename" ")" +
                            std::string(CMAM_SCENES_DIR) +
                            R"(/textures/bricks.png" "float uscale" 4 "float vscale" 4
Material "matte" "rgb Kd" [0.4 0.4 0.4]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-8 0 -8  8 0 -8  8 0 8  -8 0 8]
Material "matte" "texture Kd" "bricks"
)";

// The object's shapes, each after its own transform inside the definition.
const std::string kShapes = R"(
AttributeBegin
  Translate 0 0.5 0
  Rotate 30 0 1 0
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
      "point P" [-0.5 0 0.5  0.5 0 0.5  0.5 1 0.5  -0.5 1 0.5]
      "normal N" [0 0.2 1  0 0.2 1  0 -0.2 1  0 -0.2 1]
      "float uv" [0 0 1 0 1 1 0 1]
AttributeEnd
AttributeBegin
  Translate 0 1.3 0
  Shape "sphere" "float radius" 0.3
AttributeEnd
)";

// Instance transforms: plain, rotated and uniformly scaled, non-uniform and mirrored.
const char* const kPlacements[] = {
    "Translate -1.8 0 0",
    "Translate 0 0 -0.5 Rotate -50 0 1 0 Scale 1.3 1.3 1.3",
    "Translate 1.8 0 0.3 Scale -1 0.8 1.2",
};

std::string instanced_scene() {
    std::string s = kHeader + "ObjectBegin \"thing\"\n" + kShapes + "ObjectEnd\n";
    for (const char* p : kPlacements)
        s += std::string("AttributeBegin\n") + p + "\nObjectInstance \"thing\"\nAttributeEnd\n";
    return s + "WorldEnd\n";
}

std::string flattened_scene() {
    std::string s = kHeader;
    for (const char* p : kPlacements)
        s += std::string("AttributeBegin\n") + p + kShapes + "AttributeEnd\n";
    return s + "WorldEnd\n";
}

// `flatten`: BuildOptions::flatten_instances (0: every instance kept an instance).
std::vector<float> render_text(const std::string& text, std::optional<FootprintMethod> lod,
                               texture::FilterKind filter, std::size_t flatten = 0) {
    BuildOptions bo;
    bo.spp_override = 4;
    bo.lod = lod;
    bo.filter = filter;
    bo.flatten_instances = flatten;
    auto s = build_scene(pbrt::parse_string(text, "t.pbrt"), bo, {});
    return render::render(*s, {}, nullptr).rgb;
}

BuildOptions kept_instances() {
    BuildOptions bo;
    bo.flatten_instances = 0;
    return bo;
}

// Relative RMS difference of two images (over b's mean), which must be bright enough to say so.
double relative_rms(const std::vector<float>& a, const std::vector<float>& b) {
    EXPECT_EQ(a.size(), b.size());
    double se = 0, mean = 0;
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
        se += (a[i] - b[i]) * double(a[i] - b[i]);
        mean += b[i];
    }
    mean /= b.size();
    EXPECT_GT(mean, 0.05);
    return std::sqrt(se / a.size()) / mean;
}

}  // namespace

TEST(Instancing, ObjectIsBuiltOnceAndPlacedByEachInstance) {
    auto s = build_scene(pbrt::parse_string(instanced_scene(), "t.pbrt"), kept_instances(), {});
    EXPECT_EQ(s->primitives.size(), 1u);  // the floor
    ASSERT_EQ(s->objects.size(), 1u);
    EXPECT_EQ(s->objects[0].primitives.size(), 2u);
    ASSERT_EQ(s->instances.size(), 3u);
    // Textured-object ids differ per instance (each has its own CMAM caches).
    EXPECT_EQ(s->instances[0].first_id, 1u);
    EXPECT_EQ(s->instances[1].first_id, 3u);
    EXPECT_EQ(s->instances[2].first_id, 5u);
    // A ray down onto the first instance's sphere hits it at the top, in the world.
    std::optional<SurfaceHit> hit = s->intersect(Vec3(-1.8f, 5, 0), Vec3(0, -1, 0), 0, 100);
    ASSERT_TRUE(hit.has_value());
    SurfaceHit h = *hit;
    EXPECT_EQ(h.instance, &s->instances[0]);
    EXPECT_EQ(h.object_id, 2u);
    EXPECT_NEAR(h.p.y, 1.6, 1e-5);
    EXPECT_NEAR(h.ns.y, 1, 1e-5);
    // The mirrored, non-uniformly scaled instance: the sphere's top at 0.8 * 1.6.
    hit = s->intersect(Vec3(1.8f, 5, 0.3f), Vec3(0, -1, 0), 0, 100);
    ASSERT_TRUE(hit.has_value());
    h = *hit;
    EXPECT_EQ(h.instance, &s->instances[2]);
    EXPECT_NEAR(h.p.y, 0.8 * 1.6, 1e-5);
    EXPECT_NEAR(h.ng.y, 1, 1e-5);
}

// Every footprint producer sees the instance's transform: differentials (partials, uv offsets,
// normal offsets), cones (curvature) and the CMAM (per-instance caches). Images agree with the
// flattened scene to float precision of the transforms.
TEST(Instancing, ImagesMatchTheFlattenedScene) {
    using texture::FilterKind;
    struct Case {
        std::optional<FootprintMethod> lod;
        FilterKind filter;
    };
    for (const Case& c : {Case{FootprintMethod::Differentials, FilterKind::Ewa},
                          Case{FootprintMethod::Cones, FilterKind::Trilinear},
                          Case{FootprintMethod::ConesAniso, FilterKind::Area},
                          Case{FootprintMethod::Cmam, FilterKind::Sat},
                          Case{FootprintMethod::None, FilterKind::Trilinear}}) {
        SCOPED_TRACE(std::string(to_string(*c.lod)) + "+" +
                     std::string(texture::to_string(c.filter)));
        const std::vector<float> a = render_text(instanced_scene(), c.lod, c.filter);
        const std::vector<float> b = render_text(flattened_scene(), c.lod, c.filter);
        EXPECT_LT(relative_rms(a, b), 2e-4);
        // Built in place, the instances are the flattened scene's shapes (their transforms
        // composed in another order: float precision again).
        const std::vector<float> in_place =
            render_text(instanced_scene(), c.lod, c.filter, BuildOptions{}.flatten_instances);
        EXPECT_LT(relative_rms(in_place, b), 2e-4);
    }
}

// Which instances are built in place: an object used once always; one used more often while
// all its uses, and the scene's copies together, stay within the budget of triangles; none with
// the budget 0; never an object with curves.
TEST(Instancing, CheapInstancesAreBuiltInPlaceWithinTheBudget) {
    auto build = [](const std::string& text, std::size_t budget) {
        BuildOptions bo;
        bo.flatten_instances = budget;
        return build_scene(pbrt::parse_string(text, "t.pbrt"), bo, {});
    };
    // The object: two triangles and a sphere, 3 elements; used three times, 9.
    for (std::size_t budget : {std::size_t(9), std::size_t(8), std::size_t(0)}) {
        SCOPED_TRACE(budget);
        auto s = build(instanced_scene(), budget);
        const bool in_place = budget >= 9;
        EXPECT_EQ(s->instances.size(), in_place ? 0u : 3u);
        EXPECT_EQ(s->instances_in_place, in_place ? 3u : 0u);
        EXPECT_EQ(s->objects_in_place, in_place ? 1u : 0u);
        EXPECT_EQ(s->objects.size(), in_place ? 0u : 1u);
        EXPECT_EQ(s->primitives.size(), in_place ? 1u + 3 * 2 : 1u);  // the floor and copies
        // The copies are the shapes placed: the first instance's sphere's top at 1.6.
        const std::optional<SurfaceHit> hit =
            s->intersect(Vec3(-1.8f, 5, 0), Vec3(0, -1, 0), 0, 100);
        ASSERT_TRUE(hit.has_value());
        EXPECT_NEAR(hit->p.y, 1.6, 1e-5);
        EXPECT_EQ(hit->instance == nullptr, in_place);
    }
    // Used once: in place whatever the budget (no copy), but not with 0.
    const std::string once = kHeader + "ObjectBegin \"thing\"\n" + kShapes +
                             "ObjectEnd\nTranslate 1 0 0 ObjectInstance \"thing\"\nWorldEnd\n";
    EXPECT_EQ(build(once, 1)->instances_in_place, 1u);
    EXPECT_EQ(build(once, 1)->instances.size(), 0u);
    EXPECT_EQ(build(once, 0)->instances.size(), 1u);
    // The budget is the scene's: of two such objects used three times each, one fits in 12.
    std::string two = kHeader + "ObjectBegin \"a\"\n" + kShapes + "ObjectEnd\n" +
                      "ObjectBegin \"b\"\n" + kShapes + "ObjectEnd\n";
    for (const char* p : kPlacements)
        two += std::string("AttributeBegin\n") + p +
               "\nObjectInstance \"a\"\nObjectInstance \"b\"\nAttributeEnd\n";
    auto s = build(two + "WorldEnd\n", 12);
    EXPECT_EQ(s->objects_in_place, 1u);
    EXPECT_EQ(s->instances.size(), 3u);
    // Ids: the copies' after the floor, then the instances' (each its own, as before).
    ASSERT_EQ(s->primitives.size(), 7u);
    for (std::size_t i = 0; i < s->primitives.size(); ++i) EXPECT_EQ(s->primitives[i]->id, i);
    EXPECT_EQ(s->instances[0].first_id, 7u);
    EXPECT_EQ(s->instances[2].first_id, 11u);
    // Curves stay instances.
    const std::string curve =
        kHeader +
        "ObjectBegin \"c\" Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] "
        "\"float width\" 0.1 ObjectEnd ObjectInstance \"c\"\nWorldEnd\n";
    EXPECT_EQ(build(curve, 1000)->instances.size(), 1u);
}

// An object's warnings come once, however many of its instances are built in place.
TEST(Instancing, InPlaceObjectsWarnOnce) {
    for (int uses : {1, 3}) {
        std::string text = kHeader +
                           "ObjectBegin \"w\" Shape \"trianglemesh\" \"integer indices\" [0 1 2] "
                           "\"point3 P\" [0 0 0 1 0 0 0 1 0] \"float unknown\" 1 ObjectEnd\n";
        for (int i = 0; i < uses; ++i) text += "Translate 0 0 1 ObjectInstance \"w\"\n";
        std::vector<std::string> warnings;
        auto s = build_scene(pbrt::parse_string(text + "WorldEnd\n", "t.pbrt"), {},
                             [&](const std::string& w) { warnings.push_back(w); });
        EXPECT_EQ(s->instances_in_place, std::size_t(uses));
        int unknown = 0;
        for (const std::string& w : warnings) unknown += w.find("unknown") != std::string::npos;
        EXPECT_EQ(unknown, 1) << uses << " uses";
    }
}

// An instance whose transform cannot be inverted is an error at its directive, kept as an
// instance or built in place.
TEST(Instancing, SingularInstanceTransformIsALocatedError) {
    const std::string text = kHeader + "ObjectBegin \"thing\"\n" + kShapes +
                             "ObjectEnd\nScale 1 0 1\nObjectInstance \"thing\"\nWorldEnd\n";
    for (const BuildOptions& bo : {BuildOptions{}, kept_instances()}) {
        try {
            build_scene(pbrt::parse_string(text, "t.pbrt"), bo, {});
            FAIL();
        } catch (const pbrt::SceneError& e) {
            EXPECT_NE(std::string(e.what()).find("t.pbrt:29:1: error: the instance's transform "
                                                 "is singular"),
                      std::string::npos)
                << e.what();
        }
    }
}
