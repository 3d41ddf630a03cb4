// libFuzzer harness: the yarn-curve readers. The first byte picks one: the
// renderer's strict BCC, text and OBJ readers (render/curves.h), the
// polyline text reader of core/curve_io.h, or a text curve file and its
// vertex colours (the bytes before and after a "===" line). What the renderer's readers accept
// then goes through the curve report (render/curve_report.h, without a
// radius: the overlap sampling is bounded by the radius, not by the input).
#include "fuzz_util.h"
#include "weft/core/curve_io.h"
#include "weft/render/curve_report.h"
#include "weft/render/curves.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    const std::string bytes = weft::fuzz::bytesOf(data + 1, size - 1);
    weft::fuzz::expectOnlyInputErrors([&] {
        switch (data[0] % 5) {
            case 0:
                weft::render::curveReport(weft::render::parseBccCurves(bytes, "fuzz.bcc"));
                break;
            case 1:
                weft::render::curveReport(weft::render::parseTextCurves(bytes, "fuzz.txt"));
                break;
            case 2:
                weft::render::curveReport(weft::render::parseObjCurves(bytes, "fuzz.obj"));
                break;
            case 3:
                weft::parseCurveText(bytes, "fuzz.txt");
                break;
            default: {
                const size_t split = bytes.find("\n===\n");
                const std::string curves = bytes.substr(0, split);
                const std::string colours =
                    split == std::string::npos ? bytes : bytes.substr(split + 5);
                weft::render::CurveSet set = weft::render::parseTextCurves(curves, "fuzz.txt");
                weft::render::parseVertexColours(colours, "fuzz-colours.txt", &set);
                break;
            }
        }
    });
    return 0;
}
