#include "weft/render/scene_objects.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_message.h"
#include "weft/core/text_parse.h"
#include "weft/render/scene_limits.h"
#include "weft/render/scene_reader.h"
#include "weft/render/surface_bsdf.h"

namespace weft::render {

namespace {

SurfaceMaterialDesc readMaterial(const JsonObjectReader& object) {
    SurfaceMaterialDesc m;
    if (!object.has("material")) return m;
    JsonObjectReader r = object.object("material");
    r.allowKeys({"type", "reflectance", "colour", "roughness"});
    const size_t type = r.oneOf("type", {"diffuse", "conductor"});
    m.type = type == 0 ? SurfaceMaterialDesc::Type::Diffuse : SurfaceMaterialDesc::Type::Conductor;
    const auto rgb = [&](std::string_view key) {
        const std::vector<double> c = r.numbers(key, 3, NumberRange::closed(0, 1), "(r, g, b)");
        return Rgb(c[0], c[1], c[2]);
    };
    if (m.type == SurfaceMaterialDesc::Type::Diffuse) {
        r.allowKeys({"type", "reflectance"});
        if (r.has("reflectance")) m.reflectance = rgb("reflectance");
    } else {
        r.allowKeys({"type", "colour", "roughness"});
        if (r.has("colour")) m.colour = rgb("colour");
        if (r.has("roughness"))
            m.roughness =
                r.number("roughness", NumberRange::closed(ConductorBsdf::kMinRoughness, 1));
    }
    return m;
}

nlohmann::json materialJson(const SurfaceMaterialDesc& m) {
    if (m.type == SurfaceMaterialDesc::Type::Diffuse)
        return {{"type", "diffuse"}, {"reflectance", rgbJson(m.reflectance)}};
    return {{"type", "conductor"}, {"colour", rgbJson(m.colour)}, {"roughness", m.roughness}};
}

// The rectangle's first side: world x or z (whichever is less aligned with
// n; x on a tie, so a floor is wide along x) projected onto the plane.
Vec3 rectangleU(const Vec3& n) {
    const Vec3 axis = std::abs(n.x) <= std::abs(n.z) ? Vec3{1, 0, 0} : Vec3{0, 0, 1};
    return normalize(axis - n * dot(axis, n));
}

}  // namespace

ObjectDesc readObject(JsonObjectReader r, const std::string& baseDir) {
    ObjectDesc o;
    const size_t type = r.oneOf("type", {"rectangle", "mesh"});
    if (type == 0) {
        r.allowKeys({"type", "center", "normal", "size", "material"});
        o.type = ObjectDesc::Type::Rectangle;
        o.center = readSceneVec3(r, "center");
        if (r.has("normal")) {
            o.normal = readSceneVec3(r, "normal");
            if (o.normal == Vec3{0, 0, 0})
                r.failOutOfRange("normal", "[0, 0, 0]", "any vector but zero");
            o.normal = normalizeAnyLength(o.normal);
        }
        if (r.has("size")) {
            const std::vector<double> s =
                r.numbers("size", 2, sceneLengthRange(), "(width, height)");
            o.size = {s[0], s[1]};
        }
    } else {
        r.allowKeys({"type", "file", "scale", "translate", "material"});
        o.type = ObjectDesc::Type::Mesh;
        o.file = readFileName(r, "file", baseDir, {".obj", ".ply"});
        if (r.has("scale")) o.scale = r.number("scale", sceneLengthRange());
        if (r.has("translate")) o.translate = readSceneVec3(r, "translate");
    }
    o.material = readMaterial(r);
    return o;
}

nlohmann::json toJson(const ObjectDesc& o) {
    nlohmann::json j;
    if (o.type == ObjectDesc::Type::Rectangle)
        j = {{"type", "rectangle"},
             {"center", vecJson(o.center)},
             {"normal", vecJson(o.normal)},
             {"size", {o.size[0], o.size[1]}}};
    else
        j = {{"type", "mesh"},
             {"file", o.file},
             {"scale", o.scale},
             {"translate", vecJson(o.translate)}};
    j["material"] = materialJson(o.material);
    return j;
}

Triangles parseObjTriangles(std::string_view text, const std::string& path) {
    Triangles t;
    std::vector<uint32_t> face;
    forEachLine(text, [&](size_t lineNo, std::string_view raw) {
        const auto fail = [&](const std::string& what) {
            throw InputError(path + ":" + std::to_string(lineNo) + ": " + what);
        };
        const std::vector<std::string_view> tok = splitWhitespace(raw.substr(0, raw.find('#')));
        if (tok.empty()) return;
        if (tok[0] == "v") {
            double p[3];
            if (tok.size() < 4 || tok.size() > 5 || !parseNumber(tok[1], &p[0]) ||
                !parseNumber(tok[2], &p[1]) || !parseNumber(tok[3], &p[2]))
                fail("expected a vertex 'v x y z', got '" + printable(raw) + "'");
            for (double v : p)
                if (!std::isfinite(v) || std::abs(v) > kMaxSceneCoordinate)
                    fail("vertex coordinate out of range: allowed finite, within +-" +
                         formatNumber(kMaxSceneCoordinate));
            t.vertices.push_back({p[0], p[1], p[2]});
        } else if (tok[0] == "f") {
            if (tok.size() < 4)
                fail("a face needs at least 3 vertices, got '" + printable(raw) + "'");
            face.clear();
            for (size_t k = 1; k < tok.size(); ++k) {
                const std::string_view first = tok[k].substr(0, tok[k].find('/'));
                long long index = 0;
                if (!parseNumber(first, &index) || index == 0)
                    fail("expected a vertex index (1-based, or negative from the end), got '" +
                         std::string(printable(tok[k])) + "'");
                const long long count = static_cast<long long>(t.vertices.size());
                const long long resolved = index > 0 ? index - 1 : count + index;
                if (resolved < 0 || resolved >= count)
                    fail("vertex index " + std::to_string(index) +
                         " is out of range: " + std::to_string(count) + " vertices so far");
                face.push_back(static_cast<uint32_t>(resolved));
            }
            for (size_t k = 1; k + 1 < face.size(); ++k) {
                if (static_cast<int64_t>(t.indices.size()) >= kMaxSceneTriangles)
                    fail("more than " + std::to_string(kMaxSceneTriangles) +
                         " triangles: the most a scene takes");
                t.indices.push_back({face[0], face[k], face[k + 1]});
            }
        }
    });
    if (t.indices.empty()) throw InputError(path + ": no faces ('f' lines): nothing to draw");
    return t;
}

Triangles readMeshTriangles(const std::string& path) {
    const std::string bytes = readFile(path);
    return lowercaseExtension(path) == ".ply" ? parsePlyTriangles(bytes, path)
                                              : parseObjTriangles(bytes, path);
}

Triangles objectTriangles(const ObjectDesc& o) {
    if (o.type == ObjectDesc::Type::Rectangle) {
        const Vec3 u = rectangleU(o.normal) * (0.5 * o.size[0]);
        const Vec3 v = cross(o.normal, normalize(u)) * (0.5 * o.size[1]);
        Triangles t;
        t.vertices = {o.center - u - v, o.center + u - v, o.center + u + v, o.center - u + v};
        t.indices = {{0, 1, 2}, {0, 2, 3}};
        return t;
    }
    Triangles t = readMeshTriangles(o.file);
    for (Vec3& p : t.vertices) {
        p = o.scale * p + o.translate;
        if (!(std::abs(p.x) <= kMaxSceneCoordinate && std::abs(p.y) <= kMaxSceneCoordinate &&
              std::abs(p.z) <= kMaxSceneCoordinate))
            throw InputError(o.file + ": a vertex placed by scale and translate lies beyond +-" +
                             formatNumber(kMaxSceneCoordinate));
    }
    return t;
}

std::unique_ptr<Bsdf> makeSurfaceBsdf(const SurfaceMaterialDesc& m, const std::string& what) {
    if (m.type == SurfaceMaterialDesc::Type::Diffuse)
        return std::make_unique<DiffuseBsdf>(m.reflectance, what + ".reflectance");
    return std::make_unique<ConductorBsdf>(m.colour, m.roughness, what);
}

}  // namespace weft::render
