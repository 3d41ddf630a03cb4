// libFuzzer harness: weft view's edit messages (view/view_session.h), as the
// server receives them (core/json_file.h's parser, then applyEdit) against a
// small scene: any message ends in an InputError or an edit taken.
#include <filesystem>
#include <memory>

#include "fuzz_util.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"
#include "weft/view/view_session.h"

namespace {

weft::view::ViewSession& session() {
    static std::unique_ptr<weft::view::ViewSession> s = [] {
        const std::filesystem::path dir =
            std::filesystem::temp_directory_path() / "weft_view_edit_fuzz";
        std::filesystem::create_directories(dir);
        weft::writeFileAtomic((dir / "yarn.txt").string(), "-0.2 0 0\n0.2 0 0\n");
        weft::writeFileAtomic((dir / "scene.json").string(),
                              std::string(R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
                "film": {"width": 16, "height": 16}, "render": {"spp": 1},
                "lights": [{"type": "sky"}, {"type": "sphere", "center": [1, 1, 1],
                            "radius": 0.2, "radiance": [1, 1, 1]}],
                "yarns": [{"curves": "yarn.txt", "radius": 0.03, "plies": 2,
                           "model": ")") +
                                  WEFT_SOURCE_DIR "/tests/data/fleece-colour-small.json\"}]}");
        weft::view::ViewOptions o;
        o.scenePath = (dir / "scene.json").string();
        o.models = {WEFT_SOURCE_DIR "/tests/data/fleece-small.json"};
        o.threads = 1;
        return std::make_unique<weft::view::ViewSession>(o);
    }();
    return *s;
}

}  // namespace

// The session (a neural scene, its energy guard included) is built before
// the first input, so that libFuzzer's per-input -timeout measures edits only.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
    session();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    weft::view::ViewSession& s = session();
    weft::fuzz::expectOnlyInputErrors(
        [&] { s.applyEdit(weft::parseJsonText(weft::fuzz::bytesOf(data, size), "message")); });
    return 0;
}
