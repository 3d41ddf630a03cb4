// libFuzzer harness: the yarn-curve readers. The first byte picks one: the
// renderer's strict BCC, text and OBJ readers (render/curves.h) or the
// polyline text reader of core/curve_io.h. What the renderer's readers accept
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
        switch (data[0] % 4) {
            case 0:
                weft::render::curveReport(weft::render::parseBccCurves(bytes, "fuzz.bcc"));
                break;
            case 1:
                weft::render::curveReport(weft::render::parseTextCurves(bytes, "fuzz.txt"));
                break;
            case 2:
                weft::render::curveReport(weft::render::parseObjCurves(bytes, "fuzz.obj"));
                break;
            default:
                weft::parseCurveText(bytes, "fuzz.txt");
                break;
        }
    });
    return 0;
}
