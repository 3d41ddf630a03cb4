#include "weft/core/plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace weft {
namespace {

// ---- 5x7 bitmap font --------------------------------------------------------------------

// A glyph is 7 rows of 5 pixels, bit 4 the leftmost column; drop moves it down by
// that many rows in its 9-row cell (rows 7-8 hold descenders: g p q y , _).
struct Glyph {
    char c;
    uint8_t drop;
    std::array<uint8_t, 7> rows;
};

// Sorted by character code.
constexpr Glyph kFont[] = {
    {' ', 0, {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}},
    {'%', 0, {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'(', 0, {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', 0, {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'+', 0, {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {',', 1, {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {'-', 0, {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'.', 0, {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {'/', 0, {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {'0', 0, {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', 0, {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', 0, {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', 0, {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', 0, {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', 0, {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', 0, {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', 0, {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', 0, {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', 0, {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {':', 0, {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'=', 0, {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'?', 0, {0x0E, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04}},
    {'A', 0, {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'B', 0, {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', 0, {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {'D', 0, {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', 0, {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {'F', 0, {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', 0, {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {'H', 0, {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', 0, {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'J', 0, {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', 0, {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', 0, {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', 0, {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', 0, {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', 0, {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'P', 0, {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', 0, {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {'R', 0, {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', 0, {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {'T', 0, {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', 0, {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'V', 0, {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', 0, {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {'X', 0, {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', 0, {0x11, 0x11, 0x0A, 0x04, 0x04, 0x04, 0x04}},
    {'Z', 0, {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'_', 1, {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
    {'a', 0, {0x00, 0x00, 0x0E, 0x01, 0x0F, 0x11, 0x0F}},
    {'b', 0, {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x1E}},
    {'c', 0, {0x00, 0x00, 0x0E, 0x10, 0x10, 0x11, 0x0E}},
    {'d', 0, {0x01, 0x01, 0x0D, 0x13, 0x11, 0x11, 0x0F}},
    {'e', 0, {0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E}},
    {'f', 0, {0x06, 0x09, 0x08, 0x1C, 0x08, 0x08, 0x08}},
    {'g', 2, {0x0F, 0x11, 0x11, 0x11, 0x0F, 0x01, 0x0E}},
    {'h', 0, {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {'i', 0, {0x04, 0x00, 0x0C, 0x04, 0x04, 0x04, 0x0E}},
    {'j', 0, {0x02, 0x00, 0x06, 0x02, 0x02, 0x12, 0x0C}},
    {'k', 0, {0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12}},
    {'l', 0, {0x0C, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'m', 0, {0x00, 0x00, 0x1A, 0x15, 0x15, 0x15, 0x15}},
    {'n', 0, {0x00, 0x00, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {'o', 0, {0x00, 0x00, 0x0E, 0x11, 0x11, 0x11, 0x0E}},
    {'p', 2, {0x1E, 0x11, 0x11, 0x11, 0x1E, 0x10, 0x10}},
    {'q', 2, {0x0F, 0x11, 0x11, 0x11, 0x0F, 0x01, 0x01}},
    {'r', 0, {0x00, 0x00, 0x16, 0x19, 0x10, 0x10, 0x10}},
    {'s', 0, {0x00, 0x00, 0x0F, 0x10, 0x0E, 0x01, 0x1E}},
    {'t', 0, {0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06}},
    {'u', 0, {0x00, 0x00, 0x11, 0x11, 0x11, 0x13, 0x0D}},
    {'v', 0, {0x00, 0x00, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'w', 0, {0x00, 0x00, 0x11, 0x11, 0x15, 0x15, 0x0A}},
    {'x', 0, {0x00, 0x00, 0x11, 0x0A, 0x04, 0x0A, 0x11}},
    {'y', 2, {0x11, 0x11, 0x11, 0x11, 0x0F, 0x01, 0x0E}},
    {'z', 0, {0x00, 0x00, 0x1F, 0x02, 0x04, 0x08, 0x1F}},
};

static_assert(std::is_sorted(std::begin(kFont), std::end(kFont),
                             [](const Glyph& a, const Glyph& b) { return a.c < b.c; }));

constexpr int kGlyphWidth = 5, kGlyphHeight = 7;
constexpr int kAdvance = 6;     // glyph width plus one column of spacing
constexpr int kCellHeight = 9;  // cap height plus two descender rows

const Glyph& glyphOf(char c) {
    const auto it = std::lower_bound(std::begin(kFont), std::end(kFont), c,
                                     [](const Glyph& g, char key) { return g.c < key; });
    if (it != std::end(kFont) && it->c == c) return *it;
    return glyphOf('?');
}

// ---- pixels -----------------------------------------------------------------------------

struct Rect {
    int x0, y0, x1, y1;  // inclusive
};

// Blends c over the pixel with opacity alpha; pixels outside the image are ignored.
void blend(Image& image, int x, int y, const Rgb& c, double alpha) {
    if (x < 0 || y < 0 || x >= image.width || y >= image.height || alpha <= 0) return;
    if (alpha >= 1) return image.set(x, y, c);
    image.set(x, y, image.get(x, y) * (1 - alpha) + c * alpha);
}

void fillRect(Image& image, const Rect& r, const Rgb& c) {
    for (int y = std::max(r.y0, 0); y <= std::min(r.y1, image.height - 1); ++y)
        for (int x = std::max(r.x0, 0); x <= std::min(r.x1, image.width - 1); ++x)
            image.set(x, y, c);
}

int textWidth(const std::string& text, int scale) {
    return text.empty() ? 0 : scale * (kAdvance * static_cast<int>(text.size()) - 1);
}

// Draws text with the top-left corner of its first cell at (x, y); with up, the text
// is turned a quarter counter-clockwise (read bottom to top) and (x, y) is the
// bottom-left corner of its box.
void drawText(Image& image, const std::string& text, int x, int y, int scale, const Rgb& c,
              bool up = false) {
    for (size_t i = 0; i < text.size(); ++i) {
        const Glyph& g = glyphOf(text[i]);
        for (int row = 0; row < kGlyphHeight; ++row)
            for (int col = 0; col < kGlyphWidth; ++col) {
                if (!(g.rows[row] >> (kGlyphWidth - 1 - col) & 1)) continue;
                const int u = scale * (kAdvance * static_cast<int>(i) + col);  // along the text
                const int v = scale * (g.drop + row);                          // down the cell
                for (int dv = 0; dv < scale; ++dv)
                    for (int du = 0; du < scale; ++du) {
                        if (up)
                            blend(image, x + v + dv, y - u - du, c, 1);
                        else
                            blend(image, x + u + du, y + v + dv, c, 1);
                    }
            }
    }
}

struct Point {
    double x, y;  // pixel coordinates (column, row)
};

double distanceToSegment(const Point& p, const Point& a, const Point& b) {
    const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
    double t = len2 > 0 ? ((p.x - a.x) * dx + (p.y - a.y) * dy) / len2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    return std::hypot(p.x - a.x - t * dx, p.y - a.y - t * dy);
}

// Strokes the polylines (a single point is a dot) with width-pixel lines clipped to
// clip. Coverage is the maximum over segments, so joints are not blended twice.
void strokePolylines(Image& image, const std::vector<std::vector<Point>>& lines, double width,
                     const Rgb& color, Rect clip) {
    clip = {std::max(clip.x0, 0), std::max(clip.y0, 0), std::min(clip.x1, image.width - 1),
            std::min(clip.y1, image.height - 1)};
    if (clip.x1 < clip.x0 || clip.y1 < clip.y0) return;
    const int cw = clip.x1 - clip.x0 + 1, ch = clip.y1 - clip.y0 + 1;
    std::vector<float> coverage(static_cast<size_t>(cw) * ch, 0.0f);
    const double reach = 0.5 * width + 0.5;
    auto stroke = [&](const Point& a, const Point& b) {
        if (!std::isfinite(a.x + a.y + b.x + b.y)) return;
        // Bounds in double first: points far outside the frame must not overflow int.
        const double x0 = std::max(std::floor(std::min(a.x, b.x) - reach), double(clip.x0));
        const double x1 = std::min(std::ceil(std::max(a.x, b.x) + reach), double(clip.x1));
        const double y0 = std::max(std::floor(std::min(a.y, b.y) - reach), double(clip.y0));
        const double y1 = std::min(std::ceil(std::max(a.y, b.y) + reach), double(clip.y1));
        for (int y = int(y0); y <= int(y1) && y0 <= y1; ++y)
            for (int x = int(x0); x <= int(x1) && x0 <= x1; ++x) {
                const double c =
                    std::clamp(reach - distanceToSegment({double(x), double(y)}, a, b), 0.0, 1.0);
                float& dst = coverage[size_t(y - clip.y0) * cw + (x - clip.x0)];
                dst = std::max(dst, float(c));
            }
    };
    for (const auto& line : lines) {
        if (line.size() == 1) stroke(line[0], line[0]);
        for (size_t i = 1; i < line.size(); ++i) stroke(line[i - 1], line[i]);
    }
    for (int y = 0; y < ch; ++y)
        for (int x = 0; x < cw; ++x)
            blend(image, clip.x0 + x, clip.y0 + y, color, coverage[size_t(y) * cw + x]);
}

// ---- axes -------------------------------------------------------------------------------

struct Tick {
    double v;           // axis coordinate (log10 y on a log axis)
    std::string label;  // empty: a minor tick
};

struct Axis {
    double lo = 0, hi = 1;
    std::vector<Tick> ticks;
};

std::string format(const char* fmt, auto... args) {
    char buf[64];
    std::snprintf(buf, sizeof buf, fmt, args...);
    return buf;
}

// Labels of multiples of step: fixed point with as many decimals as step needs, or
// mantissa-exponent ("1.5e6") when the axis holds only very large or very small values.
std::string linearLabel(double v, double step, bool scientific) {
    if (std::fabs(v) < 1e-9 * step) return "0";
    const int stepExponent = int(std::floor(std::log10(step) + 1e-9));
    if (!scientific) return format("%.*f", std::max(0, -stepExponent), v);
    const int e = int(std::floor(std::log10(std::fabs(v)) + 1e-9));
    return format("%.*fe%d", std::clamp(e - stepExponent, 0, 3), v / std::pow(10.0, e), e);
}

std::string decadeLabel(int k) {
    if (k >= 0 && k <= 3) return format("%.0f", std::pow(10.0, k));
    if (k < 0 && k >= -2) return format("%.*f", -k, std::pow(10.0, k));
    return format("1e%d", k);
}

// A zero-width range widens as plot.h says.
void widen(double& lo, double& hi) {
    if (lo < hi) return;
    const double d = lo == 0 ? 1.0 : 0.1 * std::fabs(lo);
    lo -= d, hi += d;
}

Axis linearAxis(double min, double max) {
    widen(min, max);
    // Halves first, so that a span near DBL_MAX does not overflow.
    const double raw = (0.5 * max - 0.5 * min) / 2.5;
    const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
    const double norm = raw / magnitude;
    const double step = magnitude * (norm <= 1 ? 1 : norm <= 2 ? 2 : norm <= 5 ? 5 : 10);
    const double first = std::floor(min / step + 1e-9), last = std::ceil(max / step - 1e-9);
    Axis axis{first * step, last * step, {}};
    if (!std::isfinite(axis.lo) || !std::isfinite(axis.hi)) return {min, max, {}};
    const double maxAbs = std::max(std::fabs(axis.lo), std::fabs(axis.hi));
    const bool scientific = maxAbs >= 1e6 || maxAbs < 1e-3;
    for (double i = first; i <= last; ++i)
        axis.ticks.push_back({i * step, linearLabel(i * step, step, scientific)});
    return axis;
}

Axis logAxis(double minLog, double maxLog) {
    const int lo = int(std::floor(minLog));
    int hi = int(std::ceil(maxLog));
    if (hi == lo) ++hi;
    Axis axis{double(lo), double(hi), {}};
    const int every = (hi - lo + 7) / 8;  // at most 9 labelled decades
    for (int k = lo; k <= hi; ++k) {
        const bool labelled = ((k % every) + every) % every == 0;
        axis.ticks.push_back({double(k), labelled ? decadeLabel(k) : std::string()});
        if (hi - lo <= 6 && k < hi)
            for (int m = 2; m <= 9; ++m) axis.ticks.push_back({k + std::log10(double(m)), ""});
    }
    return axis;
}

void check(bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("plotLines: " + what);
}

Rgb srgbToLinear(int r, int g, int b) {
    return {weft::srgbToLinear(r / 255.0), weft::srgbToLinear(g / 255.0),
            weft::srgbToLinear(b / 255.0)};
}

}  // namespace

Rgb defaultPlotColor(size_t index) {
    static const std::array<Rgb, 10> palette = {
        srgbToLinear(0x1f, 0x77, 0xb4), srgbToLinear(0xff, 0x7f, 0x0e),
        srgbToLinear(0x2c, 0xa0, 0x2c), srgbToLinear(0xd6, 0x27, 0x28),
        srgbToLinear(0x94, 0x67, 0xbd), srgbToLinear(0x8c, 0x56, 0x4b),
        srgbToLinear(0xe3, 0x77, 0xc2), srgbToLinear(0x7f, 0x7f, 0x7f),
        srgbToLinear(0xbc, 0xbd, 0x22), srgbToLinear(0x17, 0xbe, 0xcf)};
    return palette[index % palette.size()];
}

Image plotLines(const std::vector<PlotSeries>& series, const PlotOptions& options) {
    const int s = options.textScale;
    check(options.width >= 64 && options.width <= 16384,
          "PlotOptions.width = " + std::to_string(options.width) + " is outside [64, 16384]");
    check(options.height >= 64 && options.height <= 16384,
          "PlotOptions.height = " + std::to_string(options.height) + " is outside [64, 16384]");
    check(s >= 1 && s <= 4, "PlotOptions.textScale = " + std::to_string(s) + " is outside [1, 4]");
    check(options.lineWidth > 0 && options.lineWidth <= 16,
          "PlotOptions.lineWidth = " + std::to_string(options.lineWidth) + " is outside (0, 16]");
    const Rect frame{s * (options.yLabel.empty() ? 56 : 70), s * (options.title.empty() ? 10 : 24),
                     options.width - 1 - 12 * s,
                     options.height - 1 - s * (options.xLabel.empty() ? 22 : 34)};
    check(frame.x1 - frame.x0 >= 32 && frame.y1 - frame.y0 >= 32,
          "the frame (" + std::to_string(frame.x1 - frame.x0) + " x " +
              std::to_string(frame.y1 - frame.y0) +
              " pixels) is smaller than 32 x 32: enlarge width/height or lower textScale");
    for (size_t i = 0; i < series.size(); ++i) {
        const PlotSeries& ser = series[i];
        check(ser.x.empty() || ser.x.size() == ser.y.size(),
              "series " + std::to_string(i) + " ('" + ser.label + "') has " +
                  std::to_string(ser.x.size()) + " x values but " + std::to_string(ser.y.size()) +
                  " y values");
    }

    // The used points, in data coordinates (x, v), split where a point is skipped.
    std::vector<std::vector<std::vector<Point>>> runs(series.size());
    constexpr double inf = std::numeric_limits<double>::infinity();
    double xMin = inf, xMax = -inf, vMin = inf, vMax = -inf;
    for (size_t i = 0; i < series.size(); ++i) {
        const PlotSeries& ser = series[i];
        bool broken = true;
        for (size_t j = 0; j < ser.y.size(); ++j) {
            const double x = ser.x.empty() ? double(j) : ser.x[j];
            const double y = ser.y[j];
            const double v = options.logY ? (y > 0 ? std::log10(y) : inf) : y;
            if (!std::isfinite(x) || !std::isfinite(v)) {
                broken = true;
                continue;
            }
            if (broken) runs[i].emplace_back();
            broken = false;
            runs[i].back().push_back({x, v});
            xMin = std::min(xMin, x), xMax = std::max(xMax, x);
            vMin = std::min(vMin, v), vMax = std::max(vMax, v);
        }
    }

    const Rgb black(0.0), white(1.0), grid(0.82), legendBorder(0.35);
    Image image(options.width, options.height);
    fillRect(image, {0, 0, image.width - 1, image.height - 1}, white);
    const int frameCentre = (frame.x0 + frame.x1) / 2;
    if (!options.title.empty())
        drawText(image, options.title, frameCentre - textWidth(options.title, s) / 2, 8 * s, s,
                 black);
    if (!options.xLabel.empty())
        drawText(image, options.xLabel, frameCentre - textWidth(options.xLabel, s) / 2,
                 frame.y1 + 18 * s, s, black);
    if (!options.yLabel.empty())
        drawText(image, options.yLabel, 4 * s,
                 (frame.y0 + frame.y1) / 2 + textWidth(options.yLabel, s) / 2, s, black, true);

    const bool empty = !(xMin <= xMax);
    const Axis xAxis = empty ? Axis{} : linearAxis(xMin, xMax);
    const Axis yAxis = empty ? Axis{} : options.logY ? logAxis(vMin, vMax) : linearAxis(vMin, vMax);
    // The mapping of plot.h, with halved operands (exact) so that ranges near DBL_MAX
    // do not overflow.
    auto fraction = [](double v, const Axis& axis) {
        return (0.5 * v - 0.5 * axis.lo) / (0.5 * axis.hi - 0.5 * axis.lo);
    };
    auto column = [&](double x) { return frame.x0 + fraction(x, xAxis) * (frame.x1 - frame.x0); };
    auto row = [&](double v) { return frame.y1 - fraction(v, yAxis) * (frame.y1 - frame.y0); };

    // Grid and ticks (inward, on the left and bottom sides), then the frame over them.
    for (const Tick& t : xAxis.ticks) {
        const int c = int(std::lround(column(t.v)));
        if (c < frame.x0 || c > frame.x1) continue;
        if (!t.label.empty()) fillRect(image, {c, frame.y0, c, frame.y1}, grid);
        const int len = s * (t.label.empty() ? 3 : 5);
        fillRect(image, {c, frame.y1 - len, c, frame.y1}, black);
        // Centred on the tick, but kept inside the image at the right end.
        const int labelWidth = textWidth(t.label, s);
        const int x = std::min(c - labelWidth / 2, image.width - 1 - labelWidth);
        drawText(image, t.label, x, frame.y1 + 5 * s, s, black);
    }
    for (const Tick& t : yAxis.ticks) {
        const int r = int(std::lround(row(t.v)));
        if (r < frame.y0 || r > frame.y1) continue;
        if (!t.label.empty()) fillRect(image, {frame.x0, r, frame.x1, r}, grid);
        const int len = s * (t.label.empty() ? 3 : 5);
        fillRect(image, {frame.x0, r, frame.x0 + len, r}, black);
        drawText(image, t.label, frame.x0 - 4 * s - textWidth(t.label, s), r - 3 * s, s, black);
    }
    fillRect(image, {frame.x0, frame.y0, frame.x1, frame.y0}, black);
    fillRect(image, {frame.x0, frame.y1, frame.x1, frame.y1}, black);
    fillRect(image, {frame.x0, frame.y0, frame.x0, frame.y1}, black);
    fillRect(image, {frame.x1, frame.y0, frame.x1, frame.y1}, black);
    if (empty) return image;

    const double lineWidth = options.lineWidth * s;
    for (size_t i = 0; i < series.size(); ++i) {
        for (auto& line : runs[i])
            for (Point& p : line) p = {column(p.x), row(p.y)};
        strokePolylines(image, runs[i], lineWidth, series[i].color, frame);
    }

    // Legend: a boxed list in the top-right corner of the frame.
    const int pad = 4 * s, swatch = 20 * s, entryHeight = (kCellHeight + 2) * s;
    int labelWidth = 0, entries = 0;
    for (const PlotSeries& ser : series)
        if (!ser.label.empty())
            labelWidth = std::max(labelWidth, textWidth(ser.label, s)), ++entries;
    if (entries == 0) return image;
    const Rect box{frame.x1 - 6 * s - (3 * pad + swatch + labelWidth), frame.y0 + 6 * s,
                   frame.x1 - 6 * s, frame.y0 + 6 * s + 2 * pad + entries * entryHeight - 2 * s};
    const Rect inner{std::max(box.x0, frame.x0 + 1), box.y0, box.x1,
                     std::min(box.y1, frame.y1 - 1)};
    fillRect(image, inner, legendBorder);
    fillRect(image, {inner.x0 + 1, inner.y0 + 1, inner.x1 - 1, inner.y1 - 1}, white);
    int y = box.y0 + pad;
    for (const PlotSeries& ser : series) {
        if (ser.label.empty()) continue;
        const double mid = y + 3 * s;  // the middle row of the cap height
        strokePolylines(
            image, {{{double(box.x0 + pad), mid}, {double(box.x0 + pad + swatch), mid}}}, lineWidth,
            ser.color, {inner.x0 + 1, inner.y0 + 1, inner.x1 - 1, inner.y1 - 1});
        drawText(image, ser.label, box.x0 + 2 * pad + swatch, y, s, black);
        y += entryHeight;
    }
    return image;
}

}  // namespace weft
