// pbrt — typed parameter lists ("float fov" [45]) with the pbrt-v3 type names and aliases.
// Each lookup marks its parameter used, so a builder can report unknown parameters with their
// location afterwards.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include "pbrt/error.h"

namespace cmam::pbrt {

enum class ParamType {
    Integer,
    Float,
    Point2,
    Vector2,
    Point3,
    Vector3,
    Normal,
    Rgb,
    Spectrum,
    Bool,
    String,
    Texture
};

/// Parses a pbrt-v3 type name (including the aliases point, vector, color, normal3).
std::optional<ParamType> parse_param_type(const std::string& name);
/// The type's pbrt-v3 name ("point3" for Point3, "spectrum" for Spectrum).
const char* to_string(ParamType t);
/// The type names messages list as valid, comma-separated ("integer, float, ..."): pbrt-v3's
/// own names, without the aliases.
const std::string& param_type_names();

struct Param {
    ParamType type{};
    std::string type_name;  // as written
    std::string name;
    FileLoc loc;  // of the "type name" declaration
    std::vector<double> numbers;
    std::vector<std::string> strings;
    std::vector<bool> bools;
    mutable bool used = false;
};

using Rgb = std::array<float, 3>;

/// A spectrum- or float-valued parameter that is either a constant or a named texture.
struct TextureRef {
    std::string name;  // texture name
    FileLoc loc;
};

class ParamSet {
  public:
    /// Adds a parameter; throws SceneError on a duplicate name or a malformed value list.
    /// Adds `p` after checking its values. A parameter of the same name given before is
    /// replaced, as pbrt-v3 takes the later value; its location is returned.
    std::optional<FileLoc> add(Param p);
    bool empty() const { return m_params.empty(); }
    const std::vector<Param>& params() const { return m_params; }

    /// Single-valued getters: the default when absent; SceneError on a wrong type or count.
    double get_float(const std::string& name, double def) const;
    int get_int(const std::string& name, int def) const;
    bool get_bool(const std::string& name, bool def) const;
    std::string get_string(const std::string& name, const std::string& def) const;
    std::array<double, 3> get_point3(const std::string& name, std::array<double, 3> def) const;
    /// rgb/color/spectrum constant (spectrum sampled values are converted to RGB).
    std::optional<Rgb> get_rgb(const std::string& name) const;
    std::optional<TextureRef> get_texture(const std::string& name) const;

    std::optional<std::vector<int>> get_ints(const std::string& name) const;
    std::optional<std::vector<double>> get_floats(const std::string& name) const;
    /// point3/normal/vector3 arrays as flat triples; point2/float arrays as flat pairs.
    std::optional<std::vector<double>> get_point3s(const std::string& name) const;
    std::optional<std::vector<double>> get_point2s(const std::string& name) const;

    const Param* find(const std::string& name) const;
    /// Warns of every parameter nobody asked for, naming `what` ("shape \"sphere\""): a name
    /// listed in `ignored` is a pbrt-v3 parameter cmam does not support; any other is one
    /// pbrt-v3 does not know either (a misspelt name), which pbrt-v3 reports unused and renders
    /// without, as cmam does.
    void check_unused(const std::string& what, const WarningSink& warn,
                      const std::vector<std::string>& ignored = {}) const;

  private:
    std::vector<Param> m_params;
    std::unordered_set<std::string> m_names;  // of m_params: a new name needs no scan
    const Param* find_typed(const std::string& name, std::initializer_list<ParamType> types) const;
};

/// Converts a sampled spectrum (wavelength, value pairs in nm) to linear sRGB as pbrt-v3 does:
/// CIE XYZ against the tabulated CIE 1931 2-degree observer at 1 nm steps, normalised as
/// pbrt-v3 normalises it (a constant 1 has Y = 470/471), then its XYZ-to-sRGB matrix.
/// The pairs are as ParamSet::add accepts them: at least one, finite, wavelengths increasing.
Rgb spectrum_to_rgb(const std::vector<double>& lambda_value_pairs);
/// CIE XYZ to linear sRGB with pbrt-v3's matrix (its "xyz" parameters, and spectrum_to_rgb's
/// last step).
Rgb xyz_to_rgb(double x, double y, double z);
/// pbrt-v3's "blackbody" [T scale]: Planck's spectrum at T kelvin divided by its peak, times
/// `scale`, as (wavelength in nm, value) pairs every 5 nm from 360 to 830 nm. The parser turns a
/// blackbody parameter into these samples (a spectrum parameter).
std::vector<double> blackbody_samples(double kelvin, double scale);

}  // namespace cmam::pbrt
