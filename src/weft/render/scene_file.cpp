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
#include "weft/core/json_reader.h"

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
            duplicatePath_ = openPath();
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
    // "duplicate key \"k\"" ("" for none), and the JSON path of its object.
    const std::string& duplicate() const { return duplicate_; }
    const std::string& duplicatePath() const { return duplicatePath_; }
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
    std::string duplicate_, duplicatePath_;
    size_t errorIndex_ = 0;
    std::string errorDetail_;
};

// Scene value kinds over the shared strict reader (core/json_reader.h).

Vec3 readVec3(const JsonObjectReader& r, std::string_view key) {
    const std::vector<double> v = r.numbers(key, 3);
    return {v[0], v[1], v[2]};
}

// Linear RGB radiance, each channel >= 0.
Rgb readRadiance(const JsonObjectReader& r, std::string_view key) {
    const std::vector<double> v = r.numbers(key, 3, NumberRange::atLeast(0), "(r, g, b)");
    return {v[0], v[1], v[2]};
}

// A file name, resolved against baseDir unless absolute; `extensions`
// (lowercase, with the dot) lists the accepted ones, empty: any.
std::string readFileName(const JsonObjectReader& r, std::string_view key,
                         const std::string& baseDir,
                         std::initializer_list<const char*> extensions) {
    const json& v = r.value(key);
    if (!v.is_string()) r.fail(key, "expected a file name, got " + describeJson(v));
    const std::string& name = v.get_ref<const std::string&>();
    if (name.empty()) r.fail(key, "expected a file name, got the empty string");
    // The C library would stop at the NUL and open some other file.
    if (name.find('\0') != std::string::npos)
        r.fail(key, "a file name cannot contain a NUL character");
    if (extensions.size() != 0) {
        const std::string ext = lowercaseExtension(name);
        if (std::none_of(extensions.begin(), extensions.end(),
                         [&](const char* e) { return ext == e; }))
            r.fail(key, jsonString(name) + " has an unsupported extension (allowed: " +
                            joinNames(extensions) + ")");
    }
    return (std::filesystem::path(baseDir) / name).string();
}

// v / its largest component: a direction whose length neither overflows nor
// underflows (from and to may be huge or a denormal apart). Zero stays zero.
Vec3 scaledDirection(const Vec3& v) {
    const double m = std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
    return m > 0 ? v / m : v;
}

CameraDesc readCamera(const JsonObjectReader& scene) {
    const JsonObjectReader r = scene.object("camera", {"from", "to", "up", "fov_deg"});
    CameraDesc c;
    c.from = readVec3(r, "from");
    c.to = readVec3(r, "to");
    if (r.has("up")) c.up = readVec3(r, "up");
    if (r.has("fov_deg")) c.fovDeg = r.number("fov_deg", NumberRange::open(0, 180));

    const auto vectorText = [](const Vec3& v) {
        // Appended piecewise: GCC 12 warns falsely (-Wrestrict) on "[" + string.
        std::string out = "[";
        out.append(formatNumber(v.x)).append(", ").append(formatNumber(v.y));
        return out.append(", ").append(formatNumber(v.z)).append("]");
    };
    const Vec3 view = c.to - c.from;
    if (c.from == c.to)
        r.failOutOfRange("to", vectorText(c.to), "any point other than camera.from");
    if (!isFinite(view))
        throwJsonError(r.source(), "",
                       "camera.to - camera.from overflows (the points are too far apart): "
                       "allowed a difference within the double range");
    const Vec3 d = normalize(scaledDirection(view));
    const Vec3 up = scaledDirection(c.up);
    const double upLength = length(up);
    if (upLength == 0 || length(cross(d, up)) < kMinUpSine * upLength)
        r.failOutOfRange("up", vectorText(c.up),
                         "any vector not parallel to camera.to - camera.from");
    return c;
}

FilmDesc readFilm(const JsonObjectReader& scene) {
    const JsonObjectReader r = scene.object("film", {"width", "height"});
    FilmDesc f;
    if (r.has("width")) f.width = static_cast<int>(r.integer("width", {1, kMaxFilmSide}));
    if (r.has("height")) f.height = static_cast<int>(r.integer("height", {1, kMaxFilmSide}));
    return f;
}

RenderDesc readRender(const JsonObjectReader& scene) {
    const JsonObjectReader r = scene.object("render", {"spp", "max_depth", "seed"});
    RenderDesc d;
    if (r.has("spp")) d.spp = static_cast<int>(r.integer("spp", {1, kMaxSpp}));
    if (r.has("max_depth")) d.maxDepth = static_cast<int>(r.integer("max_depth", {1, kMaxDepth}));
    if (r.has("seed")) d.seed = r.unsignedInteger("seed");
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

// The type decides the other keys: it is read before they are checked.
LightDesc readLight(JsonObjectReader r, const std::string& baseDir) {
    using Type = LightDesc::Type;
    constexpr Type kTypes[] = {Type::Sky, Type::Envmap, Type::Sphere, Type::Constant};
    LightDesc l;
    l.type = kTypes[r.oneOf("type", {typeName(kTypes[0]), typeName(kTypes[1]), typeName(kTypes[2]),
                                     typeName(kTypes[3])})];
    const NumberRange scale = NumberRange::atLeast(0);
    switch (l.type) {
        case Type::Sky:
            r.allowKeys({"type", "scale"});
            if (r.has("scale")) l.scale = r.number("scale", scale);
            break;
        case Type::Envmap:
            r.allowKeys({"type", "file", "scale", "rotate_deg"});
            l.file = readFileName(r, "file", baseDir, {".exr", ".hdr"});
            if (r.has("rotate_deg")) l.rotateDeg = r.number("rotate_deg");
            if (r.has("scale")) l.scale = r.number("scale", scale);
            break;
        case Type::Sphere:
            r.allowKeys({"type", "center", "radius", "radiance"});
            l.center = readVec3(r, "center");
            l.radius = r.number("radius", NumberRange::greaterThan(0));
            l.radiance = readRadiance(r, "radiance");
            break;
        case Type::Constant:
            r.allowKeys({"type", "radiance"});
            l.radiance = readRadiance(r, "radiance");
            break;
    }
    return l;
}

YarnDesc readYarn(JsonObjectReader r, const std::string& baseDir) {
    r.allowKeys({"curves", "scale", "radius", "plies", "ply_twist", "model"});
    YarnDesc y;
    y.curves = readFileName(r, "curves", baseDir, {".bcc", ".txt", ".obj"});
    y.model = readFileName(r, "model", baseDir, {});
    if (r.has("scale")) y.scale = r.number("scale", NumberRange::greaterThan(0));
    if (r.has("radius")) y.radius = r.number("radius", NumberRange::greaterThan(0));
    if (r.has("plies")) y.plies = static_cast<int>(r.integer("plies", {1, kMaxPlies}));
    if (r.has("ply_twist"))
        y.plyTwist = r.number("ply_twist", NumberRange::closed(-kMaxPlyTwist, kMaxPlyTwist));
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
    JsonObjectReader r(j, pathForErrors.empty() ? "scene" : pathForErrors, "",
                       JsonIntegers::WholeNumbers);
    r.allowKeys({"camera", "film", "render", "lights", "yarns"});
    SceneDesc s;
    s.path = pathForErrors;
    s.baseDir = baseDir;
    s.camera = readCamera(r);
    if (r.has("film")) s.film = readFilm(r);
    if (r.has("render")) s.render = readRender(r);
    if (r.has("lights"))
        for (JsonObjectReader& light : r.objects("lights"))
            s.lights.push_back(readLight(std::move(light), baseDir));
    if (r.has("yarns"))
        for (JsonObjectReader& yarn : r.objects("yarns"))
            s.yarns.push_back(readYarn(std::move(yarn), baseDir));
    return s;
}

SceneDesc parseSceneText(std::string_view text, const std::string& pathForErrors,
                         const std::string& baseDir) {
    const std::string source = pathForErrors.empty() ? "scene" : pathForErrors;
    checkNesting(text, source);
    StrictSax sax;
    if (!json::sax_parse(text.begin(), text.end(), &sax)) {
        if (!sax.duplicate().empty()) throwJsonError(source, sax.duplicatePath(), sax.duplicate());
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
