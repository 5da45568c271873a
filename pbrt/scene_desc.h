// pbrt — the plain description a pbrt-v3 file parses into.
// No rendering types here: records of what the file said, each with its location, transforms
// resolved, named materials and textures resolved to indices at the point of use (pbrt-v3 keeps
// them in the graphics state, so AttributeEnd scopes them).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "pbrt/params.h"
#include "pbrt/transform.h"

namespace cmam::pbrt {

/// A directive's type string and parameters ("Shape \"sphere\" ...").
struct Entity {
    std::string type;
    ParamSet params;
    FileLoc loc;
    bool given = false;  // false when the file never said it (defaults apply)
};

/// Texture names as visible at a point in the file: name -> index in SceneDesc textures. A
/// texture or material records only the names its "texture" parameters give (those that were
/// defined there), so the description grows with the file, not with the scope at each line.
struct TextureScope {
    std::map<std::string, int> float_textures;
    std::map<std::string, int> spectrum_textures;
};

struct TextureDesc {
    std::string name;
    bool is_float = false;  // "float" or "spectrum"
    Entity entity;          // entity.type is the class ("imagemap", "checkerboard", ...)
    Mat4 world_from_texture;
    TextureScope scope;  // the textures its parameters name, as visible when it was declared
};

struct MaterialDesc {
    Entity entity;       // entity.type is the material type ("matte", ...)
    TextureScope scope;  // the textures its parameters name, as visible when it was declared
    std::string name;    // for MakeNamedMaterial
    // "mix": the materials "namedmaterial1" and "namedmaterial2" name, as visible when it was
    // declared (indices into SceneDesc::materials; -1 when not defined there).
    int mix[2] = {-1, -1};
};

struct ShapeDesc {
    Entity entity;
    Mat4 world_from_object;
    bool reverse_orientation = false;
    int material = -1;    // index into SceneDesc::materials; -1 is the default matte
    int area_light = -1;  // index into SceneDesc::area_lights; -1: the shape does not emit
    TextureScope scope;   // the textures its parameters name ("alpha"), as visible there
    // The MediumInterface in effect: the media inside and outside the surface (indices into
    // SceneDesc::media; -1: none, i.e. vacuum).
    int medium_inside = -1, medium_outside = -1;
};

/// A MakeNamedMedium: its name, its "type" ("homogeneous" or "heterogeneous"; entity.type) and
/// parameters, and the transform current at the directive (a grid's placement).
struct MediumDesc {
    std::string name;
    Entity entity;
    Mat4 world_from_medium;
};

/// An object (ObjectBegin ... ObjectEnd): its shapes, each placed by the transform current at
/// its Shape directive.
struct ObjectDesc {
    std::string name;
    std::vector<ShapeDesc> shapes;
    FileLoc loc;
};

/// An ObjectInstance: the object (index into SceneDesc::objects), placed in the world by the
/// transform current at the directive.
struct InstanceDesc {
    int object = 0;
    Mat4 world_from_instance;
    FileLoc loc;
};

struct LightDesc {
    Entity entity;
    Mat4 world_from_light;
};

struct SceneDesc {
    Entity camera, film, sampler, filter, integrator, accelerator;
    Mat4 camera_from_world = Mat4::identity();
    std::vector<TextureDesc> textures;
    std::vector<MaterialDesc> materials;
    std::vector<ShapeDesc> shapes;  // outside objects
    std::vector<ObjectDesc> objects;
    std::vector<InstanceDesc> instances;
    std::vector<LightDesc> lights;
    std::vector<Entity> area_lights;  // AreaLightSource directives (each shape in scope emits)
    std::vector<MediumDesc> media;    // MakeNamedMedium directives, in file order
    // The camera's medium: as in pbrt-v3, the outside medium of the MediumInterface in effect
    // when the world ends (index into media; -1: none).
    int camera_medium = -1;
    FileLoc medium_interface;          // the first MediumInterface directive (line 0: none)
    std::vector<std::string> sources;  // every scene file read (the main file, then Includes)
    std::string base_dir;  // directory of the main file, which relative paths resolve against
                           // (pbrt-v3), Included files' too (resolve_path())
};

}  // namespace cmam::pbrt
