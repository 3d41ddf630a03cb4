#include "weft/render/scene_file.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <map>
#include <nlohmann/json.hpp>
#include <utility>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_message.h"

namespace weft::render {

namespace {

using nlohmann::json;

// A real scene nests 3 deep (lights[i].center); the limit only keeps hostile
// input from building deep trees that recursive code (copy, dump) would walk.
constexpr int kMaxNesting = 64;
// A syntax error's detail is cut here: a message should not echo megabytes.
constexpr size_t kMaxSyntaxDetail = 200;

constexpr int kMaxFilmSide = 16384;
constexpr int kMaxSpp = 1 << 20;
constexpr int kMaxDepth = 10000;
constexpr int kMaxPlies = 16;
constexpr double kMaxPlyTwist = 100;
// up counts as parallel to the view direction below this sine of their angle:
// the camera frame built from cross(dir, up) would be numerically meaningless.
constexpr double kMinUpSine = 1e-6;

std::string joinNames(std::initializer_list<const char*> names) {
    std::string out;
    for (const char* n : names) out += (out.empty() ? "" : ", ") + std::string(n);
    return out;
}

const json* find(const json& object, const char* key) {
    const auto it = object.find(key);
    return it == object.end() ? nullptr : &*it;
}

// "FILE:LINE:COLUMN" of the byte at `index` (1-based line and column; the
// end of the text when index is past it).
std::string textPosition(std::string_view text, const std::string& source, size_t index) {
    index = std::min(index, text.size());
    const std::string_view before = text.substr(0, index);
    const size_t line = 1 + static_cast<size_t>(std::count(before.begin(), before.end(), '\n'));
    const size_t lineStart = before.rfind('\n');
    const size_t column = index - (lineStart == std::string_view::npos ? 0 : lineStart + 1) + 1;
    return source + ":" + std::to_string(line) + ":" + std::to_string(column);
}

// nlohmann's message without its "[json.exception...] parse error at line L,
// column C: " prefix (we print our own position), cut to a sane length.
std::string syntaxDetail(const std::string& what) {
    std::string detail = what;
    if (!detail.empty() && detail.front() == '[') {
        const size_t close = detail.find("] ");
        if (close != std::string::npos) detail.erase(0, close + 2);
    }
    if (detail.rfind("parse error", 0) == 0) {
        const size_t colon = detail.find(": ");
        if (colon != std::string::npos) detail.erase(0, colon + 2);
    }
    if (detail.size() > kMaxSyntaxDetail) detail = detail.substr(0, kMaxSyntaxDetail) + "...";
    return detail;
}

// Rejects nesting deeper than kMaxNesting before the parser builds the tree.
void checkNesting(std::string_view text, const std::string& source) {
    int depth = 0;
    bool inString = false, escaped = false;
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (inString) {
            if (escaped) {
                escaped = false;
            } else if (c == '\\') {
                escaped = true;
            } else if (c == '"') {
                inString = false;
            }
        } else if (c == '"') {
            inString = true;
        } else if (c == '[' || c == '{') {
            if (++depth > kMaxNesting)
                throw InputError(textPosition(text, source, i) + ": JSON nested deeper than " +
                                 std::to_string(kMaxNesting) + " levels");
        } else if ((c == ']' || c == '}') && depth > 0) {
            --depth;
        }
    }
}

// Builds the tree like nlohmann's own DOM parser, but a key that repeats in
// one object is an error (the default keeps the last silently) and the byte
// position of a syntax error is kept for a line:column message.
class StrictSax final : public nlohmann::json_sax<json> {
  public:
    bool null() override { return add(json(nullptr)); }
    bool boolean(bool v) override { return add(json(v)); }
    bool number_integer(number_integer_t v) override { return add(json(v)); }
    bool number_unsigned(number_unsigned_t v) override { return add(json(v)); }
    bool number_float(number_float_t v, const string_t&) override { return add(json(v)); }
    bool string(string_t& v) override { return add(json(std::move(v))); }
    bool binary(binary_t& v) override { return add(json::binary(std::move(v))); }

    bool start_object(std::size_t) override { return open(json::object()); }
    bool start_array(std::size_t) override { return open(json::array()); }
    bool end_object() override { return close(); }
    bool end_array() override { return close(); }

    bool key(string_t& k) override {
        Frame& top = stack_.back();
        auto& object = top.container->get_ref<json::object_t&>();
        if (object.count(k) != 0) {
            duplicate_ = "duplicate key " + jsonString(k);
            const std::string where = openPath();
            if (!where.empty()) duplicate_ += " in " + where;
            return false;
        }
        top.slot = &object[k];
        top.key = std::move(k);
        return true;
    }

    // position counts the bytes read. A syntax error stops on the offending
    // byte; a number overflow (406) is reported after the number, whose text
    // is lastToken: point at its first digit instead.
    bool parse_error(std::size_t position, const std::string& lastToken,
                     const nlohmann::json::exception& e) override {
        const bool overflow = e.id == 406 && lastToken.size() <= position;
        errorIndex_ = overflow ? position - lastToken.size() : (position == 0 ? 0 : position - 1);
        errorDetail_ = syntaxDetail(e.what());
        return false;
    }

    json& root() { return root_; }
    const std::string& duplicate() const { return duplicate_; }
    size_t errorIndex() const { return errorIndex_; }
    const std::string& errorDetail() const { return errorDetail_; }

  private:
    struct Frame {
        json* container;
        json* slot = nullptr;  // object: the value of the current key
        std::string key;
    };

    // Places a value in the open container (or as the root); `placed` is where it landed.
    bool add(json v, json** placed = nullptr) {
        json* at = &root_;
        if (stack_.empty()) {
            root_ = std::move(v);
        } else if (Frame& top = stack_.back(); top.container->is_array()) {
            top.container->push_back(std::move(v));
            at = &top.container->back();
        } else {
            *top.slot = std::move(v);
            at = top.slot;
        }
        if (placed != nullptr) *placed = at;
        return true;
    }
    bool open(json container) {
        json* placed = nullptr;
        add(std::move(container), &placed);
        stack_.push_back(Frame{placed, nullptr, {}});
        return true;
    }
    bool close() {
        stack_.pop_back();
        return true;
    }
    // JSON path of the innermost open container ("" for the root).
    std::string openPath() const {
        std::string path;
        for (size_t i = 0; i + 1 < stack_.size(); ++i) {
            const Frame& f = stack_[i];
            path = f.container->is_array() ? jsonIndexPath(path, f.container->size() - 1)
                                           : jsonChildPath(path, f.key);
        }
        return path;
    }

    json root_;
    std::vector<Frame> stack_;
    std::string duplicate_;
    size_t errorIndex_ = 0;
    std::string errorDetail_;
};

// Validating reader: every error names the scene file, then the JSON path.
class Reader {
  public:
    Reader(const std::string& source, const std::string& baseDir)
        : source_(source.empty() ? "scene" : source), baseDir_(baseDir) {}

    [[noreturn]] void fail(const std::string& message) const {
        throw InputError(source_ + ": " + message);
    }
    [[noreturn]] void failAt(const std::string& path, const std::string& message) const {
        fail(path + ": " + message);
    }
    [[noreturn]] void outOfRange(const std::string& path, const std::string& value,
                                 const std::string& allowed) const {
        fail(path + " = " + value + " is out of range: allowed " + allowed);
    }

    // An object with only `allowed` keys and every `required` one. Unknown keys
    // come first: a misspelt required key is reported as the typo it is.
    void checkObject(const json& j, const std::string& path,
                     std::initializer_list<const char*> allowed,
                     std::initializer_list<const char*> required) const {
        if (!j.is_object()) {
            if (path.empty())
                fail("expected a JSON object at the top level, got " + describeJson(j));
            failAt(path, "expected an object, got " + describeJson(j));
        }
        const std::string in = path.empty() ? "" : " in " + path;
        for (const auto& item : j.items()) {
            const bool known = std::any_of(allowed.begin(), allowed.end(),
                                           [&](const char* k) { return item.key() == k; });
            if (!known)
                fail("unknown key " + jsonString(item.key()) + in +
                     " (allowed: " + joinNames(allowed) + ")");
        }
        for (const char* k : required)
            if (!j.contains(k)) fail("missing required key \"" + std::string(k) + "\"" + in);
    }

    double number(const json& v, const std::string& path) const {
        if (!v.is_number()) failAt(path, "expected a number, got " + describeJson(v));
        const double x = v.get<double>();
        if (!std::isfinite(x)) failAt(path, "expected a finite number, got " + formatNumber(x));
        return x;
    }

    double numberIn(const json& v, const std::string& path, bool ok(double),
                    const char* allowed) const {
        const double x = number(v, path);
        if (!ok(x)) outOfRange(path, formatNumber(x), allowed);
        return x;
    }

    // An integer in [lo, hi] (0 <= hi). A number with no fractional part
    // counts (64.0, 1e3); 2.5 does not.
    int64_t integer(const json& v, const std::string& path, int64_t lo, int64_t hi) const {
        const std::string allowed = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
        // The JSON parser reads every non-negative integer as unsigned.
        if (v.is_number_unsigned()) {
            const uint64_t u = v.get<uint64_t>();
            if (u > static_cast<uint64_t>(hi) || static_cast<int64_t>(u) < lo)
                outOfRange(path, std::to_string(u), allowed);
            return static_cast<int64_t>(u);
        }
        if (v.is_number_integer()) {
            const int64_t x = v.get<int64_t>();
            if (x < lo || x > hi) outOfRange(path, std::to_string(x), allowed);
            return x;
        }
        const double x = integral(v, path);
        if (x < static_cast<double>(lo) || x > static_cast<double>(hi))
            outOfRange(path, formatNumber(x), allowed);
        return static_cast<int64_t>(x);
    }

    uint64_t seed(const json& v, const std::string& path) const {
        const char* allowed = "[0, 18446744073709551615]";
        if (v.is_number_unsigned()) return v.get<uint64_t>();
        if (v.is_number_integer()) {
            const int64_t x = v.get<int64_t>();
            if (x < 0) outOfRange(path, std::to_string(x), allowed);
            return static_cast<uint64_t>(x);
        }
        const double x = integral(v, path);
        if (x < 0 || x >= 0x1p64) outOfRange(path, formatNumber(x), allowed);
        return static_cast<uint64_t>(x);
    }

    Vec3 vec3(const json& v, const std::string& path) const {
        if (!v.is_array() || v.size() != 3)
            failAt(path, "expected an array of 3 numbers, got " + describeJson(v));
        return {number(v[0], jsonIndexPath(path, 0)), number(v[1], jsonIndexPath(path, 1)),
                number(v[2], jsonIndexPath(path, 2))};
    }

    Rgb radiance(const json& v, const std::string& path) const {
        if (!v.is_array() || v.size() != 3)
            failAt(path, "expected an array of 3 numbers (r, g, b), got " + describeJson(v));
        Rgb c;
        for (int k = 0; k < 3; ++k)
            c[k] = numberIn(
                v[k], jsonIndexPath(path, k), [](double x) { return x >= 0; }, ">= 0");
        return c;
    }

    // A file name, resolved against baseDir unless absolute; `extensions`
    // (lowercase, with the dot) lists the accepted ones, empty: any.
    std::string file(const json& v, const std::string& path,
                     std::initializer_list<const char*> extensions) const {
        if (!v.is_string()) failAt(path, "expected a file name, got " + describeJson(v));
        const std::string& name = v.get_ref<const std::string&>();
        if (name.empty()) failAt(path, "expected a file name, got the empty string");
        // The C library would stop at the NUL and open some other file.
        if (name.find('\0') != std::string::npos)
            failAt(path, "a file name cannot contain a NUL character");
        if (extensions.size() != 0) {
            const std::string ext = lowercaseExtension(name);
            if (std::none_of(extensions.begin(), extensions.end(),
                             [&](const char* e) { return ext == e; }))
                failAt(path, jsonString(name) + " has an unsupported extension (allowed: " +
                                 joinNames(extensions) + ")");
        }
        return (std::filesystem::path(baseDir_) / name).string();
    }

  private:
    // A finite number with no fractional part.
    double integral(const json& v, const std::string& path) const {
        const double x = number(v, path);
        if (x != std::floor(x)) failAt(path, "expected an integer, got " + formatNumber(x));
        return x;
    }

    std::string source_;
    std::string baseDir_;
};

bool isNonNegative(double x) { return x >= 0; }
bool isPositive(double x) { return x > 0; }

// v / its largest component: a direction whose length neither overflows nor
// underflows (from and to may be huge or a denormal apart). Zero stays zero.
Vec3 scaledDirection(const Vec3& v) {
    const double m = std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
    return m > 0 ? v / m : v;
}

CameraDesc readCamera(const Reader& r, const json& j) {
    r.checkObject(j, "camera", {"from", "to", "up", "fov_deg"}, {"from", "to"});
    CameraDesc c;
    c.from = r.vec3(j.at("from"), "camera.from");
    c.to = r.vec3(j.at("to"), "camera.to");
    if (const json* up = find(j, "up")) c.up = r.vec3(*up, "camera.up");
    if (const json* fov = find(j, "fov_deg"))
        c.fovDeg = r.numberIn(
            *fov, "camera.fov_deg", [](double x) { return x > 0 && x < 180; }, "(0, 180)");

    const auto vectorText = [](const Vec3& v) {
        // Appended piecewise: GCC 12 warns falsely (-Wrestrict) on "[" + string.
        std::string out = "[";
        out.append(formatNumber(v.x)).append(", ").append(formatNumber(v.y));
        return out.append(", ").append(formatNumber(v.z)).append("]");
    };
    const Vec3 view = c.to - c.from;
    if (c.from == c.to)
        r.fail("camera.to = " + vectorText(c.to) +
               " is out of range: allowed any point other than camera.from");
    if (!isFinite(view))
        r.fail(
            "camera.to - camera.from overflows (the points are too far apart): allowed a "
            "difference within the double range");
    const Vec3 d = normalize(scaledDirection(view));
    const Vec3 up = scaledDirection(c.up);
    const double upLength = length(up);
    if (upLength == 0 || length(cross(d, up)) < kMinUpSine * upLength)
        r.fail("camera.up = " + vectorText(c.up) +
               " is out of range: allowed any vector not parallel to camera.to - camera.from");
    return c;
}

FilmDesc readFilm(const Reader& r, const json& j) {
    r.checkObject(j, "film", {"width", "height"}, {});
    FilmDesc f;
    if (const json* w = find(j, "width"))
        f.width = static_cast<int>(r.integer(*w, "film.width", 1, kMaxFilmSide));
    if (const json* h = find(j, "height"))
        f.height = static_cast<int>(r.integer(*h, "film.height", 1, kMaxFilmSide));
    return f;
}

RenderDesc readRender(const Reader& r, const json& j) {
    r.checkObject(j, "render", {"spp", "max_depth", "seed"}, {});
    RenderDesc d;
    if (const json* spp = find(j, "spp"))
        d.spp = static_cast<int>(r.integer(*spp, "render.spp", 1, kMaxSpp));
    if (const json* depth = find(j, "max_depth"))
        d.maxDepth = static_cast<int>(r.integer(*depth, "render.max_depth", 1, kMaxDepth));
    if (const json* seed = find(j, "seed")) d.seed = r.seed(*seed, "render.seed");
    return d;
}

const char* typeName(LightDesc::Type t) {
    switch (t) {
        case LightDesc::Type::Sky:
            return "sky";
        case LightDesc::Type::Envmap:
            return "envmap";
        case LightDesc::Type::Sphere:
            return "sphere";
        case LightDesc::Type::Constant:
            return "constant";
    }
    return "sky";
}

LightDesc readLight(const Reader& r, const json& j, const std::string& path) {
    if (!j.is_object()) r.failAt(path, "expected an object, got " + describeJson(j));
    const json* type = find(j, "type");
    if (type == nullptr) r.fail("missing required key \"type\" in " + path);
    const std::string typePath = jsonChildPath(path, "type");
    const char* allowedTypes = "sky, envmap, sphere, constant";
    if (!type->is_string())
        r.failAt(typePath, std::string("expected a string (") + allowedTypes + "), got " +
                               describeJson(*type));
    const std::string& name = type->get_ref<const std::string&>();
    LightDesc l;
    if (name == "sky") {
        l.type = LightDesc::Type::Sky;
        r.checkObject(j, path, {"type", "scale"}, {});
    } else if (name == "envmap") {
        l.type = LightDesc::Type::Envmap;
        r.checkObject(j, path, {"type", "file", "scale", "rotate_deg"}, {"file"});
        l.file = r.file(j.at("file"), jsonChildPath(path, "file"), {".exr", ".hdr"});
        if (const json* rot = find(j, "rotate_deg"))
            l.rotateDeg = r.number(*rot, jsonChildPath(path, "rotate_deg"));
    } else if (name == "sphere") {
        l.type = LightDesc::Type::Sphere;
        r.checkObject(j, path, {"type", "center", "radius", "radiance"},
                      {"center", "radius", "radiance"});
        l.center = r.vec3(j.at("center"), jsonChildPath(path, "center"));
        l.radius = r.numberIn(j.at("radius"), jsonChildPath(path, "radius"), isPositive, "> 0");
    } else if (name == "constant") {
        l.type = LightDesc::Type::Constant;
        r.checkObject(j, path, {"type", "radiance"}, {"radiance"});
    } else {
        r.failAt(typePath,
                 "unknown light type " + jsonString(name) + " (allowed: " + allowedTypes + ")");
    }
    if (const json* scale = find(j, "scale"))
        l.scale = r.numberIn(*scale, jsonChildPath(path, "scale"), isNonNegative, ">= 0");
    if (const json* radiance = find(j, "radiance"))
        l.radiance = r.radiance(*radiance, jsonChildPath(path, "radiance"));
    return l;
}

YarnDesc readYarn(const Reader& r, const json& j, const std::string& path) {
    r.checkObject(j, path, {"curves", "scale", "radius", "plies", "ply_twist", "model"},
                  {"curves", "model"});
    YarnDesc y;
    y.curves = r.file(j.at("curves"), jsonChildPath(path, "curves"), {".bcc", ".txt", ".obj"});
    y.model = r.file(j.at("model"), jsonChildPath(path, "model"), {});
    if (const json* scale = find(j, "scale"))
        y.scale = r.numberIn(*scale, jsonChildPath(path, "scale"), isPositive, "> 0");
    if (const json* radius = find(j, "radius"))
        y.radius = r.numberIn(*radius, jsonChildPath(path, "radius"), isPositive, "> 0");
    if (const json* plies = find(j, "plies"))
        y.plies = static_cast<int>(r.integer(*plies, jsonChildPath(path, "plies"), 1, kMaxPlies));
    if (const json* twist = find(j, "ply_twist"))
        y.plyTwist = r.numberIn(
            *twist, jsonChildPath(path, "ply_twist"),
            [](double x) { return std::fabs(x) <= kMaxPlyTwist; }, "[-100, 100]");
    return y;
}

json vecJson(const Vec3& v) { return json::array({v.x, v.y, v.z}); }

// FNV-1a, 64 bit.
uint64_t fnv1a(std::string_view bytes) {
    uint64_t h = 0xcbf29ce484222325ULL;
    for (const char c : bytes) {
        h ^= static_cast<unsigned char>(c);
        h *= 0x100000001b3ULL;
    }
    return h;
}

std::string hex16(uint64_t v) {
    char buffer[17];
    std::snprintf(buffer, sizeof buffer, "%016" PRIx64, v);
    return buffer;
}

}  // namespace

SceneDesc parseScene(const json& j, const std::string& pathForErrors, const std::string& baseDir) {
    const Reader r(pathForErrors, baseDir);
    r.checkObject(j, "", {"camera", "film", "render", "lights", "yarns"}, {"camera"});
    SceneDesc s;
    s.path = pathForErrors;
    s.baseDir = baseDir;
    s.camera = readCamera(r, j.at("camera"));
    if (const json* film = find(j, "film")) s.film = readFilm(r, *film);
    if (const json* render = find(j, "render")) s.render = readRender(r, *render);
    if (const json* lights = find(j, "lights")) {
        if (!lights->is_array())
            r.failAt("lights", "expected an array of lights, got " + describeJson(*lights));
        for (size_t i = 0; i < lights->size(); ++i)
            s.lights.push_back(readLight(r, (*lights)[i], jsonIndexPath("lights", i)));
    }
    if (const json* yarns = find(j, "yarns")) {
        if (!yarns->is_array())
            r.failAt("yarns", "expected an array of yarns, got " + describeJson(*yarns));
        for (size_t i = 0; i < yarns->size(); ++i)
            s.yarns.push_back(readYarn(r, (*yarns)[i], jsonIndexPath("yarns", i)));
    }
    return s;
}

SceneDesc parseSceneText(std::string_view text, const std::string& pathForErrors,
                         const std::string& baseDir) {
    const std::string source = pathForErrors.empty() ? "scene" : pathForErrors;
    checkNesting(text, source);
    StrictSax sax;
    if (!json::sax_parse(text.begin(), text.end(), &sax)) {
        if (!sax.duplicate().empty()) throw InputError(source + ": " + sax.duplicate());
        throw InputError(textPosition(text, source, sax.errorIndex()) +
                         ": malformed JSON: " + sax.errorDetail());
    }
    return parseScene(sax.root(), pathForErrors, baseDir);
}

SceneDesc loadScene(const std::string& path) {
    const std::string text = readFile(path);
    // An absolute folder, so that the resolved paths (and toJson) do not
    // depend on the working directory of whoever reads them later.
    std::error_code ec;
    std::filesystem::path absolute = std::filesystem::absolute(path, ec);
    if (ec) absolute = path;
    return parseSceneText(text, path, absolute.parent_path().string());
}

json toJson(const SceneDesc& scene) {
    json j = json::object();
    const CameraDesc& c = scene.camera;
    j["camera"] = {{"from", vecJson(c.from)},
                   {"to", vecJson(c.to)},
                   {"up", vecJson(c.up)},
                   {"fov_deg", c.fovDeg}};
    j["film"] = {{"width", scene.film.width}, {"height", scene.film.height}};
    j["render"] = {{"spp", scene.render.spp},
                   {"max_depth", scene.render.maxDepth},
                   {"seed", scene.render.seed}};
    json lights = json::array();
    for (const LightDesc& l : scene.lights) {
        json lj = {{"type", typeName(l.type)}};
        switch (l.type) {
            case LightDesc::Type::Sky:
                lj["scale"] = l.scale;
                break;
            case LightDesc::Type::Envmap:
                lj["file"] = l.file;
                lj["scale"] = l.scale;
                lj["rotate_deg"] = l.rotateDeg;
                break;
            case LightDesc::Type::Sphere:
                lj["center"] = vecJson(l.center);
                lj["radius"] = l.radius;
                lj["radiance"] = rgbJson(l.radiance);
                break;
            case LightDesc::Type::Constant:
                lj["radiance"] = rgbJson(l.radiance);
                break;
        }
        lights.push_back(std::move(lj));
    }
    j["lights"] = std::move(lights);
    json yarns = json::array();
    for (const YarnDesc& y : scene.yarns) {
        json yj = {{"curves", y.curves},
                   {"scale", y.scale},
                   {"plies", y.plies},
                   {"ply_twist", y.plyTwist},
                   {"model", y.model}};
        if (y.radius) yj["radius"] = *y.radius;
        yarns.push_back(std::move(yj));
    }
    j["yarns"] = std::move(yarns);
    return j;
}

std::string sceneHash(const SceneDesc& scene) {
    json j = toJson(scene);
    const std::string source = scene.path.empty() ? "scene" : scene.path;
    // A file referenced twice (one model for many yarns) is read once.
    std::map<std::string, std::string> digests;
    const auto digest = [&](json& value, const std::string& jsonPath) {
        const std::string path = value.get<std::string>();
        auto it = digests.find(path);
        if (it == digests.end()) {
            std::string bytes;
            try {
                bytes = readFile(path);
            } catch (const InputError& e) {
                throw InputError(source + ": " + jsonPath + ": " + e.what());
            }
            // The contents, not the path: a scene folder copied elsewhere keeps its hash.
            it = digests
                     .emplace(path,
                              "fnv1a64:" + hex16(fnv1a(bytes)) + ":" + std::to_string(bytes.size()))
                     .first;
        }
        value = it->second;
    };
    for (size_t i = 0; i < scene.lights.size(); ++i)
        if (scene.lights[i].type == LightDesc::Type::Envmap)
            digest(j["lights"][i]["file"], jsonIndexPath("lights", i) + ".file");
    for (size_t i = 0; i < scene.yarns.size(); ++i) {
        digest(j["yarns"][i]["curves"], jsonIndexPath("yarns", i) + ".curves");
        digest(j["yarns"][i]["model"], jsonIndexPath("yarns", i) + ".model");
    }
    // Object keys dump sorted (std::map), so the text is canonical.
    return hex16(fnv1a("weft scene hash 1\n" + j.dump()));
}

}  // namespace weft::render
