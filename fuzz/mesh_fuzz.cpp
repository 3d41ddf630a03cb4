// libFuzzer harness: the mesh readers of scene objects (render/scene_objects.h).
// The first byte picks one: the OBJ reader or the PLY reader (ascii and
// binary); what they accept must index only vertices they read.
#include <stdexcept>

#include "fuzz_util.h"
#include "weft/render/scene_objects.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    const std::string bytes = weft::fuzz::bytesOf(data + 1, size - 1);
    weft::fuzz::expectOnlyInputErrors([&] {
        const weft::render::Triangles t = data[0] % 2 == 0
                                              ? weft::render::parseObjTriangles(bytes, "fuzz.obj")
                                              : weft::render::parsePlyTriangles(bytes, "fuzz.ply");
        for (const auto& tri : t.indices)
            for (uint32_t v : tri)
                if (v >= t.vertices.size())
                    throw std::logic_error("a mesh reader returned an index past its vertices");
    });
    return 0;
}
