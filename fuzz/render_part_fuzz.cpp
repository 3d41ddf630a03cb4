// libFuzzer harness: the render parts of `weft render merge`
// (render/render_merge.h): the reader of PART.json and PART.exr, the checks
// that they are the shards of one render, the checksum of their pixels, and
// the merge, on files given from memory. The input is up to four parts, each
// a little-endian uint32 length and that many bytes of PART.json, then a
// length and PART.exr (a length beyond the input takes what is left). The
// seeds (fuzz/seeds/render_part/) are parts written by `weft render --shard`.
#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "fuzz_util.h"
#include "weft/core/error.h"
#include "weft/render/render_merge.h"

namespace {

// The length-prefixed piece of `input` at `at`, which moves past it.
std::string nextPiece(const std::string& input, size_t& at) {
    uint32_t length = 0;
    for (int k = 0; k < 4 && at < input.size(); ++k, ++at)
        length |= static_cast<uint32_t>(static_cast<unsigned char>(input[at])) << (8 * k);
    const size_t n = std::min<size_t>(length, input.size() - at);
    const std::string piece = input.substr(at, n);
    at += n;
    return piece;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string input = weft::fuzz::bytesOf(data, size);
    std::map<std::string, std::string> files;
    std::vector<std::string> parts;
    for (size_t at = 0; at < input.size() && parts.size() < 4;) {
        const std::string stem = "part" + std::to_string(parts.size());
        files[stem + ".json"] = nextPiece(input, at);
        files[stem + ".exr"] = nextPiece(input, at);
        parts.push_back(stem + ".exr");
    }
    weft::fuzz::expectOnlyInputErrors([&] {
        // As readFile: a file that is not there is an InputError (the merge
        // looks for PART.render.json when PART.json holds no statistics).
        const weft::render::MergedRender merged =
            weft::render::mergeRenderParts(parts, [&](const std::string& path) {
                const auto it = files.find(path);
                if (it == files.end())
                    throw weft::InputError("cannot read '" + path + "': No such file or directory");
                return it->second;
            });
        // What `weft render merge` then writes of the statistics.
        (void)merged.stats.dump(2);
        (void)merged.stats.at("mode").get<std::string>();
    });
    return 0;
}
