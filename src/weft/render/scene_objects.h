// weft/render/scene_objects.h — what a scene holds besides yarns: a floor, a
// backdrop, triangle meshes (issue 43; docs/scene-format.md, "objects").
//
//   "objects": [
//     {"type": "rectangle", "center": [0, -0.1, 0], "normal": [0, 1, 0], "size": [4, 4],
//      "material": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}},
//     {"type": "mesh", "file": "arm.obj", "scale": 1, "translate": [0, 0, 0],
//      "material": {"type": "conductor", "colour": [0.95, 0.64, 0.54], "roughness": 0.3}}
//   ]
//
// A rectangle is two triangles: centre c, unit normal n, sides size[0] along
// u and size[1] along v, where u is world x or world z, whichever is less
// aligned with n, projected onto the plane, and v = n x u (a floor with
// normal +y: width along x, height along z). A mesh is the triangles of an OBJ file ("v"
// and "f" lines; a face of k vertices is a fan of k - 2 triangles; indices
// 1-based or negative, "v/vt/vn" forms read for their first number; other
// lines ignored) or of a PLY file (ascii or binary, either byte order: the
// vertex element's x, y, z and the face element's vertex_indices, faces as
// fans; every other property and element read past), each vertex p placed
// at scale p + translate. Materials are
// surface_bsdf.h's: "diffuse" (reflectance, default 0.5 grey) and
// "conductor" (colour F0, default copper-ish 0.95 0.64 0.54; roughness,
// default 0.3). Objects occlude and reflect light in every yarn mode.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "weft/core/bsdf.h"
#include "weft/core/json_reader.h"
#include "weft/core/rgb.h"
#include "weft/core/vec.h"

namespace weft::render {

// Largest number of triangles a scene's objects may hold (about 100 bytes
// each with Embree's BVH): an InputError naming the object beyond it.
inline constexpr int64_t kMaxSceneTriangles = int64_t{20} * 1000 * 1000;

struct SurfaceMaterialDesc {
    enum class Type { Diffuse, Conductor };
    Type type = Type::Diffuse;
    Rgb reflectance{0.5};          // diffuse
    Rgb colour{0.95, 0.64, 0.54};  // conductor: F0
    double roughness = 0.3;        // conductor: GGX alpha
};

struct ObjectDesc {
    enum class Type { Rectangle, Mesh };
    Type type = Type::Rectangle;
    // rectangle
    Vec3 center, normal{0, 1, 0};
    std::array<double, 2> size{1, 1};
    // mesh
    std::string file;  // resolved path of an .obj or .ply
    double scale = 1;
    Vec3 translate;
    SurfaceMaterialDesc material;
};

// Reads objects[i] (its keys checked; file extensions checked, files not opened).
ObjectDesc readObject(JsonObjectReader r, const std::string& baseDir);
// Every key written (defaults included), paths as stored.
nlohmann::json toJson(const ObjectDesc& object);

// A triangle soup in world space.
struct Triangles {
    std::vector<Vec3> vertices;
    std::vector<std::array<uint32_t, 3>> indices;
};
// The object's triangles (a mesh's file read here: InputError naming
// file:line for a malformed line, an index out of range, a non-finite
// coordinate, or more than kMaxSceneTriangles).
Triangles objectTriangles(const ObjectDesc& object);
// The OBJ reader on text already in memory (pathForErrors in messages).
Triangles parseObjTriangles(std::string_view text, const std::string& pathForErrors);
// The PLY reader on a file's bytes (ply_triangles.cpp): InputError naming
// the file, and the header line, the body line (ascii) or the element
// instance, for anything malformed, truncated or out of range.
Triangles parsePlyTriangles(std::string_view bytes, const std::string& pathForErrors);
// The triangles of a mesh file, by its extension (.obj or .ply, any case).
Triangles readMeshTriangles(const std::string& path);
// Its material's BSDF, validated (`what`: "objects[i].material").
std::unique_ptr<Bsdf> makeSurfaceBsdf(const SurfaceMaterialDesc& material, const std::string& what);

}  // namespace weft::render
