#include "pbrt/params.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cmam::pbrt {

namespace {

// Every type name a parameter declaration may use. The first name of each type is the one
// printed; the aliases pbrt-v3 also reads are not listed in messages. "blackbody" is pbrt-v3's
// own type, read into a sampled spectrum.
struct ParamTypeName {
    ParamType type;
    const char* name;
    bool listed;
};
constexpr ParamTypeName kParamTypeNames[] = {
    {ParamType::Integer, "integer", true},   {ParamType::Float, "float", true},
    {ParamType::Point2, "point2", true},     {ParamType::Vector2, "vector2", true},
    {ParamType::Point3, "point3", true},     {ParamType::Point3, "point", false},
    {ParamType::Vector3, "vector3", true},   {ParamType::Vector3, "vector", false},
    {ParamType::Normal, "normal", true},     {ParamType::Normal, "normal3", false},
    {ParamType::Rgb, "rgb", true},           {ParamType::Rgb, "color", false},
    {ParamType::Spectrum, "spectrum", true}, {ParamType::Spectrum, "blackbody", true},
    {ParamType::Bool, "bool", true},         {ParamType::String, "string", true},
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
        throw SceneError(p.loc, std::string(to_string(p.type)) + " parameter " + in_quotes(p.name) +
                                    " needs a multiple of " + std::to_string(k) + " values, got " +
                                    std::to_string(p.numbers.size()));
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
// CIE 1931 2-degree colour matching functions, multi-lobe Gaussian fit
// (Wyman, Sloan & Shirley, JCGT 2013), wavelength in nm.
double g(double x, double mu, double s1, double s2) {
    double t = (x - mu) / (x < mu ? s1 : s2);
    return std::exp(-0.5 * t * t);
}
double cie_x(double l) {
    return 1.056 * g(l, 599.8, 37.9, 31.0) + 0.362 * g(l, 442.0, 16.0, 26.7) -
           0.065 * g(l, 501.1, 20.4, 26.2);
}
double cie_y(double l) {
    return 0.821 * g(l, 568.8, 46.9, 40.5) + 0.286 * g(l, 530.9, 16.3, 31.1);
}
double cie_z(double l) {
    return 1.217 * g(l, 437.0, 11.8, 36.0) + 0.681 * g(l, 459.0, 26.0, 13.8);
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
    double x = 0, y = 0, z = 0, yint = 0;
    for (double l = 360; l <= 830; l += 1) {
        double v = interpolate(s, l);
        x += v * cie_x(l);
        y += v * cie_y(l);
        z += v * cie_z(l);
        yint += cie_y(l);
    }
    x /= yint;
    y /= yint;
    z /= yint;
    // XYZ to linear sRGB (the matrix pbrt-v3 uses).
    return Rgb{static_cast<float>(3.240479 * x - 1.537150 * y - 0.498535 * z),
               static_cast<float>(-0.969256 * x + 1.875991 * y + 0.041556 * z),
               static_cast<float>(0.055648 * x - 0.204043 * y + 1.057311 * z)};
}

}  // namespace cmam::pbrt
