// Parser on valid input: parameters, graphics state, named materials and textures, instancing.
#include "pbrt/parser.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "expect_throw.h"
#include "temp_dir.h"

using namespace cmam::pbrt;

namespace {
const char* kHeader = "Camera \"perspective\" \"float fov\" 45\nWorldBegin\n";
SceneDesc parse_world(const std::string& body, const WarningSink& warn = {}) {
    return parse_string(std::string(kHeader) + body + "\nWorldEnd\n", "t.pbrt", warn);
}
}  // namespace

TEST(Parser, ParameterTypesAndAliases) {
    SceneDesc d = parse_world(
        "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2] "
        "\"normal N\" [0 0 1 0 0 1 0 0 1] \"point2 uv\" [0 0 1 0 0 1] \"bool b\" true \"string s\" "
        "\"x\" "
        "\"color c\" [1 2 3] \"vector3 v\" [1 2 3] \"spectrum sp\" [400 1 700 1]");
    const ParamSet& p = d.shapes[0].entity.params;
    EXPECT_EQ(p.get_point3s("P")->size(), 9u);
    EXPECT_EQ(p.get_ints("indices")->at(2), 2);
    EXPECT_TRUE(p.get_bool("b", false));
    EXPECT_EQ(p.get_string("s", ""), "x");
    EXPECT_EQ((*p.get_rgb("c"))[2], 3.0f);
    EXPECT_EQ(p.get_point3("v", {}), (std::array<double, 3>{1, 2, 3}));
    EXPECT_EQ(p.find("P")->type, ParamType::Point3);
    EXPECT_EQ(p.find("N")->type, ParamType::Normal);
    auto sp = *p.get_rgb("sp");  // a flat spectrum is a near-white
    EXPECT_NEAR(0.212671 * sp[0] + 0.715160 * sp[1] + 0.072169 * sp[2], 1.0, 0.02);
}

// Every type prints its pbrt-v3 name, which parses back to it; the aliases parse too, and the
// error for an unknown type lists the names without them.
TEST(Parser, ParameterTypeNamesRoundTrip) {
    for (int k = 0; k <= static_cast<int>(ParamType::Texture); ++k)
        EXPECT_EQ(parse_param_type(to_string(ParamType(k))), ParamType(k)) << k;
    EXPECT_EQ(parse_param_type("point"), ParamType::Point3);
    EXPECT_EQ(parse_param_type("vector"), ParamType::Vector3);
    EXPECT_EQ(parse_param_type("normal3"), ParamType::Normal);
    EXPECT_EQ(parse_param_type("color"), ParamType::Rgb);
    EXPECT_EQ(parse_param_type("blackbody"), ParamType::Spectrum);
    EXPECT_EQ(parse_param_type("Float"), std::nullopt);
    EXPECT_STREQ(to_string(ParamType::Spectrum), "spectrum");
    EXPECT_EQ(parse_param_type("xyz"), ParamType::Rgb);
    EXPECT_EQ(param_type_names(),
              "integer, float, point2, vector2, point3, vector3, normal, rgb, xyz, spectrum, "
              "blackbody, bool, string, texture");
    EXPECT_THROW_MSG(parse_world("Shape \"sphere\" \"flaot radius\" 1"), SceneError,
                     "t.pbrt:3:16: error: unknown parameter type \"flaot\" (expected integer, "
                     "float, point2, vector2, point3, vector3, normal, rgb, xyz, spectrum, "
                     "blackbody, bool, string, texture)");
}

TEST(Parser, SingleValuesWithoutBrackets) {
    SceneDesc d = parse_world("Shape \"sphere\" \"float radius\" 2.5 \"float zmin\" [-1]");
    EXPECT_DOUBLE_EQ(d.shapes[0].entity.params.get_float("radius", 1), 2.5);
    EXPECT_DOUBLE_EQ(d.shapes[0].entity.params.get_float("zmin", 0), -1);
    EXPECT_DOUBLE_EQ(d.shapes[0].entity.params.get_float("zmax", 7), 7);
}

TEST(Parser, AttributesScopeMaterialsTransformsAndOrientation) {
    SceneDesc d = parse_world(
        "Material \"mirror\"\n"
        "AttributeBegin Material \"glass\" Translate 1 0 0 ReverseOrientation Shape \"sphere\" "
        "AttributeEnd\n"
        "Shape \"sphere\"\n"
        "TransformBegin Translate 0 2 0 Material \"matte\" TransformEnd Shape \"sphere\"");
    ASSERT_EQ(d.shapes.size(), 3u);
    EXPECT_EQ(d.materials[d.shapes[0].material].entity.type, "glass");
    EXPECT_TRUE(d.shapes[0].reverse_orientation);
    EXPECT_EQ(d.shapes[0].world_from_object.apply_point({0, 0, 0})[0], 1);
    EXPECT_EQ(d.materials[d.shapes[1].material].entity.type, "mirror");
    EXPECT_FALSE(d.shapes[1].reverse_orientation);
    EXPECT_TRUE(d.shapes[1].world_from_object.is_identity());
    // TransformEnd restores the transform only; the material set inside stays.
    EXPECT_EQ(d.materials[d.shapes[2].material].entity.type, "matte");
    EXPECT_TRUE(d.shapes[2].world_from_object.is_identity());
}

TEST(Parser, DefaultMaterialIsMinusOne) {
    SceneDesc d = parse_world("Shape \"sphere\"");
    EXPECT_EQ(d.shapes[0].material, -1);
}

TEST(Parser, NamedMaterialsAndTextureScopes) {
    SceneDesc d = parse_world(
        "Texture \"k\" \"spectrum\" \"constant\" \"rgb value\" [1 0 0]\n"
        "MakeNamedMaterial \"red\" \"string type\" \"matte\" \"texture Kd\" \"k\"\n"
        "NamedMaterial \"red\" Shape \"sphere\"");
    ASSERT_EQ(d.materials.size(), 1u);
    EXPECT_EQ(d.materials[0].entity.type, "matte");
    EXPECT_EQ(d.materials[0].name, "red");
    EXPECT_EQ(d.shapes[0].material, 0);
    EXPECT_EQ(d.materials[0].scope.spectrum_textures.at("k"), 0);
    EXPECT_TRUE(d.materials[0].scope.float_textures.empty());
}

// As in pbrt-v3, AttributeEnd (and ObjectEnd) ends the names declared in its block, and a
// name redefined there means its outer definition again; TransformEnd keeps them.
TEST(Parser, NamesDeclaredInABlockEndWithIt) {
    SceneDesc d = parse_world(
        "Texture \"k\" \"float\" \"constant\"\n"               // 0
        "MakeNamedMaterial \"m\" \"string type\" \"matte\"\n"  // 0
        "AttributeBegin\n"
        "  Texture \"k\" \"float\" \"constant\"\n"                              // 1
        "  MakeNamedMaterial \"m\" \"string type\" \"plastic\"\n"               // 1
        "  TransformBegin Texture \"j\" \"float\" \"constant\" TransformEnd\n"  // 2
        "  MakeNamedMaterial \"n\" \"string type\" \"matte\" \"texture sigma\" \"j\"\n"
        "  NamedMaterial \"m\" Shape \"sphere\"\n"
        "AttributeEnd\n"
        "ObjectBegin \"o\" Texture \"k\" \"float\" \"constant\" ObjectEnd\n"  // 3
        "MakeNamedMaterial \"p\" \"string type\" \"matte\" \"texture sigma\" \"k\"\n"
        "NamedMaterial \"m\" Shape \"sphere\"\n");
    ASSERT_EQ(d.materials.size(), 4u);
    EXPECT_EQ(d.materials[d.shapes[0].material].entity.type, "plastic");
    EXPECT_EQ(d.materials[2].scope.float_textures.at("j"), 2);
    EXPECT_EQ(d.materials[3].scope.float_textures.at("k"), 0);
    EXPECT_EQ(d.materials[3].scope.float_textures.size(), 1u);
    EXPECT_EQ(d.materials[d.shapes[1].material].entity.type, "matte");
    EXPECT_EQ(d.shapes[1].material, 0);
    // Out of scope: pbrt-v3 reports it and keeps the current material.
    std::vector<std::string> warnings;
    SceneDesc out = parse_world(
        "Material \"plastic\" AttributeBegin MakeNamedMaterial \"m\" \"string type\" "
        "\"matte\" AttributeEnd NamedMaterial \"m\" Shape \"sphere\"",
        [&](const std::string& w) { warnings.push_back(w); });
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0],
              "t.pbrt:3:92: warning: named material \"m\" is not defined; the current material "
              "is kept (as pbrt-v3 does)");
    EXPECT_EQ(out.materials[out.shapes[0].material].entity.type, "plastic");
}

TEST(Parser, ObjectInstancesReferToOneObjectWithTheirTransforms) {
    SceneDesc d = parse_world(
        "ObjectBegin \"ball\" Translate 0 1 0 Shape \"sphere\" ObjectEnd\n"
        "Translate 5 0 0 ObjectInstance \"ball\"\n"
        "Translate 5 0 0 ObjectInstance \"ball\"\n"
        "ObjectBegin \"ball\" Shape \"disk\" ObjectEnd ObjectInstance \"ball\"");
    EXPECT_TRUE(d.shapes.empty());
    ASSERT_EQ(d.objects.size(), 2u);  // a redefinition is a new object
    ASSERT_EQ(d.objects[0].shapes.size(), 1u);
    EXPECT_EQ(d.objects[0].name, "ball");
    // The shape keeps the transform of its definition; the instance carries its own.
    EXPECT_EQ(d.objects[0].shapes[0].world_from_object.apply_point({0, 0, 0}),
              (std::array<double, 3>{0, 1, 0}));
    ASSERT_EQ(d.instances.size(), 3u);
    EXPECT_EQ(d.instances[0].object, 0);
    EXPECT_EQ(d.instances[1].object, 0);
    EXPECT_EQ(d.instances[2].object, 1);  // instances before the redefinition keep the old one
    EXPECT_EQ(d.instances[0].world_from_instance.apply_point({0, 0, 0}),
              (std::array<double, 3>{5, 0, 0}));
    EXPECT_EQ(d.instances[1].world_from_instance.apply_point({0, 0, 0}),
              (std::array<double, 3>{10, 0, 0}));
    EXPECT_EQ(d.instances[1].loc.line, 5);
}

TEST(Parser, OptionsAndEntities) {
    SceneDesc d = parse_string(
        "Film \"image\" \"integer xresolution\" 10 Sampler \"stratified\" PixelFilter \"box\" "
        "Integrator \"whitted\" Accelerator \"bvh\" Camera \"perspective\" WorldBegin WorldEnd");
    EXPECT_TRUE(d.film.given);
    EXPECT_EQ(d.sampler.type, "stratified");
    EXPECT_EQ(d.filter.type, "box");
    EXPECT_EQ(d.integrator.type, "whitted");
    EXPECT_EQ(d.accelerator.type, "bvh");
    EXPECT_EQ(d.film.params.get_int("xresolution", 0), 10);
}

TEST(Parser, IgnoredDirectivesWarnWithLocation) {
    std::vector<std::string> warnings;
    parse_world("TransformTimes 0 1\nActiveTransform All",
                [&](const std::string& w) { warnings.push_back(w); });
    ASSERT_EQ(warnings.size(), 2u);
    EXPECT_EQ(warnings[0],
              "t.pbrt:3:1: warning: TransformTimes ignored: cmam renders no motion blur");
    EXPECT_EQ(warnings[1],
              "t.pbrt:4:1: warning: ActiveTransform All ignored: cmam renders no motion blur");
}

TEST(Parser, RepeatedParameterTakesTheLaterValueWithAWarning) {
    std::vector<std::string> warnings;
    SceneDesc d = parse_world("Shape \"sphere\" \"float radius\" 1 \"float radius\" 2",
                              [&](const std::string& w) { warnings.push_back(w); });
    EXPECT_EQ(d.shapes[0].entity.params.get_float("radius", 0), 2);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0],
              "t.pbrt:3:33: warning: parameter \"radius\" given twice; the later value is used "
              "(the first is at t.pbrt:3:16)");
}

TEST(Parser, RelativePathsResolveAgainstTheMainFilesFolderAsInPbrtV3) {
    // main.pbrt Includes sub/part.pbrt, which names "data/x.ply": pbrt-v3 reads <main>/data/x.ply.
    // A path found only beside the including file (other renderers' convention) is read there.
    namespace fs = std::filesystem;
    const cmam::test::TempDir tmp("cmam_paths");
    const fs::path& dir = tmp.path;
    fs::create_directories(dir / "sub" / "only");
    fs::create_directories(dir / "data");
    std::ofstream(dir / "data" / "x.ply") << "x";
    std::ofstream(dir / "sub" / "only" / "y.ply") << "y";
    std::ofstream(dir / "sub" / "part.pbrt")
        << "Shape \"plymesh\" \"string filename\" \"data/x.ply\"\n"
        << "Shape \"plymesh\" \"string filename\" \"only/y.ply\"\n";
    std::ofstream(dir / "main.pbrt") << kHeader << "Include \"sub/part.pbrt\"\nWorldEnd\n";
    SceneDesc d = parse_file((dir / "main.pbrt").string());
    ASSERT_EQ(d.shapes.size(), 2u);
    auto resolved = [&](int k) {
        const Param* p = d.shapes[k].entity.params.find("filename");
        return fs::path(resolve_path(d.base_dir, p->loc, p->strings[0]));
    };
    EXPECT_TRUE(fs::equivalent(resolved(0), dir / "data" / "x.ply")) << resolved(0);
    EXPECT_TRUE(fs::equivalent(resolved(1), dir / "sub" / "only" / "y.ply")) << resolved(1);
}

TEST(Parser, BlackbodyIsPlancksSpectrumNormalisedToItsPeak) {
    // pbrt-v3's "blackbody" [T scale]: B(lambda, T) / B(lambda_max, T) * scale, as RGB.
    SceneDesc d = parse_world(
        "LightSource \"point\" \"blackbody I\" [3000 2]\n"
        "LightSource \"point\" \"blackbody I\" [10000 1]\n"
        "LightSource \"point\" \"blackbody I\" [5000 1]");
    auto rgb_of = [&](int k) { return *d.lights[k].entity.params.get_rgb("I"); };
    const auto warm = rgb_of(0), cool = rgb_of(1);
    EXPECT_GT(warm[0], warm[2]);  // 3000 K is red, 10000 K blue
    EXPECT_LT(cool[0], cool[2]);
    // Independently: Planck's law at the CIE samples, by the formula, through the same
    // conversion the spectrum type uses.
    std::vector<double> pairs;
    const double h = 6.62606957e-34, c = 299792458.0, kb = 1.3806488e-23, T = 3000;
    auto planck = [&](double l) {
        return 2 * h * c * c / (std::pow(l, 5) * (std::exp(h * c / (l * kb * T)) - 1));
    };
    for (int nm = 360; nm <= 830; nm += 5) {
        pairs.push_back(nm);
        pairs.push_back(2 * planck(nm * 1e-9) / planck(2.8977721e-3 / T));
    }
    const Rgb want = spectrum_to_rgb(pairs);
    EXPECT_NEAR(warm[0], want[0], 1e-5);
    EXPECT_NEAR(warm[1], want[1], 1e-5);
    EXPECT_NEAR(warm[2], want[2], 1e-5);
    // Normalised to the peak: at 5000 K (peak 579.6 nm, inside the samples) no sample exceeds 1
    // and the largest is within 0.1% of it.
    const auto s = blackbody_samples(5000, 1);
    double top = 0;
    for (std::size_t i = 1; i < s.size(); i += 2) top = std::max(top, s[i]);
    EXPECT_LE(top, 1.0);
    EXPECT_GT(top, 0.999);
    EXPECT_THROW_MSG(parse_world("LightSource \"point\" \"blackbody I\" [-5 1]"), SceneError,
                     "t.pbrt:3:21: error: blackbody \"I\" temperature must be a positive finite "
                     "number of kelvin, got -5");
}

// Spectra become RGB as in pbrt-v3: XYZ against the tabulated CIE 1931 2-degree observer, a
// constant 1 at Y = 470/471 (pbrt-v3's normalisation), then its XYZ-to-sRGB matrix. A spike at
// one wavelength gives XYZ in the ratios of the observer's table there (x, y, z at 450 nm:
// 0.3362, 0.038, 1.77211; at 600 nm: 1.0622, 0.631, 0.0008), which a fitted observer misses by
// percents.
TEST(Parser, SpectraConvertThroughTheTabulatedCieObserver) {
    auto xyz = [](const std::vector<double>& pairs) {
        const Rgb c = spectrum_to_rgb(pairs);
        return std::array<double, 3>{0.412453 * c[0] + 0.357580 * c[1] + 0.180423 * c[2],
                                     0.212671 * c[0] + 0.715160 * c[1] + 0.072169 * c[2],
                                     0.019334 * c[0] + 0.119193 * c[1] + 0.950227 * c[2]};
    };
    EXPECT_NEAR(xyz({300, 1, 900, 1})[1], 470.0 / 471, 1e-5);
    const auto b = xyz({449, 0, 450, 1, 451, 0}), o = xyz({599, 0, 600, 1, 601, 0});
    EXPECT_NEAR(b[0] / b[2], 0.3362 / 1.77211, 1e-4);
    EXPECT_NEAR(b[1] / b[2], 0.038 / 1.77211, 1e-4);
    EXPECT_NEAR(o[1] / o[0], 0.631 / 1.0622, 1e-4);
    EXPECT_NEAR(o[2] / o[0], 0.0008 / 1.0622, 1e-4);
}

// pbrt-v3's "xyz" colours become RGB through its XYZ-to-sRGB matrix: taken back to XYZ with the
// sRGB primaries' matrix (its inverse, to the matrices' six digits) they are what was written,
// D65's white is RGB 1, and a count that is not whole colours is a located error.
TEST(Parser, XyzColoursConvertWithPbrtV3sMatrix) {
    SceneDesc d = parse_world(
        "LightSource \"point\" \"xyz I\" [0.3 0.5 0.2]\n"
        "Material \"matte\" \"xyz Kd\" [0.950456 1 1.088754]\n"
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"xyz Kd\" [1 2 3 4 5 6]");
    const auto c = *d.lights[0].entity.params.get_rgb("I");
    EXPECT_NEAR(0.412453 * c[0] + 0.357580 * c[1] + 0.180423 * c[2], 0.3, 1e-5);
    EXPECT_NEAR(0.212671 * c[0] + 0.715160 * c[1] + 0.072169 * c[2], 0.5, 1e-5);
    EXPECT_NEAR(0.019334 * c[0] + 0.119193 * c[1] + 0.950227 * c[2], 0.2, 1e-5);
    EXPECT_NEAR(c[0], 3.240479 * 0.3 - 1.537150 * 0.5 - 0.498535 * 0.2, 1e-6);
    const auto white = *d.materials[0].entity.params.get_rgb("Kd");
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(white[k], 1.0, 1e-3) << k;
    EXPECT_EQ(d.shapes[0].entity.params.find("Kd")->numbers.size(), 6u);
    EXPECT_THROW_MSG(parse_world("LightSource \"point\" \"xyz I\" [1 1]"), SceneError,
                     "t.pbrt:3:21: error: xyz parameter \"I\" needs a multiple of 3 values, got "
                     "2");
}

TEST(Parser, SpectrumFromAnSpdFileIsItsSamples) {
    // pbrt-v3 reads "spectrum Kd" "file.spd" (wavelength value pairs, '#' comments) relative to
    // the main file's folder: the same RGB as the pairs written inline.
    namespace fs = std::filesystem;
    const cmam::test::TempDir tmp("cmam_spd");
    const fs::path& dir = tmp.path;
    fs::create_directories(dir / "spds");
    std::ofstream(dir / "spds" / "k.spd") << "# a test\n400 0.2\n500 0.5 # mid\n600 0.9\n700 0.4\n";
    std::ofstream(dir / "main.pbrt")
        << kHeader << "Material \"matte\" \"spectrum Kd\" \"spds/k.spd\"\n"
        << "Material \"matte\" \"spectrum Kd\" [400 0.2 500 0.5 600 0.9 700 0.4]\n"
        << "Material \"matte\" \"spectrum Kd\" \"spds/missing.spd\"\nWorldEnd\n";
    // The third names a file that is not there.
    const std::string main = (dir / "main.pbrt").string();
    EXPECT_THROW_MSG(parse_file(main), SceneError,
                     main + ":5:18: error: cannot read spectrum file \"" +
                         (dir / "spds/missing.spd").string() +
                         "\": file not found (named by spectrum \"Kd\")");
    std::ofstream(dir / "main.pbrt")
        << kHeader << "Material \"matte\" \"spectrum Kd\" \"spds/k.spd\"\n"
        << "Material \"matte\" \"spectrum Kd\" [400 0.2 500 0.5 600 0.9 700 0.4]\nWorldEnd\n";
    SceneDesc d = parse_file((dir / "main.pbrt").string());
    ASSERT_EQ(d.materials.size(), 2u);
    const auto a = *d.materials[0].entity.params.get_rgb("Kd"),
               b = *d.materials[1].entity.params.get_rgb("Kd");
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(a[c], b[c]);
}

// A parameter nobody reads and pbrt-v3 does not know either (a misspelt name) is a warning
// naming it and its directive, as pbrt-v3 reports it unused and renders without it; every one
// is reported, not only the first.
TEST(Parser, UnknownParameterWarnsNamingEntity) {
    SceneDesc d =
        parse_world("Shape \"sphere\" \"float radius\" 1 \"float bogus\" 3 \"float radiu\" 2");
    const ParamSet& p = d.shapes[0].entity.params;
    p.get_float("radius", 1);
    std::vector<std::string> w;
    p.check_unused("shape \"sphere\"", [&](const std::string& s) { w.push_back(s); });
    EXPECT_EQ(w, (std::vector<std::string>{
                     "t.pbrt:3:33: warning: unknown parameter \"bogus\" for shape \"sphere\" "
                     "(pbrt-v3 reports it unused); ignored",
                     "t.pbrt:3:49: warning: unknown parameter \"radiu\" for shape \"sphere\" "
                     "(pbrt-v3 reports it unused); ignored"}));
    EXPECT_NO_THROW(p.check_unused("shape \"sphere\"", {}));  // no sink: nothing reported
}

TEST(Parser, KnownButUnsupportedParameterWarns) {
    SceneDesc d = parse_world("Shape \"sphere\" \"texture alpha\" \"a\"");
    std::vector<std::string> w;
    d.shapes[0].entity.params.check_unused(
        "shape \"sphere\"", [&](const std::string& s) { w.push_back(s); }, {"alpha"});
    ASSERT_EQ(w.size(), 1u);
    EXPECT_EQ(w[0],
              "t.pbrt:3:16: warning: parameter \"alpha\" of shape \"sphere\" is not supported by "
              "cmam; ignored");
}

TEST(Errors, MessagesEscapeWhatATerminalWouldActOn) {
    // Control bytes and bytes that are not UTF-8 become \xNN; UTF-8 text and newlines stay.
    EXPECT_EQ(printable("a\x1b[31m\x07z"), "a\\x1b[31m\\x07z");
    EXPECT_EQ(printable("caf\xc3\xa9 \xff\xc3"), "caf\xc3\xa9 \\xff\\xc3");
    EXPECT_EQ(printable("two\nlines\t"), "two\nlines\\x09");
    const std::string what = cmam::test::thrown_text<SceneError>([] {
        parse_string(
            "\x7f"
            "ELF\x02\x01",
            "bin.pbrt");
    });
    EXPECT_EQ(
        what.rfind("bin.pbrt:1:1: error: unknown directive \\x7fELF\\x02\\x01 (supported: ", 0), 0u)
        << what;
    for (char c : what) EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20 && c != '\n');
}

// The directives the unknown-directive error lists are the ones the parser reads: each listed
// one parses, and so do the pbrt-v3 directives cmam reads without listing them.
TEST(Parser, TheUnknownDirectiveErrorListsTheDirectivesItReads) {
    const cmam::test::TempDir tmp("cmam_directives");
    const std::string part = (tmp.path / "part.pbrt").string();
    std::ofstream(part) << "Shape \"sphere\"\n";
    // Every pbrt-v3 directive, in the error's order, with text before and inside the world
    // block that uses it.
    struct Use {
        const char* name;
        bool listed;
        std::string options, world;
    };
    const Use uses[] = {
        {"LookAt", true, "LookAt 0 0 -1  0 0 0  0 1 0", ""},
        {"Translate", true, "", "Translate 1 0 0"},
        {"Rotate", true, "", "Rotate 30 0 0 1"},
        {"Scale", true, "", "Scale 1 2 3"},
        {"Transform", true, "", "Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]"},
        {"ConcatTransform", true, "", "ConcatTransform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]"},
        {"Identity", true, "", "Identity"},
        {"CoordinateSystem", true, "", "CoordinateSystem \"c\""},
        {"CoordSysTransform", true, "", "CoordinateSystem \"c\" CoordSysTransform \"c\""},
        {"ReverseOrientation", true, "", "ReverseOrientation"},
        {"WorldBegin", true, "", ""},
        {"WorldEnd", true, "", ""},
        {"AttributeBegin", true, "", "AttributeBegin AttributeEnd"},
        {"AttributeEnd", true, "", "AttributeBegin AttributeEnd"},
        {"TransformBegin", true, "", "TransformBegin TransformEnd"},
        {"TransformEnd", true, "", "TransformBegin TransformEnd"},
        {"Include", true, "", "Include \"" + part + "\""},
        {"MakeNamedMaterial", true, "", "MakeNamedMaterial \"m\" \"string type\" \"matte\""},
        {"NamedMaterial", true, "",
         "MakeNamedMaterial \"m\" \"string type\" \"matte\" NamedMaterial \"m\""},
        {"Material", true, "", "Material \"matte\""},
        {"Texture", true, "", "Texture \"t\" \"float\" \"constant\""},
        {"Shape", true, "", "Shape \"sphere\""},
        {"LightSource", true, "", "LightSource \"point\""},
        {"AreaLightSource", true, "", "AreaLightSource \"diffuse\""},
        {"Camera", true, "Camera \"perspective\"", ""},
        {"Film", true, "Film \"image\"", ""},
        {"Sampler", true, "Sampler \"random\"", ""},
        {"PixelFilter", true, "PixelFilter \"box\"", ""},
        {"Integrator", true, "Integrator \"whitted\"", ""},
        {"Accelerator", true, "Accelerator \"bvh\"", ""},
        {"ObjectBegin", true, "", "ObjectBegin \"o\" ObjectEnd"},
        {"ObjectEnd", true, "", "ObjectBegin \"o\" ObjectEnd"},
        {"ObjectInstance", true, "", "ObjectBegin \"o\" ObjectEnd ObjectInstance \"o\""},
        {"SurfaceIntegrator", false, "SurfaceIntegrator \"whitted\"", ""},
        {"MakeNamedMedium", true, "", "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\""},
        {"MediumInterface", true, "", "MediumInterface \"fog\" \"\""},
        {"ActiveTransform", false, "", "ActiveTransform All"},
        {"TransformTimes", false, "", "TransformTimes 0 1"},
    };
    std::string listed;
    for (const Use& u : uses) {
        if (u.listed) listed += (listed.empty() ? "" : ", ") + std::string(u.name);
        const std::string scene = u.options + "\nWorldBegin\n" + u.world + "\nWorldEnd\n";
        ASSERT_NE(scene.find(u.name), std::string::npos) << u.name;
        EXPECT_NO_THROW(parse_string(scene)) << u.name << ":\n" << scene;
    }
    EXPECT_THROW_MSG(parse_string("WorldBegin\nBogus\n"), SceneError,
                     "<string>:2:1: error: unknown directive Bogus (supported: " + listed + ")");
    EXPECT_THROW_MSG(
        parse_string("WorldBegin\nBogus\n"), SceneError,
        "<string>:2:1: error: unknown directive Bogus (supported: LookAt, Translate, Rotate, "
        "Scale, Transform, ConcatTransform, Identity, CoordinateSystem, CoordSysTransform, "
        "ReverseOrientation, WorldBegin, WorldEnd, AttributeBegin, AttributeEnd, "
        "TransformBegin, TransformEnd, Include, MakeNamedMaterial, NamedMaterial, Material, "
        "Texture, Shape, LightSource, AreaLightSource, Camera, Film, Sampler, PixelFilter, "
        "Integrator, Accelerator, ObjectBegin, ObjectEnd, ObjectInstance, MakeNamedMedium, "
        "MediumInterface)");
}
