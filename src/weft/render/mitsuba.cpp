// Mitsuba 3 scene files in and out (mitsuba.h, docs/mitsuba.md).
#include "weft/render/mitsuba.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <pugixml.hpp>
#include <set>
#include <sstream>

#include "weft/core/curves.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/image_io.h"
#include "weft/core/math.h"
#include "weft/core/text_parse.h"
#include "weft/render/catmull_rom.h"
#include "weft/render/environment_light.h"
#include "weft/render/scene.h"
#include "weft/render/scene_objects.h"
#include "weft/yarn/family_model.h"

namespace weft::render {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// weft's largest max_depth, what Mitsuba's -1 (no limit) becomes.
constexpr int kUnlimitedDepth = 10000;
// Points per span when a bsplinecurve or a Catmull-Rom yarn becomes a polyline.
constexpr int kSplineSteps = 8;

// An affine map x -> A x + t (Mitsuba's to_world, without projection).
struct Affine {
    std::array<std::array<double, 3>, 3> a{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    Vec3 t;

    Vec3 point(const Vec3& p) const { return vector(p) + t; }
    Vec3 vector(const Vec3& v) const {
        return {a[0][0] * v.x + a[0][1] * v.y + a[0][2] * v.z,
                a[1][0] * v.x + a[1][1] * v.y + a[1][2] * v.z,
                a[2][0] * v.x + a[2][1] * v.y + a[2][2] * v.z};
    }
    // this after `first`: x -> this(first(x)).
    Affine after(const Affine& first) const {
        Affine r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                r.a[i][j] =
                    a[i][0] * first.a[0][j] + a[i][1] * first.a[1][j] + a[i][2] * first.a[2][j];
        r.t = point(first.t);
        return r;
    }
    double determinant() const {
        return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
               a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
               a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    }
    // The scale of a similarity (rotation x uniform scale x translation), or
    // nullopt when the linear part is not one (a shear or an unequal scale).
    std::optional<double> similarityScale() const {
        const double s = std::cbrt(std::abs(determinant()));
        if (!(s > 0) || !std::isfinite(s)) return std::nullopt;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                const double dot = a[0][i] * a[0][j] + a[1][i] * a[1][j] + a[2][i] * a[2][j];
                if (std::abs(dot - (i == j ? s * s : 0.0)) > 1e-6 * s * s) return std::nullopt;
            }
        return s;
    }
    bool isIdentity() const {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                if (a[i][j] != (i == j ? 1.0 : 0.0)) return false;
        return t.x == 0 && t.y == 0 && t.z == 0;
    }
};

Affine rotation(Vec3 axis, double degrees) {
    axis = normalize(axis);
    const double r = degrees * kPi / 180, c = std::cos(r), s = std::sin(r), k = 1 - c;
    Affine m;
    m.a = {{{c + axis.x * axis.x * k, axis.x * axis.y * k - axis.z * s,
             axis.x * axis.z * k + axis.y * s},
            {axis.y * axis.x * k + axis.z * s, c + axis.y * axis.y * k,
             axis.y * axis.z * k - axis.x * s},
            {axis.z * axis.x * k - axis.y * s, axis.z * axis.y * k + axis.x * s,
             c + axis.z * axis.z * k}}};
    return m;
}

// Mitsuba's look_at: columns (left, up, direction), translation the origin.
Affine lookAt(const Vec3& origin, const Vec3& target, const Vec3& up) {
    const Vec3 dir = normalize(target - origin);
    const Vec3 left = normalize(cross(up, dir));
    const Vec3 newUp = cross(dir, left);
    Affine m;
    m.a = {{{left.x, newUp.x, dir.x}, {left.y, newUp.y, dir.y}, {left.z, newUp.z, dir.z}}};
    m.t = origin;
    return m;
}

std::string formatNumber(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

std::string formatVec(const Vec3& v) {
    return formatNumber(v.x) + ", " + formatNumber(v.y) + ", " + formatNumber(v.z);
}

// Triangles as an OBJ file (what import writes for a moved mesh and export
// for every object: the same bytes for the same triangles).
std::string objText(const Triangles& t) {
    std::string text = "# triangles written by weft\n";
    for (const Vec3& v : t.vertices)
        text += "v " + formatNumber(v.x) + " " + formatNumber(v.y) + " " + formatNumber(v.z) + "\n";
    for (const auto& f : t.indices)
        text += "f " + std::to_string(f[0] + 1) + " " + std::to_string(f[1] + 1) + " " +
                std::to_string(f[2] + 1) + "\n";
    return text;
}

// The files of an output folder as they are made: each under a fresh name
// FOLDER/STEM.EXT (odd characters of the stem as _, -2, -3, ... on a clash),
// an input file copied once however often it is named.
class FolderFiles {
  public:
    explicit FolderFiles(std::vector<std::pair<std::string, std::string>>* files) : files_(files) {}

    std::string add(const std::string& folder, std::string stem, const std::string& ext,
                    std::string bytes) {
        for (char& c : stem)
            if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
        if (stem.empty()) stem = "file";
        std::string name = folder + "/" + stem + ext;
        for (int k = 2; used_.count(name); ++k)
            name = folder + "/" + stem + "-" + std::to_string(k) + ext;
        used_.insert(name);
        files_->push_back({name, std::move(bytes)});
        return name;
    }
    std::string copy(const std::string& source, const std::string& folder) {
        const auto it = copied_.find(source);
        if (it != copied_.end()) return it->second;
        const std::string name = add(folder, fs::path(source).stem().string(),
                                     lowercaseExtension(source), readFile(source));
        copied_[source] = name;
        return name;
    }

  private:
    std::vector<std::pair<std::string, std::string>>* files_;
    std::set<std::string> used_;
    std::map<std::string, std::string> copied_;  // source path -> name in the folder
};

// ---------------------------------------------------------------------------
// Reading the XML.

// The element tags Mitsuba 3 uses for plugins, and for properties.
const std::set<std::string> kPluginTags = {"bsdf",       "emitter", "film",    "sampler",
                                           "rfilter",    "shape",   "texture", "medium",
                                           "integrator", "sensor",  "phase",   "volume"};
const std::set<std::string> kPropertyTags = {"float",    "integer", "boolean", "string",   "rgb",
                                             "spectrum", "point",   "vector",  "transform"};

class XmlFile {
  public:
    XmlFile(std::string path, std::string text) : path_(std::move(path)), text_(std::move(text)) {}

    const std::string& path() const { return path_; }
    std::string& text() { return text_; }

    int lineOf(const pugi::xml_node& node) const {
        const ptrdiff_t offset = node.offset_debug();
        if (offset < 0 || static_cast<size_t>(offset) > text_.size()) return 0;
        return 1 + static_cast<int>(std::count(text_.begin(), text_.begin() + offset, '\n'));
    }
    [[noreturn]] void fail(const pugi::xml_node& node, const std::string& where,
                           const std::string& what) const {
        throw InputError(path_ + ":" + std::to_string(lineOf(node)) + ": " + where + ": " + what);
    }

    std::map<std::string, std::string> defines;

    // An attribute with $name replaced by its <default> (or -D) value.
    std::string attribute(const pugi::xml_node& node, const std::string& where,
                          const char* name) const {
        const pugi::xml_attribute a = node.attribute(name);
        if (!a) fail(node, where, std::string("missing attribute \"") + name + "\"");
        return substitute(node, where, a.value());
    }
    std::optional<std::string> optionalAttribute(const pugi::xml_node& node,
                                                 const std::string& where, const char* name) const {
        const pugi::xml_attribute a = node.attribute(name);
        if (!a) return std::nullopt;
        return substitute(node, where, a.value());
    }
    void allowAttributes(const pugi::xml_node& node, const std::string& where,
                         std::initializer_list<const char*> names) const {
        for (const pugi::xml_attribute& a : node.attributes()) {
            bool known = false;
            for (const char* n : names) known = known || std::string(n) == a.name();
            if (!known) {
                std::string allowed;
                for (const char* n : names) allowed += std::string(allowed.empty() ? "" : ", ") + n;
                fail(node, where,
                     std::string("unknown attribute \"") + printable(a.name()) +
                         "\" (allowed: " + allowed + ")");
            }
        }
    }

  private:
    std::string substitute(const pugi::xml_node& node, const std::string& where,
                           std::string value) const {
        std::string out;
        for (size_t i = 0; i < value.size();) {
            if (value[i] != '$') {
                out += value[i++];
                continue;
            }
            size_t j = i + 1;
            while (j < value.size() &&
                   (std::isalnum(static_cast<unsigned char>(value[j])) || value[j] == '_'))
                ++j;
            const std::string name = value.substr(i + 1, j - i - 1);
            const auto it = defines.find(name);
            if (name.empty() || it == defines.end())
                fail(node, where,
                     "\"$" + printable(name) + "\" has no <default name=\"" + printable(name) +
                         "\"> (nor -D " + printable(name) + "=...)");
            out += it->second;
            i = j;
        }
        return out;
    }

    std::string path_, text_;
};

std::vector<double> numbers(const XmlFile& file, const pugi::xml_node& node,
                            const std::string& where, std::string text, size_t count) {
    std::replace(text.begin(), text.end(), ',', ' ');
    std::vector<double> out;
    for (std::string_view tok : splitWhitespace(text)) {
        double v = 0;
        if (!parseNumber(tok, &v) || !std::isfinite(v))
            file.fail(node, where, "\"" + printable(tok) + "\" is not a finite number");
        out.push_back(v);
    }
    if (count != 0 && out.size() != count)
        file.fail(
            node, where,
            "expected " + std::to_string(count) + " numbers, got " + std::to_string(out.size()));
    return out;
}

// One plugin element (<shape type="...">) with its properties and children.
struct Plugin {
    std::string tag, type, id, where;
    pugi::xml_node node;
    struct Property {
        std::string tag, name, where;
        pugi::xml_node node;
        bool used = false;
    };
    std::vector<Property> properties;
    std::vector<Plugin> children;
    struct Ref {
        std::string id, where;
        pugi::xml_node node;
    };
    std::vector<Ref> refs;
};

// The paths of a node's element children, for messages: "scene/shape[2]"
// (an index where the tag repeats), "scene/sensor/float[name=fov]" (a
// property by its name). of() is called once per element child, in order;
// the counts take one pass, so a scene of many shapes costs no more.
class ChildPaths {
  public:
    ChildPaths(std::string parent, const pugi::xml_node& node) : parent_(std::move(parent)) {
        for (const pugi::xml_node& c : node.children())
            if (c.type() == pugi::node_element) ++total_[c.name()];
    }
    std::string of(const pugi::xml_node& child) {
        const std::string name = child.name();
        const int index = ++seen_[name];
        if (const pugi::xml_attribute a = child.attribute("name"); a && !kPluginTags.count(name))
            return parent_ + "/" + name + "[name=" + printable(a.value()) + "]";
        return parent_ + "/" + name + (total_[name] > 1 ? "[" + std::to_string(index) + "]" : "");
    }

  private:
    std::string parent_;
    std::map<std::string, int> total_, seen_;
};

// Mitsuba scenes nest plugins a few deep (scene/shape/bsdf/bsdf/texture);
// deeper is refused before the recursion could exhaust the stack.
constexpr int kMaxPluginDepth = 8;

Plugin readPlugin(const XmlFile& file, const pugi::xml_node& node, const std::string& where,
                  int depth = 1) {
    if (depth > kMaxPluginDepth)
        file.fail(node, where,
                  "plugins nested deeper than " + std::to_string(kMaxPluginDepth) +
                      " (a Mitsuba scene nests a few)");
    Plugin p;
    p.tag = node.name();
    p.node = node;
    p.where = where;
    file.allowAttributes(node, where, {"type", "id", "name", "version"});
    p.type = file.attribute(node, where, "type");
    p.id = file.optionalAttribute(node, where, "id").value_or("");
    ChildPaths paths(where, node);
    for (const pugi::xml_node& child : node.children()) {
        if (child.type() != pugi::node_element) {
            if (child.type() == pugi::node_pcdata && !trim(child.value()).empty())
                file.fail(child, where,
                          "unexpected text \"" + printable(trim(child.value())) + "\"");
            continue;
        }
        const std::string tag = child.name();
        const std::string w = paths.of(child);
        if (kPropertyTags.count(tag)) {
            const std::string name = file.attribute(child, w, "name");
            for (const Plugin::Property& q : p.properties)
                if (q.name == name) file.fail(child, w, "property \"" + name + "\" given twice");
            p.properties.push_back({tag, name, w, child});
        } else if (kPluginTags.count(tag)) {
            p.children.push_back(readPlugin(file, child, w, depth + 1));
        } else if (tag == "ref") {
            file.allowAttributes(child, w, {"id", "name"});
            p.refs.push_back({file.attribute(child, w, "id"), w, child});
        } else {
            file.fail(child, w, "unknown element <" + printable(tag) + "> in a " + p.tag);
        }
    }
    return p;
}

// Reads the properties of one plugin; finish() refuses any it did not read.
class Properties {
  public:
    Properties(const XmlFile& file, Plugin& plugin) : file_(file), plugin_(plugin) {}

    const Plugin::Property* find(const std::string& name, const std::string& tag) {
        for (Plugin::Property& p : plugin_.properties)
            if (p.name == name) {
                if (p.tag != tag && !(tag == "float" && p.tag == "integer") &&
                    !(tag == "vector" && p.tag == "point") &&
                    !(tag == "point" && p.tag == "vector"))
                    file_.fail(p.node, p.where, "expected <" + tag + " name=\"" + name + "\">");
                p.used = true;
                return &p;
            }
        return nullptr;
    }
    std::optional<double> number(const std::string& name) {
        const Plugin::Property* p = find(name, "float");
        if (!p) return std::nullopt;
        return numbers(file_, p->node, p->where, file_.attribute(p->node, p->where, "value"), 1)[0];
    }
    std::optional<int64_t> integer(const std::string& name) {
        const Plugin::Property* p = find(name, "integer");
        if (!p) return std::nullopt;
        const std::string v = file_.attribute(p->node, p->where, "value");
        int64_t i = 0;
        if (!parseNumber(std::string_view(v), &i))
            file_.fail(p->node, p->where, "\"" + printable(v) + "\" is not an integer");
        return i;
    }
    std::optional<bool> boolean(const std::string& name) {
        const Plugin::Property* p = find(name, "boolean");
        if (!p) return std::nullopt;
        const std::string v = file_.attribute(p->node, p->where, "value");
        if (v == "true") return true;
        if (v == "false") return false;
        file_.fail(p->node, p->where, "\"" + printable(v) + "\" is not true or false");
    }
    std::optional<std::string> string(const std::string& name) {
        const Plugin::Property* p = find(name, "string");
        if (!p) return std::nullopt;
        return file_.attribute(p->node, p->where, "value");
    }
    std::optional<Vec3> vector(const std::string& name) {
        const Plugin::Property* p = find(name, "point");
        if (!p) return std::nullopt;
        return vectorValue(*p);
    }
    // <rgb value="r, g, b"> (or one grey value), <spectrum value="v"> (a
    // constant spectrum), <float value="v"> (grey).
    std::optional<Rgb> colour(const std::string& name) {
        for (Plugin::Property& p : plugin_.properties)
            if (p.name == name) {
                p.used = true;
                const std::string v = file_.attribute(p.node, p.where, "value");
                if (p.tag == "rgb") {
                    const std::vector<double> c = numbers(file_, p.node, p.where, v, 0);
                    if (c.size() == 1) return Rgb(c[0]);
                    if (c.size() == 3) return Rgb(c[0], c[1], c[2]);
                    file_.fail(p.node, p.where,
                               "expected 3 numbers (or 1), got " + std::to_string(c.size()));
                }
                if (p.tag == "spectrum" || p.tag == "float") {
                    if (v.find(':') != std::string::npos)
                        file_.fail(p.node, p.where,
                                   "a spectrum sampled at wavelengths is not read by weft: give "
                                   "an <rgb> value");
                    return Rgb(numbers(file_, p.node, p.where, v, 1)[0]);
                }
                file_.fail(p.node, p.where, "expected <rgb name=\"" + name + "\">");
            }
        return std::nullopt;
    }
    std::optional<Affine> transform(const std::string& name) {
        const Plugin::Property* p = find(name, "transform");
        if (!p) return std::nullopt;
        Affine m;
        ChildPaths paths(p->where, p->node);
        for (const pugi::xml_node& step : p->node.children()) {
            if (step.type() != pugi::node_element) continue;
            const std::string tag = step.name();
            const std::string w = paths.of(step);
            Affine s;
            if (tag == "lookat") {
                file_.allowAttributes(step, w, {"origin", "target", "up"});
                const Vec3 origin = vec3(step, w, file_.attribute(step, w, "origin"));
                const Vec3 target = vec3(step, w, file_.attribute(step, w, "target"));
                const Vec3 up =
                    vec3(step, w, file_.optionalAttribute(step, w, "up").value_or("0, 1, 0"));
                if (length(target - origin) == 0 || length(cross(up, target - origin)) == 0)
                    file_.fail(step, w, "origin equals target, or up is parallel to the view");
                s = lookAt(origin, target, up);
            } else if (tag == "translate") {
                s.t = xyz(step, w, 0.0);
            } else if (tag == "scale") {
                const Vec3 f = xyz(step, w, 1.0);
                s.a = {{{f.x, 0, 0}, {0, f.y, 0}, {0, 0, f.z}}};
            } else if (tag == "rotate") {
                file_.allowAttributes(step, w, {"x", "y", "z", "value", "angle"});
                const Vec3 axis = xyz(step, w, 0.0, true);
                if (length(axis) == 0) file_.fail(step, w, "the rotation axis is zero");
                s = rotation(axis,
                             numbers(file_, step, w, file_.attribute(step, w, "angle"), 1)[0]);
            } else if (tag == "matrix") {
                file_.allowAttributes(step, w, {"value"});
                const std::vector<double> v =
                    numbers(file_, step, w, file_.attribute(step, w, "value"), 16);
                if (v[12] != 0 || v[13] != 0 || v[14] != 0 || v[15] != 1)
                    file_.fail(step, w, "a projective matrix (last row not 0 0 0 1)");
                for (int i = 0; i < 3; ++i) {
                    for (int j = 0; j < 3; ++j) s.a[i][j] = v[4 * i + j];
                }
                s.t = {v[3], v[7], v[11]};
            } else {
                file_.fail(step, w,
                           "unknown transform step <" + printable(tag) +
                               "> (allowed: lookat, translate, scale, rotate, matrix)");
            }
            m = s.after(m);
        }
        return m;
    }
    // Refuses every property not read, naming it and the ones the plugin takes.
    void finish(std::initializer_list<const char*> allowed) {
        for (const Plugin::Property& p : plugin_.properties)
            if (!p.used) {
                std::string list;
                for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
                file_.fail(p.node, p.where,
                           "property \"" + printable(p.name) + "\" of a " + plugin_.tag + " \"" +
                               plugin_.type + "\" is not read by weft (it reads: " +
                               (list.empty() ? std::string("none") : list) + ")");
            }
    }

  private:
    Vec3 vec3(const pugi::xml_node& node, const std::string& w, const std::string& text) {
        const std::vector<double> v = numbers(file_, node, w, text, 3);
        return {v[0], v[1], v[2]};
    }
    // x= y= z= attributes or value="x, y, z" (a single value: all three, for scale).
    Vec3 xyz(const pugi::xml_node& node, const std::string& w, double fallback, bool axis = false) {
        if (!axis) file_.allowAttributes(node, w, {"x", "y", "z", "value"});
        if (const auto v = file_.optionalAttribute(node, w, "value")) {
            const std::vector<double> n = numbers(file_, node, w, *v, 0);
            if (n.size() == 1 && !axis) return {n[0], n[0], n[0]};
            if (n.size() == 3) return {n[0], n[1], n[2]};
            file_.fail(node, w, "expected 3 numbers, got " + std::to_string(n.size()));
        }
        auto one = [&](const char* c) {
            const auto v = file_.optionalAttribute(node, w, c);
            return v ? numbers(file_, node, w, *v, 1)[0] : fallback;
        };
        return {one("x"), one("y"), one("z")};
    }
    Vec3 vectorValue(const Plugin::Property& p) {
        if (p.node.attribute("value")) {
            file_.allowAttributes(p.node, p.where, {"name", "value"});
            return vec3(p.node, p.where, file_.attribute(p.node, p.where, "value"));
        }
        file_.allowAttributes(p.node, p.where, {"name", "x", "y", "z"});
        auto one = [&](const char* c) {
            return numbers(file_, p.node, p.where, file_.attribute(p.node, p.where, c), 1)[0];
        };
        return {one("x"), one("y"), one("z")};
    }

    const XmlFile& file_;
    Plugin& plugin_;
};

// ---------------------------------------------------------------------------
// The import.

struct Importer {
    Importer(const std::string& xmlPath, std::string text, const std::string& baseDir)
        : file(xmlPath, std::move(text)), xmlDir(baseDir) {}

    XmlFile file;
    fs::path xmlDir;
    MitsubaImport out;
    std::map<std::string, Plugin> bsdfs;  // top-level <bsdf id=...>
    json mapping;                         // bsdf id -> yarn keys
    std::string defaultModel;
    FolderFiles files{&out.files};

    std::string resolve(const std::string& name) const {
        const fs::path p(name);
        return p.is_absolute() ? p.string() : (xmlDir / p).lexically_normal().string();
    }
    void note(const Plugin& p, const std::string& what) {
        out.notes.push_back(file.path() + ":" + std::to_string(file.lineOf(p.node)) + ": " +
                            p.where + ": " + what);
    }
};

void readIntegrator(Importer& im, Plugin& p, json& render) {
    if (p.type != "path")
        im.file.fail(p.node, p.where,
                     "integrator \"" + printable(p.type) + "\": weft reads the path integrator");
    Properties props(im.file, p);
    if (const auto depth = props.integer("max_depth")) {
        // Mitsuba counts the camera ray as a bounce: max_depth 2 is direct light only.
        if (*depth == -1) {
            render["max_depth"] = kUnlimitedDepth;
        } else if (*depth >= 2 && *depth <= kUnlimitedDepth + 1) {
            render["max_depth"] = *depth - 1;
        } else {
            im.file.fail(p.node, p.where,
                         "max_depth " + std::to_string(*depth) +
                             " is out of range: allowed -1 or "
                             "[2, " +
                             std::to_string(kUnlimitedDepth + 1) + "] (weft's max_depth " +
                             "is Mitsuba's minus 1)");
        }
    }
    if (props.integer("rr_depth")) im.note(p, "rr_depth: weft's own Russian roulette is used");
    if (const auto hide = props.boolean("hide_emitters"); hide && *hide)
        im.file.fail(p.node, p.where, "hide_emitters true is not read by weft");
    props.finish({"max_depth", "rr_depth", "hide_emitters"});
    if (!p.children.empty() || !p.refs.empty())
        im.file.fail(p.node, p.where, "an integrator takes no nested plugins here");
}

void readSensor(Importer& im, Plugin& p, json& scene) {
    if (p.type != "perspective")
        im.file.fail(p.node, p.where,
                     "sensor \"" + printable(p.type) + "\": weft has a perspective camera only");
    Properties props(im.file, p);
    const double fov = props.number("fov").value_or(-1);
    const std::string axis = props.string("fov_axis").value_or("x");
    const Affine toWorld = props.transform("to_world").value_or(Affine{});
    if (props.number("near_clip") || props.number("far_clip"))
        im.note(p, "near_clip and far_clip: weft's camera does not clip");
    if (props.number("focal_length"))
        im.file.fail(p.node, p.where, "give fov (degrees), not focal_length");
    props.finish({"fov", "fov_axis", "to_world", "near_clip", "far_clip"});
    if (!(fov > 0 && fov < 180))
        im.file.fail(p.node, p.where, "fov must be given, in (0, 180) degrees");
    int width = 768, height = 576;  // Mitsuba's hdrfilm default
    json render = {{"spp", 4}};
    for (Plugin& c : p.children) {
        Properties cp(im.file, c);
        if (c.tag == "film") {
            if (c.type != "hdrfilm")
                im.file.fail(c.node, c.where,
                             "film \"" + printable(c.type) + "\": weft reads hdrfilm");
            width = static_cast<int>(cp.integer("width").value_or(width));
            height = static_cast<int>(cp.integer("height").value_or(height));
            cp.string("pixel_format"), cp.string("component_format"), cp.string("file_format");
            cp.boolean("banner");
            cp.finish(
                {"width", "height", "pixel_format", "component_format", "file_format", "banner"});
            for (Plugin& f : c.children) {
                if (f.tag != "rfilter")
                    im.file.fail(f.node, f.where, "a film takes an rfilter only");
                Properties fp(im.file, f);
                fp.number("radius"), fp.number("stddev");
                fp.finish({"radius", "stddev"});
                if (f.type != "box")
                    im.note(f, "rfilter \"" + f.type + "\": weft filters pixels with a box");
            }
            if (c.children.empty())
                im.note(c, "Mitsuba's default Gaussian pixel filter: weft uses a box");
        } else if (c.tag == "sampler") {
            static const std::set<std::string> stratified = {"stratified", "multijitter",
                                                             "orthogonal", "ldsampler"};
            if (c.type == "independent") {
                render["sampler"] = "independent";
            } else if (stratified.count(c.type)) {
                render["sampler"] = "sobol";
                im.note(c, "sampler \"" + c.type + "\": weft's Owen-scrambled Sobol' points");
            } else {
                im.file.fail(c.node, c.where, "sampler \"" + printable(c.type) + "\" is not read");
            }
            if (const auto n = cp.integer("sample_count")) render["spp"] = *n;
            if (const auto s = cp.integer("seed")) {
                if (*s < 0) im.file.fail(c.node, c.where, "seed must be >= 0");
                render["seed"] = *s;
            }
            cp.boolean("jitter");
            cp.finish({"sample_count", "seed", "jitter"});
        } else {
            im.file.fail(c.node, c.where, "a sensor takes a film and a sampler only");
        }
    }
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        im.file.fail(p.node, p.where, "film width and height must be in [1, 16384]");
    // fov spans the chosen axis; weft's spans the shorter side.
    const double w = width, h = height;
    double extent = w;
    if (axis == "y")
        extent = h;
    else if (axis == "diagonal")
        extent = std::hypot(w, h);
    else if (axis == "smaller")
        extent = std::min(w, h);
    else if (axis == "larger")
        extent = std::max(w, h);
    else if (axis != "x")
        im.file.fail(
            p.node, p.where,
            "fov_axis \"" + printable(axis) + "\" (allowed: x, y, diagonal, smaller, larger)");
    const double perPixel = std::tan(fov * kPi / 360) / (extent / 2);
    const double fovShort = 2 * std::atan(perPixel * std::min(w, h) / 2) * 180 / kPi;
    if (toWorld.determinant() <= 0)
        im.file.fail(p.node, p.where,
                     "the camera's to_world mirrors the image (a negative scale): weft's camera "
                     "does not");
    const Vec3 from = toWorld.point({0, 0, 0});
    const Vec3 dir = toWorld.vector({0, 0, 1});
    const Vec3 up = toWorld.vector({0, 1, 0});
    scene["camera"] = {{"from", {from.x, from.y, from.z}},
                       {"to", {from.x + dir.x, from.y + dir.y, from.z + dir.z}},
                       {"up", {up.x, up.y, up.z}},
                       {"fov_deg", fovShort}};
    scene["film"] = {{"width", width}, {"height", height}};
    for (auto& [k, v] : render.items()) scene["render"][k] = v;
}

json readEmitter(Importer& im, Plugin& p) {
    Properties props(im.file, p);
    json light;
    if (p.type == "constant") {
        const Rgb c = props.colour("radiance").value_or(Rgb(1));
        props.finish({"radiance"});
        light = {{"type", "constant"}, {"radiance", {c.r, c.g, c.b}}};
    } else if (p.type == "envmap") {
        const auto name = props.string("filename");
        const double scale = props.number("scale").value_or(1);
        const Affine toWorld = props.transform("to_world").value_or(Affine{});
        props.finish({"filename", "scale", "to_world"});
        if (!name) im.file.fail(p.node, p.where, "an envmap needs its filename");
        // to_world may only turn the map about +y: weft's rotate_deg.
        const double angle = std::atan2(toWorld.a[0][2], toWorld.a[0][0]) * 180 / kPi;
        const Affine turn = rotation({0, 1, 0}, angle);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                if (std::abs(turn.a[i][j] - toWorld.a[i][j]) > 1e-6)
                    im.file.fail(p.node, p.where,
                                 "an envmap's to_world may only rotate about +y (weft's "
                                 "rotate_deg)");
        const std::string source = im.resolve(*name);
        const std::string ext = lowercaseExtension(source);
        if (ext != ".exr" && ext != ".hdr")
            im.file.fail(p.node, p.where, "envmap " + *name + ": weft reads .exr and .hdr maps");
        light = {{"type", "envmap"},
                 {"file", im.files.copy(source, "textures")},
                 {"scale", scale},
                 {"rotate_deg", angle}};
    } else if (p.type == "point") {
        // Mitsuba: intensity (W/sr, default 1) at `position` or at to_world's origin.
        const Rgb intensity = props.colour("intensity").value_or(Rgb(1));
        const auto position = props.vector("position");
        const auto toWorld = props.transform("to_world");
        props.finish({"intensity", "position", "to_world"});
        if (position && toWorld)
            im.file.fail(p.node, p.where, "a point emitter takes position or to_world, not both");
        const Vec3 at = position ? *position : toWorld.value_or(Affine{}).point({0, 0, 0});
        light = {{"type", "point"},
                 {"position", {at.x, at.y, at.z}},
                 {"intensity", {intensity.r, intensity.g, intensity.b}}};
    } else if (p.type == "directional") {
        // Mitsuba: irradiance (W/m^2, default 1) travelling along `direction`
        // or along to_world's +z.
        const Rgb irradiance = props.colour("irradiance").value_or(Rgb(1));
        const auto direction = props.vector("direction");
        const auto toWorld = props.transform("to_world");
        props.finish({"irradiance", "direction", "to_world"});
        if (direction && toWorld)
            im.file.fail(p.node, p.where,
                         "a directional emitter takes direction or to_world, not both");
        const Vec3 d = direction ? *direction : toWorld.value_or(Affine{}).vector({0, 0, 1});
        if (d.x == 0 && d.y == 0 && d.z == 0)
            im.file.fail(p.node, p.where, "a directional emitter's direction cannot be 0");
        light = {{"type", "directional"},
                 {"direction", {d.x, d.y, d.z}},
                 {"irradiance", {irradiance.r, irradiance.g, irradiance.b}}};
    } else {
        im.file.fail(p.node, p.where,
                     "emitter \"" + printable(p.type) +
                         "\": weft has constant, envmap, point and directional emitters, and "
                         "spheres with an area emitter (no spot lights or area lights on other "
                         "shapes)");
    }
    if (!p.children.empty() || !p.refs.empty())
        im.file.fail(p.node, p.where, "an emitter takes no nested plugins here");
    return light;
}

// The yarn keys of a bsdf id: the mapping file's entry, or --model.
json yarnKeys(Importer& im, const Plugin& shape, const std::string& bsdfId) {
    if (!bsdfId.empty() && im.mapping.contains(bsdfId)) return im.mapping[bsdfId];
    if (!im.defaultModel.empty()) return {{"model", im.defaultModel}};
    im.file.fail(shape.node, shape.where,
                 (bsdfId.empty() ? std::string("a curve shape without a bsdf id")
                                 : "bsdf \"" + bsdfId + "\"") +
                     " has no weft model: map it in a models file (--models MAP.json, "
                     "docs/mitsuba.md) or give --model MODEL.json");
}

// A cubic B-spline (Embree's round B-spline, Mitsuba's bsplinecurve) as a
// polyline of kSplineSteps points per span; the curve does not reach its end
// control points.
Curve bsplinePolyline(const Curve& c) {
    Curve out;
    const size_t spans = c.points.size() - 3;
    auto at = [&](size_t i, double t, auto get) {
        const double s = 1 - t;
        const double b[4] = {s * s * s / 6, (3 * t * t * t - 6 * t * t + 4) / 6,
                             (-3 * t * t * t + 3 * t * t + 3 * t + 1) / 6, t * t * t / 6};
        return b[0] * get(i) + b[1] * get(i + 1) + b[2] * get(i + 2) + b[3] * get(i + 3);
    };
    for (size_t i = 0; i < spans; ++i)
        for (int k = 0; k <= kSplineSteps; ++k) {
            if (k == kSplineSteps && i + 1 < spans) break;
            const double t = static_cast<double>(k) / kSplineSteps;
            out.points.push_back(at(i, t, [&](size_t j) { return c.points[j]; }));
            out.radii.push_back(at(i, t, [&](size_t j) { return c.radii[j]; }));
        }
    return out;
}

void readCurveShape(Importer& im, Plugin& p, json& yarns) {
    Properties props(im.file, p);
    const auto name = props.string("filename");
    const Affine toWorld = props.transform("to_world").value_or(Affine{});
    props.finish({"filename", "to_world"});
    if (!name) im.file.fail(p.node, p.where, "a " + p.type + " needs its filename");
    std::string bsdfId;
    for (const Plugin::Ref& r : p.refs) {
        if (!im.bsdfs.count(r.id))
            im.file.fail(r.node, r.where, "no <bsdf id=\"" + printable(r.id) + "\"> before it");
        bsdfId = r.id;
    }
    for (const Plugin& c : p.children) {
        if (c.tag != "bsdf") im.file.fail(c.node, c.where, "a curve shape takes a bsdf only");
        bsdfId = c.id;
    }
    if (p.refs.size() + p.children.size() > 1)
        im.file.fail(p.node, p.where, "a shape takes one bsdf");
    const auto scale = toWorld.similarityScale();
    if (!scale)
        im.file.fail(p.node, p.where,
                     "to_world scales unequally or shears: a yarn's radius would not stay round");
    const std::string source = im.resolve(*name);
    CurveSet set = parseTextCurves(readFile(source), source);
    for (size_t i = 0; i < set.curves.size(); ++i) {
        Curve& c = set.curves[i];
        if (c.radii.empty())
            im.file.fail(p.node, p.where,
                         *name + ": a Mitsuba curve file gives a radius per point (x y z radius)");
        if (c.closed)
            im.file.fail(p.node, p.where, *name + ": Mitsuba's curves are open (# closed)");
        if (p.type == "bsplinecurve") {
            if (c.points.size() < 4)
                im.file.fail(p.node, p.where,
                             *name + ": curve " + std::to_string(i) +
                                 " has fewer than the 4 points of a B-spline span");
            c = bsplinePolyline(c);
        }
        for (Vec3& q : c.points) q = toWorld.point(q);
        for (double& r : c.radii) r *= *scale;
    }
    if (p.type == "bsplinecurve")
        im.note(p, "bsplinecurve: drawn as " + std::to_string(kSplineSteps) +
                       " straight pieces per span");
    const std::string curves = im.files.add("curves", fs::path(*name).stem().string(), ".txt",
                                            formatCurveText(set, source));
    json entry = yarnKeys(im, p, bsdfId);
    entry["curves"] = curves;
    yarns.push_back(entry);
}

json surfaceMaterial(Importer& im, const Plugin& shape, const Plugin* bsdf) {
    if (!bsdf) return {{"type", "diffuse"}, {"reflectance", {0.5, 0.5, 0.5}}};
    Plugin b = *bsdf;
    if (b.type == "twosided") {
        if (b.children.size() != 1 || b.children[0].tag != "bsdf")
            im.file.fail(b.node, b.where, "a twosided bsdf wraps one nested bsdf");
        Plugin inner = b.children[0];
        b = std::move(inner);
    }
    Properties props(im.file, b);
    if (b.type == "diffuse") {
        const Rgb r = props.colour("reflectance").value_or(Rgb(0.5));
        props.finish({"reflectance"});
        return {{"type", "diffuse"}, {"reflectance", {r.r, r.g, r.b}}};
    }
    if (b.type == "roughconductor") {
        const std::string material = props.string("material").value_or("");
        const Rgb colour = props.colour("specular_reflectance").value_or(Rgb(1));
        const double alpha = props.number("alpha").value_or(0.1);
        const std::string distribution = props.string("distribution").value_or("beckmann");
        props.finish({"material", "specular_reflectance", "alpha", "distribution"});
        if (material != "none" || distribution != "ggx")
            im.file.fail(b.node, b.where,
                         "a roughconductor is read with material \"none\" and distribution "
                         "\"ggx\" only (weft's conductor: a Schlick Fresnel of that colour)");
        return {{"type", "conductor"},
                {"colour", {colour.r, colour.g, colour.b}},
                {"roughness", alpha}};
    }
    im.file.fail(b.node, b.where,
                 "bsdf \"" + printable(b.type) + "\" on a " + shape.type +
                     " shape: weft's surfaces are diffuse or roughconductor (twosided or not)");
}

void readMeshShape(Importer& im, Plugin& p, json& objects) {
    Properties props(im.file, p);
    const auto name = props.string("filename");
    const Affine toWorld = props.transform("to_world").value_or(Affine{});
    if (props.boolean("face_normals")) im.note(p, "face_normals: weft shades with face normals");
    props.finish({"filename", "to_world", "face_normals"});
    if (!name) im.file.fail(p.node, p.where, "a mesh shape needs its filename");
    const Plugin* bsdf = nullptr;
    for (const Plugin::Ref& r : p.refs) {
        const auto it = im.bsdfs.find(r.id);
        if (it == im.bsdfs.end())
            im.file.fail(r.node, r.where, "no <bsdf id=\"" + printable(r.id) + "\"> before it");
        bsdf = &it->second;
    }
    for (const Plugin& c : p.children) {
        if (c.tag != "bsdf") im.file.fail(c.node, c.where, "a mesh shape takes a bsdf only");
        bsdf = &c;
    }
    const std::string source = im.resolve(*name);
    if (lowercaseExtension(source) != "." + p.type)
        im.file.fail(p.node, p.where,
                     "a " + p.type + " shape's filename must end in ." + p.type + ", not " + *name);
    std::string file;
    if (toWorld.isIdentity()) {
        file = im.files.copy(source, "meshes");
    } else {
        // The triangles moved into the world, as an OBJ of their own.
        Triangles t = readMeshTriangles(source);
        for (Vec3& v : t.vertices) v = toWorld.point(v);
        file = im.files.add("meshes", fs::path(*name).stem().string(), ".obj", objText(t));
    }
    objects.push_back(
        {{"type", "mesh"}, {"file", file}, {"material", surfaceMaterial(im, p, bsdf)}});
}

void readSphereShape(Importer& im, Plugin& p, json& lights) {
    Properties props(im.file, p);
    Vec3 center = props.vector("center").value_or(Vec3{});
    double radius = props.number("radius").value_or(1);
    const Affine toWorld = props.transform("to_world").value_or(Affine{});
    props.finish({"center", "radius", "to_world"});
    const auto scale = toWorld.similarityScale();
    if (!scale) im.file.fail(p.node, p.where, "to_world scales a sphere unequally");
    center = toWorld.point(center);
    radius *= *scale;
    const Plugin* emitter = nullptr;
    for (const Plugin& c : p.children) {
        if (c.tag == "emitter")
            emitter = &c;
        else if (c.tag == "bsdf")
            im.note(c, "the bsdf of an emitting sphere: weft's sphere lights do not reflect");
        else
            im.file.fail(c.node, c.where, "a sphere takes an emitter (and a bsdf)");
    }
    if (!p.refs.empty())
        im.note(p, "the bsdf of an emitting sphere: weft's sphere lights do not reflect");
    if (!emitter)
        im.file.fail(p.node, p.where,
                     "a sphere without an area emitter: weft draws spheres only as lights");
    Plugin e = *emitter;
    if (e.type != "area") im.file.fail(e.node, e.where, "a sphere's emitter must be \"area\"");
    Properties ep(im.file, e);
    const Rgb c = ep.colour("radiance").value_or(Rgb(1));
    ep.finish({"radiance"});
    lights.push_back({{"type", "sphere"},
                      {"center", {center.x, center.y, center.z}},
                      {"radius", radius},
                      {"radiance", {c.r, c.g, c.b}}});
}

// The mapping file: {"bsdf id": {yarn entry keys but curves, scale and radius}}.
json readMapping(const std::string& path) {
    const std::string text = readFile(path);
    json doc;
    try {
        doc = json::parse(text);
    } catch (const json::parse_error& e) {
        throw InputError(path + ": malformed JSON: " + e.what());
    }
    if (!doc.is_object()) throw InputError(path + ": expected an object {\"bsdf id\": {...}}");
    const fs::path base = fs::path(path).parent_path();
    for (auto& [id, entry] : doc.items()) {
        const std::string where = path + ": \"" + id + "\"";
        if (!entry.is_object()) throw InputError(where + ": expected an object of yarn keys");
        for (const char* key : {"curves", "scale", "radius"})
            if (entry.contains(key))
                throw InputError(where + ": \"" + key + "\" comes from the Mitsuba scene");
        if (!entry.contains("model") || !entry["model"].is_string())
            throw InputError(where + ": missing key \"model\" (a string)");
        for (const char* key : {"model", "vertex_colours"})
            if (entry.contains(key) && entry[key].is_string()) {
                const fs::path f(entry[key].get<std::string>());
                entry[key] = (f.is_absolute() ? f : base / f).lexically_normal().string();
            }
        // Its values are checked as a yarn entry is, named by the bsdf id.
        json probe = entry;
        probe["curves"] = "probe.txt";
        probe["radius"] = 1;
        try {
            parseScene({{"camera", {{"from", {0, 0, 1}}, {"to", {0, 0, 0}}}},
                        {"yarns", json::array({probe})}},
                       "", "/");
        } catch (const InputError& e) {
            std::string m = e.what();
            const std::string prefix = "scene: yarns[0]";
            if (m.rfind(prefix, 0) == 0) m = m.substr(prefix.size());
            throw InputError(where + m);
        }
    }
    return doc;
}

}  // namespace

MitsubaImport importMitsubaScene(const std::string& xmlPath, const MitsubaImportOptions& options) {
    return importMitsubaText(readFile(xmlPath), xmlPath,
                             fs::absolute(xmlPath).parent_path().string(), options);
}

MitsubaImport importMitsubaText(std::string text, const std::string& xmlPath,
                                const std::string& baseDir, const MitsubaImportOptions& options) {
    Importer im(xmlPath, std::move(text), baseDir);
    pugi::xml_document doc;
    const pugi::xml_parse_result parsed = doc.load_buffer(
        im.file.text().data(), im.file.text().size(), pugi::parse_default | pugi::parse_comments);
    if (!parsed) {
        const std::string& t = im.file.text();
        const size_t offset =
            std::min(static_cast<size_t>(std::max<ptrdiff_t>(parsed.offset, 0)), t.size());
        const int line = 1 + static_cast<int>(std::count(t.begin(), t.begin() + offset, '\n'));
        throw InputError(xmlPath + ":" + std::to_string(line) +
                         ": malformed XML: " + parsed.description());
    }
    pugi::xml_node root = doc.document_element();
    if (std::string(root.name()) != "scene")
        im.file.fail(root, root.name(), "the root element must be <scene version=\"3.0.0\">");
    im.file.allowAttributes(root, "scene", {"version"});
    const std::string version = root.attribute("version").value();
    if (version.empty() || (version.rfind("3.", 0) != 0 && version.rfind("2.", 0) != 0))
        im.file.fail(root, "scene",
                     "version \"" + printable(version) +
                         "\": weft reads Mitsuba 3 scenes (version 3.x.y, or 2.x.y)");

    // Defaults first (-D over them), then every plugin in order.
    ChildPaths defaultPaths("scene", root);
    for (const pugi::xml_node& d : root.children("default")) {
        const std::string w = defaultPaths.of(d);
        im.file.allowAttributes(d, w, {"name", "value"});
        im.file.defines.emplace(im.file.attribute(d, w, "name"), d.attribute("value").value());
    }
    for (const auto& [name, value] : options.defines) im.file.defines[name] = value;

    if (!options.model.empty()) im.defaultModel = fs::absolute(options.model).string();
    std::string mapping = options.mapping;
    if (mapping.empty() && fs::exists(im.xmlDir / "weft-models.json")) {
        mapping = (im.xmlDir / "weft-models.json").string();
        im.out.notes.push_back(xmlPath + ": the weft models of its bsdfs from " + mapping);
    }
    if (!mapping.empty()) im.mapping = readMapping(mapping);

    json scene = {{"render", {{"max_depth", kUnlimitedDepth}}}};
    json lights = json::array(), yarns = json::array(), objects = json::array();
    bool sawSensor = false, sawIntegrator = false;
    ChildPaths scenePaths("scene", root);
    for (const pugi::xml_node& child : root.children()) {
        if (child.type() != pugi::node_element) {
            if (child.type() == pugi::node_pcdata && !trim(child.value()).empty())
                im.file.fail(child, "scene", "unexpected text");
            continue;
        }
        const std::string tag = child.name();
        const std::string w = scenePaths.of(child);
        if (tag == "default") continue;
        if (!kPluginTags.count(tag))
            im.file.fail(child, w,
                         "element <" + printable(tag) +
                             "> is not read by weft (it reads default, integrator, sensor, "
                             "emitter, shape, bsdf)");
        Plugin p = readPlugin(im.file, child, w);
        if (tag == "integrator") {
            if (sawIntegrator) im.file.fail(child, w, "a second integrator");
            sawIntegrator = true;
            json render = scene["render"];
            readIntegrator(im, p, render);
            scene["render"] = render;
        } else if (tag == "sensor") {
            if (sawSensor) im.file.fail(child, w, "a second sensor: weft renders one camera");
            sawSensor = true;
            readSensor(im, p, scene);
        } else if (tag == "emitter") {
            lights.push_back(readEmitter(im, p));
        } else if (tag == "bsdf") {
            if (p.id.empty()) im.file.fail(child, w, "a bsdf at the top level needs an id");
            if (im.bsdfs.count(p.id)) im.file.fail(child, w, "a second bsdf \"" + p.id + "\"");
            im.bsdfs.emplace(p.id, p);
        } else if (tag == "shape") {
            if (p.type == "linearcurve" || p.type == "bsplinecurve") {
                readCurveShape(im, p, yarns);
            } else if (p.type == "obj" || p.type == "ply") {
                readMeshShape(im, p, objects);
            } else if (p.type == "sphere") {
                readSphereShape(im, p, lights);
            } else {
                im.file.fail(child, w,
                             "shape \"" + printable(p.type) +
                                 "\": weft reads linearcurve, bsplinecurve, obj, ply, and "
                                 "spheres with an area emitter");
            }
        } else {
            im.file.fail(child, w, "<" + tag + "> at the top level is not read by weft");
        }
    }
    if (!sawSensor) im.file.fail(root, "scene", "no <sensor>: weft needs the camera");
    if (lights.empty()) {
        // Mitsuba renders black without emitters; weft's default is its sky.
        lights.push_back({{"type", "constant"}, {"radiance", {0, 0, 0}}});
    }
    scene["lights"] = lights;
    scene["yarns"] = yarns;
    if (!objects.empty()) scene["objects"] = objects;
    // Yarn models become files of the folder.
    for (json& y : scene["yarns"]) {
        y["model"] = im.files.copy(y["model"].get<std::string>(), "models");
        if (y.contains("vertex_colours"))
            y["vertex_colours"] = im.files.copy(y["vertex_colours"].get<std::string>(), "curves");
    }
    // What weft will read: a scene that does not validate is a bug here.
    parseScene(scene, xmlPath, "/");
    im.out.scene = scene;
    return im.out;
}

// ---------------------------------------------------------------------------
// The export.

namespace {

std::string xmlEscape(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '&')
            out += "&amp;";
        else if (c == '<')
            out += "&lt;";
        else if (c == '>')
            out += "&gt;";
        else if (c == '"')
            out += "&quot;";
        else
            out += c;
    }
    return out;
}

// A Catmull-Rom curve as the polyline through its spans (kSplineSteps per
// span), the spans weft draws (catmull_rom.h), radii linear in each span.
Curve catmullRomPolyline(const Curve& c) {
    Curve out;
    const size_t n = c.points.size(), spans = c.closed ? n : n - 1;
    for (size_t i = 0; i < spans; ++i) {
        const CatmullRomSpan span = catmullRomSpan(c.points, c.closed, i);
        for (int k = 0; k < kSplineSteps; ++k) {
            const double t = static_cast<double>(k) / kSplineSteps;
            out.points.push_back(span.position(t));
            if (!c.radii.empty())
                out.radii.push_back(c.radii[i] + (c.radii[(i + 1) % n] - c.radii[i]) * t);
        }
    }
    if (!c.closed) {
        out.points.push_back(c.points.back());
        if (!c.radii.empty()) out.radii.push_back(c.radii.back());
    }
    out.closed = c.closed;
    return out;
}

}  // namespace

MitsubaExport exportMitsubaScene(const SceneDesc& scene, bool fibers) {
    MitsubaExport ex;
    FolderFiles files(&ex.files);
    const std::string source = scene.path.empty() ? std::string("scene") : scene.path;
    std::ostringstream x;
    x << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
      << "<!-- Written by weft (weft scene export --mitsuba) from "
      << xmlEscape(fs::path(source).filename().string())
      << ". Each yarn's bsdf stands in for a weft model: weft-models.json names it "
         "(docs/mitsuba.md). -->\n"
      << "<scene version=\"3.0.0\">\n";
    const int maxDepth = scene.render.maxDepth >= kUnlimitedDepth ? -1 : scene.render.maxDepth + 1;
    x << "    <integrator type=\"path\">\n        <integer name=\"max_depth\" value=\"" << maxDepth
      << "\"/>\n    </integrator>\n";
    const CameraDesc& cam = scene.camera;
    x << "    <sensor type=\"perspective\">\n"
      << "        <float name=\"fov\" value=\"" << formatNumber(cam.fovDeg) << "\"/>\n"
      << "        <string name=\"fov_axis\" value=\"smaller\"/>\n"
      << "        <transform name=\"to_world\">\n"
      << "            <lookat origin=\"" << formatVec(cam.from) << "\" target=\""
      << formatVec(cam.to) << "\" up=\"" << formatVec(cam.up) << "\"/>\n"
      << "        </transform>\n"
      << "        <sampler type=\""
      << (scene.render.sampler == SamplerKind::Sobol ? "ldsampler" : "independent") << "\">\n"
      << "            <integer name=\"sample_count\" value=\"" << scene.render.spp << "\"/>\n"
      << "            <integer name=\"seed\" value=\"" << scene.render.seed << "\"/>\n"
      << "        </sampler>\n"
      << "        <film type=\"hdrfilm\">\n"
      << "            <integer name=\"width\" value=\"" << scene.film.width << "\"/>\n"
      << "            <integer name=\"height\" value=\"" << scene.film.height << "\"/>\n"
      << "            <rfilter type=\"box\"/>\n"
      << "        </film>\n"
      << "    </sensor>\n";
    if (scene.render.sampler == SamplerKind::Sobol)
        ex.notes.push_back("render.sampler sobol: written as Mitsuba's ldsampler");
    if (scene.lightSampler.kind != LightSamplerKind::Uniform)
        ex.notes.push_back(
            "light_sampler: Mitsuba picks lights its own way (same image, other noise)");

    const json lights = [&] {
        json all = json::array();
        for (const auto& l : scene.lights) all.push_back(toJson(*l));
        if (all.empty()) all.push_back({{"type", "sky"}, {"scale", 1.0}});
        return all;
    }();
    for (size_t i = 0; i < lights.size(); ++i) {
        const json& l = lights[i];
        const std::string type = l["type"];
        if (type == "constant") {
            x << "    <emitter type=\"constant\">\n        <rgb name=\"radiance\" value=\""
              << formatNumber(l["radiance"][0]) << ", " << formatNumber(l["radiance"][1]) << ", "
              << formatNumber(l["radiance"][2]) << "\"/>\n    </emitter>\n";
        } else if (type == "point" || type == "directional") {
            const bool point = type == "point";
            const json& at = l[point ? "position" : "direction"];
            const json& power = l[point ? "intensity" : "irradiance"];
            x << "    <emitter type=\"" << type << "\">\n        <"
              << (point ? "point name=\"position\"" : "vector name=\"direction\"") << " value=\""
              << formatVec({at[0], at[1], at[2]}) << "\"/>\n        <rgb name=\""
              << (point ? "intensity" : "irradiance") << "\" value=\"" << formatNumber(power[0])
              << ", " << formatNumber(power[1]) << ", " << formatNumber(power[2])
              << "\"/>\n    </emitter>\n";
        } else if (type == "sphere") {
            const Vec3 c{l["center"][0], l["center"][1], l["center"][2]};
            x << "    <shape type=\"sphere\">\n        <point name=\"center\" value=\""
              << formatVec(c) << "\"/>\n        <float name=\"radius\" value=\""
              << formatNumber(l["radius"]) << "\"/>\n        <emitter type=\"area\">\n"
              << "            <rgb name=\"radiance\" value=\"" << formatNumber(l["radiance"][0])
              << ", " << formatNumber(l["radiance"][1]) << ", " << formatNumber(l["radiance"][2])
              << "\"/>\n        </emitter>\n    </shape>\n";
        } else {
            std::string file;
            double scale = l.value("scale", 1.0), rotate = l.value("rotate_deg", 0.0);
            if (type == "envmap") {
                file = files.copy(l["file"].get<std::string>(), "textures");
            } else {  // the procedural sky, as the image weft samples it from
                file = files.add("textures", "sky", ".exr", encodeExr(skyImage(1024, 512), "sky"));
                ex.notes.push_back("lights[" + std::to_string(i) +
                                   "]: the procedural sky written as a 1024 x 512 envmap");
            }
            x << "    <emitter type=\"envmap\">\n        <string name=\"filename\" value=\""
              << xmlEscape(file) << "\"/>\n        <float name=\"scale\" value=\""
              << formatNumber(scale) << "\"/>\n";
            if (rotate != 0)
                x << "        <transform name=\"to_world\">\n            <rotate y=\"1\" "
                     "angle=\""
                  << formatNumber(rotate) << "\"/>\n        </transform>\n";
            x << "    </emitter>\n";
        }
    }

    json models = json::object();
    const json sceneJson = toJson(scene);  // each yarn entry's keys, written once
    for (size_t y = 0; y < scene.yarns.size(); ++y) {
        const YarnDesc& yarn = scene.yarns[y];
        const std::string id = "yarn" + std::to_string(y);
        json entry = sceneJson.at("yarns").at(y);
        for (const char* key : {"curves", "scale", "radius"}) entry.erase(key);
        entry["model"] = files.copy(yarn.model, "models");
        if (!yarn.vertexColours.empty())
            entry["vertex_colours"] = files.copy(yarn.vertexColours, "curves");
        models[id] = entry;
        CurveSet set = readCurves(yarn.curves);
        CurveSet drawn;
        if (fibers) {
            const std::string what = source + ": yarns[" + std::to_string(y) + "]";
            const YarnModel model =
                ModelFile::load(yarn.model).forYarn(yarn.yarn, what, what + ".yarn", "in \"yarn\"");
            for (size_t c = 0; c < set.curves.size(); ++c) {
                const std::vector<FramedCurve> plies =
                    yarnPlyCurves(set.curves[c], yarn, &model.ply, c);
                for (size_t j = 0; j < plies.size(); ++j)
                    for (const Tube& t : fiberTubes(plies[j], model.ply,
                                                    fiberSeed(y, c, j, scene.render.fiberSeed))) {
                        Curve f;
                        f.points = t.points;
                        f.radii.assign(t.radii.begin(), t.radii.end());
                        if (t.closed)
                            f.points.push_back(t.points.front()),
                                f.radii.push_back(t.radii.front());
                        drawn.curves.push_back(std::move(f));
                    }
            }
        } else {
            for (size_t c = 0; c < set.curves.size(); ++c) {
                Curve curve = set.curves[c];
                if (curve.radii.empty() && !yarn.radius)
                    throw InputError(source + ": yarns[" + std::to_string(y) +
                                     "]: the curve file has no radii and the yarn no radius");
                if (curve.basis == CurveBasis::CatmullRom) {
                    curve = catmullRomPolyline(curve);
                    ex.notes.push_back("yarns[" + std::to_string(y) +
                                       "]: Catmull-Rom curves written as polylines of " +
                                       std::to_string(kSplineSteps) + " pieces per span");
                }
                for (Vec3& p : curve.points) p = p * yarn.scale;
                if (yarn.radius)
                    curve.radii.assign(curve.points.size(), *yarn.radius);
                else
                    for (double& r : curve.radii) r *= yarn.scale;
                if (curve.closed) {
                    // Mitsuba's curves are open: repeat the first point.
                    curve.points.push_back(curve.points.front());
                    curve.radii.push_back(curve.radii.front());
                    curve.closed = false;
                }
                curve.colours.clear();
                drawn.curves.push_back(std::move(curve));
            }
        }
        const std::string file =
            files.add(fibers ? "fibers" : "curves", fs::path(yarn.curves).stem().string(), ".txt",
                      formatCurveText(drawn, yarn.curves));
        x << "    <bsdf type=\"diffuse\" id=\"" << id << "\">\n"
          << "        <!-- weft: " << xmlEscape(entry["model"].get<std::string>())
          << (fibers ? ", its fibers" : "") << " (weft-models.json) -->\n"
          << "        <rgb name=\"reflectance\" value=\"0.5, 0.5, 0.5\"/>\n    </bsdf>\n"
          << "    <shape type=\"linearcurve\">\n        <string name=\"filename\" value=\""
          << xmlEscape(file) << "\"/>\n        <ref id=\"" << id << "\"/>\n    </shape>\n";
    }
    if (fibers && !scene.yarns.empty())
        ex.notes.push_back(
            "--fibers: weft-models.json maps the fiber curves back to weft "
            "models, whose import draws each fiber as a yarn");
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        const ObjectDesc& o = scene.objects[i];
        const std::string file = files.add(
            "meshes",
            o.type == ObjectDesc::Type::Mesh ? fs::path(o.file).stem().string() : "rectangle",
            ".obj", objText(objectTriangles(o)));
        x << "    <shape type=\"obj\">\n        <string name=\"filename\" value=\""
          << xmlEscape(file) << "\"/>\n";
        const SurfaceMaterialDesc& m = o.material;
        if (m.type == SurfaceMaterialDesc::Type::Diffuse) {
            x << "        <bsdf type=\"diffuse\">\n            <rgb name=\"reflectance\" value=\""
              << formatNumber(m.reflectance.r) << ", " << formatNumber(m.reflectance.g) << ", "
              << formatNumber(m.reflectance.b) << "\"/>\n        </bsdf>\n";
        } else {
            x << "        <bsdf type=\"roughconductor\">\n"
              << "            <string name=\"material\" value=\"none\"/>\n"
              << "            <string name=\"distribution\" value=\"ggx\"/>\n"
              << "            <float name=\"alpha\" value=\"" << formatNumber(m.roughness)
              << "\"/>\n"
              << "            <rgb name=\"specular_reflectance\" value=\""
              << formatNumber(m.colour.r) << ", " << formatNumber(m.colour.g) << ", "
              << formatNumber(m.colour.b) << "\"/>\n        </bsdf>\n";
            ex.notes.push_back("objects[" + std::to_string(i) +
                               "]: a conductor written as Mitsuba's roughconductor of material "
                               "none (a tinted mirror Fresnel, not weft's Schlick)");
        }
        x << "    </shape>\n";
    }
    x << "</scene>\n";
    ex.files.insert(ex.files.begin(), {"scene.xml", x.str()});
    ex.files.push_back({"weft-models.json", models.dump(2) + "\n"});
    return ex;
}

void writeSceneFolder(const std::vector<std::pair<std::string, std::string>>& files,
                      const std::string& dir) {
    static const std::set<std::string> ours = {"scene.json", "scene.xml", "weft-models.json",
                                               "curves",     "fibers",    "meshes",
                                               "models",     "textures"};
    std::error_code ec;
    if (fs::is_directory(fs::symlink_status(dir, ec))) {
        for (const fs::directory_entry& e : fs::directory_iterator(dir, ec))
            if (!ours.count(e.path().filename().string()))
                throw InputError("output directory '" + dir + "' exists and holds '" +
                                 e.path().filename().string() +
                                 "', which a scene import or export does not write: remove it "
                                 "or choose another directory");
        if (ec) throw InputError("cannot list output directory '" + dir + "': " + ec.message());
    }
    TempDirCommit out(dir);
    for (const auto& [name, bytes] : files) {
        fs::create_directories(fs::path(out.path()) / fs::path(name).parent_path());
        writeFileAtomic(out.path() + "/" + name, bytes);
    }
    out.commit();
}

}  // namespace weft::render
