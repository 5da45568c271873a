#include "pbrt/params.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cmam::pbrt {

namespace {

// Every type name a parameter declaration may use. The first name of each type is the one
// printed; the aliases pbrt-v3 also reads are not listed in messages. "blackbody" is pbrt-v3's
// own type, read into a sampled spectrum; "xyz" is a colour in CIE XYZ, read into RGB.
struct ParamTypeName {
    ParamType type;
    const char* name;
    bool listed;
};
constexpr ParamTypeName kParamTypeNames[] = {
    {ParamType::Integer, "integer", true},
    {ParamType::Float, "float", true},
    {ParamType::Point2, "point2", true},
    {ParamType::Vector2, "vector2", true},
    {ParamType::Point3, "point3", true},
    {ParamType::Point3, "point", false},
    {ParamType::Vector3, "vector3", true},
    {ParamType::Vector3, "vector", false},
    {ParamType::Normal, "normal", true},
    {ParamType::Normal, "normal3", false},
    {ParamType::Rgb, "rgb", true},
    {ParamType::Rgb, "color", false},
    {ParamType::Rgb, "xyz", true},
    {ParamType::Spectrum, "spectrum", true},
    {ParamType::Spectrum, "blackbody", true},
    {ParamType::Bool, "bool", true},
    {ParamType::String, "string", true},
    {ParamType::Texture, "texture", true},
};

// Each type's first entry, the name printed, is one messages list.
constexpr bool every_type_named() {
    for (int k = 0; k <= static_cast<int>(ParamType::Texture); ++k) {
        const ParamTypeName* first = nullptr;
        for (const ParamTypeName& t : kParamTypeNames)
            if (!first && t.type == ParamType(k)) first = &t;
        if (!first || !first->listed) return false;
    }
    return true;
}
static_assert(every_type_named());

}  // namespace

std::optional<ParamType> parse_param_type(const std::string& name) {
    for (const ParamTypeName& t : kParamTypeNames)
        if (t.name == name) return t.type;
    return std::nullopt;
}

const char* to_string(ParamType type) {
    for (const ParamTypeName& t : kParamTypeNames)
        if (t.type == type) return t.name;
    return "?";
}

const std::string& param_type_names() {
    static const std::string list = [] {
        std::string s;
        for (const ParamTypeName& t : kParamTypeNames)
            if (t.listed) s += (s.empty() ? "" : ", ") + std::string(t.name);
        return s;
    }();
    return list;
}

namespace {
std::size_t arity(ParamType t) {
    switch (t) {
        case ParamType::Point2:
        case ParamType::Vector2:
            return 2;
        case ParamType::Point3:
        case ParamType::Vector3:
        case ParamType::Normal:
        case ParamType::Rgb:
            return 3;
        default:
            return 1;
    }
}

// Sampled spectra are (wavelength, value) pairs with finite numbers and increasing wavelengths,
// which is what spectrum_to_rgb interpolates.
void check_spectrum_samples(const Param& p) {
    const std::vector<double>& v = p.numbers;
    for (std::size_t i = 0; i + 1 < v.size(); i += 2) {
        if (!std::isfinite(v[i]))
            throw SceneError(p.loc, "spectrum " + in_quotes(p.name) +
                                        " wavelengths must be finite numbers, got " +
                                        number_text(v[i]));
        if (!std::isfinite(v[i + 1]))
            throw SceneError(p.loc, "spectrum " + in_quotes(p.name) +
                                        " values must be finite numbers, got " +
                                        number_text(v[i + 1]) + " at " + number_text(v[i]) + " nm");
        if (i > 0 && !(v[i] > v[i - 2]))
            throw SceneError(p.loc, "spectrum " + in_quotes(p.name) +
                                        " wavelengths must increase, got " + number_text(v[i]) +
                                        " after " + number_text(v[i - 2]));
    }
}
}  // namespace

std::vector<double> blackbody_samples(double kelvin, double scale) {
    // Planck's law per wavelength, divided by its value at the peak (Wien: 2.8977721e-3 m K / T),
    // as pbrt-v3's BlackbodyNormalized; sampled every 5 nm over the colour matching functions.
    constexpr double h = 6.62606957e-34, c = 299792458.0, kb = 1.3806488e-23;
    auto planck = [&](double lambda_m) {
        const double l5 = lambda_m * lambda_m * lambda_m * lambda_m * lambda_m;
        return (2 * h * c * c) / (l5 * (std::exp((h * c) / (lambda_m * kb * kelvin)) - 1));
    };
    const double peak = planck(2.8977721e-3 / kelvin);
    std::vector<double> out;
    for (int nm = 360; nm <= 830; nm += 5) {
        out.push_back(nm);
        out.push_back(scale * planck(nm * 1e-9) / peak);
    }
    return out;
}

std::optional<FileLoc> ParamSet::add(Param p) {
    // pbrt-v3 takes the later of two values of one parameter: the earlier one is dropped (and
    // its location returned, for the caller's warning).
    std::optional<FileLoc> replaced;
    if (m_names.count(p.name))  // linear only for a repeated name: 10^5 parameters stay fast
        for (auto it = m_params.begin(); it != m_params.end(); ++it)
            if (it->name == p.name) {
                replaced = it->loc;
                m_params.erase(it);
                break;
            }
    std::size_t n = p.numbers.size() + p.strings.size() + p.bools.size();
    if (n == 0) throw SceneError(p.loc, "parameter " + in_quotes(p.name) + " has no values");
    if (p.type_name == "blackbody") {  // [temperature scale]: a sampled spectrum
        if (!p.strings.empty() || p.numbers.size() != 2)
            throw SceneError(p.loc, "blackbody " + in_quotes(p.name) +
                                        " needs two numbers, a temperature in kelvin and a "
                                        "scale, got " +
                                        std::to_string(p.numbers.size() + p.strings.size()) +
                                        " values");
        const double kelvin = p.numbers[0], scale = p.numbers[1];
        if (!(kelvin > 0 && std::isfinite(kelvin)))
            throw SceneError(p.loc, "blackbody " + in_quotes(p.name) +
                                        " temperature must be a positive finite number of "
                                        "kelvin, got " +
                                        number_text(kelvin));
        if (!std::isfinite(scale))
            throw SceneError(p.loc, "blackbody " + in_quotes(p.name) +
                                        " scale must be a finite number, got " +
                                        number_text(scale));
        p.numbers = blackbody_samples(kelvin, scale);
    }
    std::size_t k = arity(p.type);
    if (p.type == ParamType::Spectrum) {
        if (!p.numbers.empty() && p.numbers.size() % 2 != 0)
            throw SceneError(p.loc, "spectrum " + in_quotes(p.name) +
                                        " needs (wavelength, value) pairs, got " +
                                        std::to_string(p.numbers.size()) + " numbers");
        check_spectrum_samples(p);
    } else if (p.numbers.size() % k != 0) {
        throw SceneError(p.loc, (p.type_name == "xyz" ? std::string("xyz") : to_string(p.type)) +
                                    " parameter " + in_quotes(p.name) + " needs a multiple of " +
                                    std::to_string(k) + " values, got " +
                                    std::to_string(p.numbers.size()));
    }
    // pbrt-v3's "xyz": each colour converted to linear sRGB with the matrix spectra go through
    // (spectrum_to_rgb), as pbrt-v3's RGB spectra take it.
    if (p.type_name == "xyz")
        for (std::size_t i = 0; i + 2 < p.numbers.size(); i += 3) {
            const Rgb c = xyz_to_rgb(p.numbers[i], p.numbers[i + 1], p.numbers[i + 2]);
            p.numbers[i] = c[0];
            p.numbers[i + 1] = c[1];
            p.numbers[i + 2] = c[2];
        }
    // Integers are read as doubles: each must convert to int exactly (NaN, infinities, 2.5 and
    // 1e10 do not).
    if (p.type == ParamType::Integer)
        for (double x : p.numbers)
            if (!(x >= std::numeric_limits<int>::min() && x <= std::numeric_limits<int>::max() &&
                  x == std::floor(x)))
                throw SceneError(p.loc, "integer parameter " + in_quotes(p.name) +
                                            " must be a whole number in int's range, got " +
                                            number_text(x));
    m_names.insert(p.name);
    m_params.push_back(std::move(p));
    return replaced;
}

const Param* ParamSet::find(const std::string& name) const {
    for (const Param& p : m_params)
        if (p.name == name) return &p;
    return nullptr;
}

const Param* ParamSet::find_typed(const std::string& name,
                                  std::initializer_list<ParamType> types) const {
    const Param* p = find(name);
    if (!p) return nullptr;
    if (std::find(types.begin(), types.end(), p->type) == types.end()) {
        std::string expected;
        for (ParamType t : types)
            expected += (expected.empty() ? "" : " or ") + std::string(to_string(t));
        throw SceneError(p->loc, "parameter " + in_quotes(name) + " has type " + p->type_name +
                                     ", expected " + expected);
    }
    p->used = true;
    return p;
}

namespace {
void expect_single(const Param& p, std::size_t n, std::size_t expected = 1) {
    if (n != expected)
        throw SceneError(p.loc, "parameter " + in_quotes(p.name) + " expects " +
                                    std::to_string(expected) + " value" +
                                    (expected == 1 ? "" : "s") + ", got " + std::to_string(n));
}
}  // namespace

double ParamSet::get_float(const std::string& name, double def) const {
    const Param* p = find_typed(name, {ParamType::Float});
    if (!p) return def;
    expect_single(*p, p->numbers.size());
    return p->numbers[0];
}

int ParamSet::get_int(const std::string& name, int def) const {
    const Param* p = find_typed(name, {ParamType::Integer});
    if (!p) return def;
    expect_single(*p, p->numbers.size());
    return static_cast<int>(p->numbers[0]);
}

bool ParamSet::get_bool(const std::string& name, bool def) const {
    const Param* p = find_typed(name, {ParamType::Bool});
    if (!p) return def;
    expect_single(*p, p->bools.size());
    return p->bools[0];
}

std::string ParamSet::get_string(const std::string& name, const std::string& def) const {
    const Param* p = find_typed(name, {ParamType::String});
    if (!p) return def;
    expect_single(*p, p->strings.size());
    return p->strings[0];
}

std::array<double, 3> ParamSet::get_point3(const std::string& name,
                                           std::array<double, 3> def) const {
    const Param* p = find_typed(name, {ParamType::Point3, ParamType::Vector3, ParamType::Normal});
    if (!p) return def;
    expect_single(*p, p->numbers.size(), 3);
    return {p->numbers[0], p->numbers[1], p->numbers[2]};
}

std::optional<Rgb> ParamSet::get_rgb(const std::string& name) const {
    const Param* p = find(name);
    if (!p || p->type == ParamType::Texture) return std::nullopt;
    p = find_typed(name, {ParamType::Rgb, ParamType::Spectrum});
    if (p->type == ParamType::Rgb) {
        expect_single(*p, p->numbers.size(), 3);
        return Rgb{static_cast<float>(p->numbers[0]), static_cast<float>(p->numbers[1]),
                   static_cast<float>(p->numbers[2])};
    }
    if (!p->strings.empty())
        throw SceneError(p->loc,
                         "spectrum " + in_quotes(name) + " from file or named spectrum " +
                             in_quotes(p->strings[0]) +
                             " is not supported; give rgb values or (wavelength, value) pairs");
    return spectrum_to_rgb(p->numbers);
}

std::optional<TextureRef> ParamSet::get_texture(const std::string& name) const {
    const Param* p = find(name);
    if (!p || p->type != ParamType::Texture) return std::nullopt;
    p->used = true;
    expect_single(*p, p->strings.size());
    return TextureRef{p->strings[0], p->loc};
}

std::optional<std::vector<int>> ParamSet::get_ints(const std::string& name) const {
    const Param* p = find_typed(name, {ParamType::Integer});
    if (!p) return std::nullopt;
    std::vector<int> r;
    r.reserve(p->numbers.size());
    for (double x : p->numbers) r.push_back(static_cast<int>(x));
    return r;
}

std::optional<std::vector<double>> ParamSet::get_floats(const std::string& name) const {
    const Param* p = find_typed(name, {ParamType::Float});
    if (!p) return std::nullopt;
    return p->numbers;
}

std::optional<std::vector<double>> ParamSet::get_point3s(const std::string& name) const {
    const Param* p = find_typed(name, {ParamType::Point3, ParamType::Vector3, ParamType::Normal});
    if (!p) return std::nullopt;
    return p->numbers;
}

std::optional<std::vector<double>> ParamSet::get_point2s(const std::string& name) const {
    const Param* p = find_typed(name, {ParamType::Point2, ParamType::Vector2, ParamType::Float});
    if (!p) return std::nullopt;
    if (p->numbers.size() % 2 != 0)
        throw SceneError(p->loc, "parameter " + in_quotes(name) + " needs pairs of values, got " +
                                     std::to_string(p->numbers.size()));
    return p->numbers;
}

void ParamSet::check_unused(const std::string& what, const WarningSink& warn,
                            const std::vector<std::string>& ignored) const {
    for (const Param& p : m_params) {
        if (p.used) continue;
        if (std::find(ignored.begin(), ignored.end(), p.name) != ignored.end()) {
            if (warn)
                warn(format_warning(p.loc, "parameter " + in_quotes(p.name) + " of " + what +
                                               " is not supported by cmam; ignored"));
            continue;
        }
        if (warn)
            warn(format_warning(p.loc, "unknown parameter " + in_quotes(p.name) + " for " + what +
                                           " (pbrt-v3 reports it unused); ignored"));
    }
}

namespace {
// The CIE 1931 2-degree standard observer's colour matching functions x, y and z, every 5 nm
// from 360 to 830 nm, as the CIE tabulates them (the table Debian's colord-data package ships as
// CIE1931-2deg-XYZ.cmf). pbrt-v3 integrates spectra against the same observer.
constexpr int kCieCount = 95;
constexpr double kCieX[kCieCount] = {
    0.0001299,    0.0002321,    0.0004149,    0.0007416,    0.001368,     0.002236,
    0.004243,     0.00765,      0.01431,      0.02319,      0.04351,      0.07763,
    0.13438,      0.21477,      0.2839,       0.3285,       0.34828,      0.34806,
    0.3362,       0.3187,       0.2908,       0.2511,       0.19536,      0.1421,
    0.09564,      0.05795001,   0.03201,      0.0147,       0.0049,       0.0024,
    0.0093,       0.0291,       0.06327,      0.1096,       0.1655,       0.2257499,
    0.2904,       0.3597,       0.4334499,    0.5120501,    0.5945,       0.6784,
    0.7621,       0.8425,       0.9163,       0.9786,       1.0263,       1.0567,
    1.0622,       1.0456,       1.0026,       0.9384,       0.8544499,    0.7514,
    0.6424,       0.5419,       0.4479,       0.3608,       0.2835,       0.2187,
    0.1649,       0.1212,       0.0874,       0.0636,       0.04677,      0.0329,
    0.0227,       0.01584,      0.01135916,   0.008110916,  0.005790346,  0.004109457,
    0.002899327,  0.00204919,   0.001439971,  0.0009999493, 0.0006900786, 0.0004760213,
    0.0003323011, 0.0002348261, 0.0001661505, 0.000117413,  8.307527e-05, 5.870652e-05,
    4.150994e-05, 2.935326e-05, 2.067383e-05, 1.455977e-05, 1.025398e-05, 7.221456e-06,
    5.085868e-06, 3.581652e-06, 2.522525e-06, 1.776509e-06, 1.251141e-06};
constexpr double kCieY[kCieCount] = {
    3.917e-06,  6.965e-06,  1.239e-05,  2.202e-05,  3.9e-05,    6.4e-05,    0.00012,    0.000217,
    0.000396,   0.00064,    0.00121,    0.00218,    0.004,      0.0073,     0.0116,     0.01684,
    0.023,      0.0298,     0.038,      0.048,      0.06,       0.0739,     0.09098,    0.1126,
    0.13902,    0.1693,     0.20802,    0.2586,     0.323,      0.4073,     0.503,      0.6082,
    0.71,       0.7932,     0.862,      0.9148501,  0.954,      0.9803,     0.9949501,  1.0,
    0.995,      0.9786,     0.952,      0.9154,     0.87,       0.8163,     0.757,      0.6949,
    0.631,      0.5668,     0.503,      0.4412,     0.381,      0.321,      0.265,      0.217,
    0.175,      0.1382,     0.107,      0.0816,     0.061,      0.04458,    0.032,      0.0232,
    0.017,      0.01192,    0.00821,    0.005723,   0.004102,   0.002929,   0.002091,   0.001484,
    0.001047,   0.00074,    0.00052,    0.0003611,  0.0002492,  0.0001719,  0.00012,    8.48e-05,
    6e-05,      4.24e-05,   3e-05,      2.12e-05,   1.499e-05,  1.06e-05,   7.4657e-06, 5.2578e-06,
    3.7029e-06, 2.6078e-06, 1.8366e-06, 1.2934e-06, 9.1093e-07, 6.4153e-07, 4.5181e-07};
constexpr double kCieZ[kCieCount] = {0.0006061,  0.001086,    0.001946,   0.003486,    0.006450001,
                                     0.01054999, 0.02005001,  0.03621,    0.06785001,  0.1102,
                                     0.2074,     0.3713,      0.6456,     1.0390501,   1.3856,
                                     1.62296,    1.74706,     1.7826,     1.77211,     1.7441,
                                     1.6692,     1.5281,      1.28764,    1.0419,      0.8129501,
                                     0.6162,     0.46518,     0.3533,     0.272,       0.2123,
                                     0.1582,     0.1117,      0.07824999, 0.05725001,  0.04216,
                                     0.02984,    0.0203,      0.0134,     0.008749999, 0.005749999,
                                     0.0039,     0.002749999, 0.0021,     0.0018,      0.001650001,
                                     0.0014,     0.0011,      0.001,      0.0008,      0.0006,
                                     0.00034,    0.00024,     0.00019,    0.0001,      4.999999e-05,
                                     3e-05,      2e-05,       1e-05,      0,           0,
                                     0,          0,           0,          0,           0,
                                     0,          0,           0,          0,           0,
                                     0,          0,           0,          0,           0,
                                     0,          0,           0,          0,           0,
                                     0,          0,           0,          0,           0,
                                     0,          0,           0,          0,           0,
                                     0,          0,           0,          0,           0};

// The observer at wavelength l (nm, within [360, 830]), linear between the 5 nm entries.
double cie(const double* table, double l) {
    const double f = (l - 360) / 5;
    const int i = std::min(static_cast<int>(f), kCieCount - 2);
    return table[i] + (f - i) * (table[i + 1] - table[i]);
}

double interpolate(const std::vector<std::pair<double, double>>& s, double l) {
    if (l <= s.front().first) return s.front().second;
    if (l >= s.back().first) return s.back().second;
    auto it = std::lower_bound(s.begin(), s.end(), l,
                               [](const auto& a, double x) { return a.first < x; });
    auto prev = it - 1;
    double t = (l - prev->first) / (it->first - prev->first);
    return prev->second + t * (it->second - prev->second);
}
}  // namespace

Rgb spectrum_to_rgb(const std::vector<double>& pairs) {
    std::vector<std::pair<double, double>> s;
    for (std::size_t i = 0; i + 1 < pairs.size(); i += 2) s.emplace_back(pairs[i], pairs[i + 1]);
    // Sums over 1 nm steps, as pbrt-v3's RGBSpectrum::FromSampled, divided as it divides them:
    // by the integral of y times 471 / 470 (its 471 samples over 470 nm), so a constant 1 has
    // Y = 470 / 471, not 1, in pbrt-v3 and here alike.
    double x = 0, y = 0, z = 0, yint = 0;
    for (int nm = 360; nm <= 830; ++nm) {
        const double l = nm, v = interpolate(s, l), cy = cie(kCieY, l);
        x += v * cie(kCieX, l);
        y += v * cy;
        z += v * cie(kCieZ, l);
        yint += cy;
    }
    const double k = 470.0 / (471.0 * yint);
    x *= k;
    y *= k;
    z *= k;
    return xyz_to_rgb(x, y, z);
}

Rgb xyz_to_rgb(double x, double y, double z) {
    // The matrix pbrt-v3 uses.
    return Rgb{static_cast<float>(3.240479 * x - 1.537150 * y - 0.498535 * z),
               static_cast<float>(-0.969256 * x + 1.875991 * y + 0.041556 * z),
               static_cast<float>(0.055648 * x - 0.204043 * y + 1.057311 * z)};
}

}  // namespace cmam::pbrt
