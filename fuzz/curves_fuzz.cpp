// libFuzzer harness: the yarn-curve files (core/curves.h). The first byte
// picks one: the BCC, text or OBJ reader; the text reader and then both
// writers, whose output must read back as what was read; or a text curve file
// and its vertex colours (render/curves.h; the bytes before and after a "==="
// line). What the readers accept then goes through the curve report
// (render/curve_report.h, without a radius: the overlap sampling is bounded
// by the radius, not by the input).
#include <bit>
#include <cstdint>
#include <stdexcept>

#include "fuzz_util.h"
#include "weft/core/curves.h"
#include "weft/render/curve_report.h"
#include "weft/render/curves.h"

namespace {

// The curves as float32 data, as BCC holds them and the renderer draws them.
weft::CurveSet toFloat(weft::CurveSet set) {
    for (weft::Curve& c : set.curves)
        for (weft::Vec3& p : c.points)
            p = {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)};
    return set;
}

// Float32 curves written by `format` and read again by `parse` must come back
// bit for bit once rounded to float32 (text keeps the radii, BCC has none).
template <typename Format, typename Parse>
void expectRoundTrip(const weft::CurveSet& set, Format format, Parse parse, bool radii) {
    const weft::CurveSet back = toFloat(parse(format(set)));
    bool same = back.curves.size() == set.curves.size();
    for (size_t i = 0; same && i < set.curves.size(); ++i) {
        const weft::Curve &a = set.curves[i], &b = back.curves[i];
        same = a.points.size() == b.points.size() && a.closed == b.closed &&
               (radii ? a.radii == b.radii : b.radii.empty());
        for (size_t j = 0; same && j < a.points.size(); ++j)
            for (int k = 0; k < 3; ++k)
                same = same && std::bit_cast<uint32_t>(static_cast<float>(a.points[j][k])) ==
                                   std::bit_cast<uint32_t>(static_cast<float>(b.points[j][k]));
    }
    if (!same) throw std::logic_error("a curve file written by weft reads back differently");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    const std::string bytes = weft::fuzz::bytesOf(data + 1, size - 1);
    weft::fuzz::expectOnlyInputErrors([&] {
        switch (data[0] % 5) {
            case 0:
                weft::render::curveReport(weft::parseBccCurves(bytes, "fuzz.bcc"));
                break;
            case 1:
                weft::render::curveReport(weft::parseTextCurves(bytes, "fuzz.txt"));
                break;
            case 2:
                weft::render::curveReport(weft::parseObjCurves(bytes, "fuzz.obj"));
                break;
            case 3: {
                const weft::CurveSet set = toFloat(weft::parseTextCurves(bytes, "fuzz.txt"));
                expectRoundTrip(
                    set, [](const weft::CurveSet& s) { return weft::formatCurveText(s, "w.txt"); },
                    [](const std::string& t) { return weft::parseTextCurves(t, "w.txt"); }, true);
                expectRoundTrip(
                    set, [](const weft::CurveSet& s) { return weft::formatBcc(s, "", "w.bcc"); },
                    [](const std::string& b) { return weft::parseBccCurves(b, "w.bcc"); }, false);
                break;
            }
            default: {
                const size_t split = bytes.find("\n===\n");
                const std::string curves = bytes.substr(0, split);
                const std::string colours =
                    split == std::string::npos ? bytes : bytes.substr(split + 5);
                weft::CurveSet set = weft::parseTextCurves(curves, "fuzz.txt");
                weft::render::parseVertexColours(colours, "fuzz-colours.txt", &set);
                break;
            }
        }
    });
    return 0;
}
