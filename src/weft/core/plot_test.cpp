#include "weft/core/plot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace weft {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

const Rgb kRed(0.8, 0.05, 0.05), kGreen(0.05, 0.6, 0.1), kBlue(0.05, 0.1, 0.8);

// The frame of plot.h's layout for textScale 1 and no title or axis labels.
struct Frame {
    int left, right, top, bottom;
};
Frame frameOf(const PlotOptions& o) { return {56, o.width - 1 - 12, 10, o.height - 1 - 22}; }

// Exactly the colour as stored in the float image (full coverage).
bool isColor(const Image& image, int x, int y, const Rgb& c) {
    const Rgb p = image.get(x, y);
    return p.r == float(c.r) && p.g == float(c.g) && p.b == float(c.b);
}

int countColor(const Image& image, const Rgb& c) {
    int n = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) n += isColor(image, x, y, c);
    return n;
}

// Rows of column x holding exactly colour c.
std::vector<int> rowsOf(const Image& image, int x, const Rgb& c) {
    std::vector<int> rows;
    for (int y = 0; y < image.height; ++y)
        if (isColor(image, x, y, c)) rows.push_back(y);
    return rows;
}

// The row of column x whose pixel is nearest to colour c (the line's centre).
int nearestRow(const Image& image, int x, const Rgb& c) {
    int best = -1;
    double bestDistance = 1e300;
    for (int y = 0; y < image.height; ++y) {
        const Rgb d = image.get(x, y) - c;
        const double distance = d.r * d.r + d.g * d.g + d.b * d.b;
        if (distance < bestDistance) best = y, bestDistance = distance;
    }
    return best;
}

PlotOptions linearOptions(int width = 800, int height = 501) {
    PlotOptions o;
    o.width = width, o.height = height, o.logY = false;
    return o;
}

TEST(Plot, ImageHasTheRequestedSize) {
    PlotOptions o = linearOptions(321, 203);
    o.title = "Loss (train)";
    o.xLabel = "step";
    o.yLabel = "loss";
    const Image image = plotLines({{"a", {0, 1, 2}, {3, 1, 2}, kRed}}, o);
    EXPECT_EQ(image.width, 321);
    EXPECT_EQ(image.height, 203);
    EXPECT_EQ(image.pixels.size(), size_t(321) * 203 * 3);
}

TEST(Plot, HorizontalSeriesLandsOnTheMappedRow) {
    const PlotOptions o = linearOptions();
    // The diagonal sets the ranges: x in [0, 10], y in [0, 10] (step 2, already nice).
    const Image image =
        plotLines({{"diagonal", {0, 10}, {0, 10}, Rgb(0.0)}, {"five", {0, 10}, {5, 5}, kRed}}, o);
    const Frame f = frameOf(o);
    const double row = f.bottom - (5.0 - 0.0) / (10.0 - 0.0) * (f.bottom - f.top);
    ASSERT_EQ(row, std::round(row)) << "choose a height with an integer row";
    const int x = int(std::lround(f.left + 0.2 * (f.right - f.left)));  // x = 2
    EXPECT_EQ(rowsOf(image, x, kRed), std::vector<int>{int(row)});
    // The line is continuous and confined to the frame: red in every column inside it.
    int redColumns = 0;
    for (int c = 0; c < image.width; ++c) redColumns += !rowsOf(image, c, kRed).empty();
    EXPECT_GE(redColumns, f.right - f.left - 20);  // the legend covers its right end
    EXPECT_LE(redColumns, f.right - f.left + 1);
    // Ticks at the 1-2-5 step: y = 2 is a tick (inward from the left side), y = 3 is not.
    const auto tickRow = [&](double y) {
        return int(std::lround(f.bottom - y / 10 * (f.bottom - f.top)));
    };
    EXPECT_TRUE(isColor(image, f.left + 3, tickRow(2), Rgb(0.0)));
    EXPECT_FALSE(isColor(image, f.left + 3, tickRow(3), Rgb(0.0)));
}

TEST(Plot, SeriesColourAppears) {
    const Image image = plotLines({{"loss", {}, {1.0, 0.5, 0.2, 0.1, 0.05}, kGreen},
                                   {"", {}, {2.0, 1.0, 0.7, 0.4, 0.3}, kBlue}},
                                  PlotOptions{});
    EXPECT_GT(countColor(image, kGreen), 200);  // full coverage only near the centre line
    EXPECT_GT(countColor(image, kBlue), 200);
    EXPECT_EQ(countColor(image, kRed), 0);
}

TEST(Plot, LogAxisPlacesDecadesAtEqualSpacing) {
    PlotOptions o = linearOptions();
    o.logY = true;
    const Image image = plotLines({{"", {0, 1}, {1, 1}, kRed},
                                   {"", {0, 1}, {10, 10}, kGreen},
                                   {"", {0, 1}, {100, 100}, kBlue}},
                                  o);
    const Frame f = frameOf(o);
    const int x = (f.left + f.right) / 2;
    // Range [10^0, 10^2]: 1 on the bottom side, 100 on the top side, 10 halfway.
    ASSERT_EQ((f.bottom - f.top) % 2, 0);
    EXPECT_EQ(rowsOf(image, x, kRed), std::vector<int>{f.bottom});
    EXPECT_EQ(rowsOf(image, x, kGreen), std::vector<int>{(f.top + f.bottom) / 2});
    EXPECT_EQ(rowsOf(image, x, kBlue), std::vector<int>{f.top});
}

TEST(Plot, LogAxisSlopeIsStraightAcrossDecades) {
    PlotOptions o = linearOptions();
    o.logY = true;
    // y = 10^(x / 2) on x in [0, 4]: a straight line from the bottom-left to the top-right.
    std::vector<double> x, y;
    for (int i = 0; i <= 40; ++i) x.push_back(i / 10.0), y.push_back(std::pow(10.0, i / 20.0));
    const Image image = plotLines({{"", x, y, kRed}}, o);
    const Frame f = frameOf(o);
    for (double t : {0.25, 0.5, 0.75}) {
        const int c = int(std::lround(f.left + t * (f.right - f.left)));
        const double expected = f.bottom - t * (f.bottom - f.top);
        EXPECT_NEAR(nearestRow(image, c, kRed), expected, 1.0) << "t = " << t;
    }
}

TEST(Plot, NonFiniteAndNonPositivePointsAreSkipped) {
    PlotOptions o = linearOptions(801);  // the frame spans 732 = 3 * 244 columns
    o.logY = true;
    // Used points: (3, 10), (5, 1000), (6, 100): x in [3, 6], decades [1, 3]. The skipped
    // point at x = 4 breaks the line between x = 3 and x = 5.
    const Image image = plotLines(
        {{"", {0, 1, 2, 3, 4, 5, 6, kNan}, {kNan, -1, 0, 10, kInf, 1000, 100, 1e9}, kRed}}, o);
    const Frame f = frameOf(o);
    EXPECT_TRUE(isColor(image, f.left, f.bottom, kRed));                         // (3, 10): a dot
    EXPECT_TRUE(isColor(image, f.right - (f.right - f.left) / 3, f.top, kRed));  // (5, 1000)
    const int x4 = f.left + (f.right - f.left) / 3;
    EXPECT_TRUE(rowsOf(image, x4, kRed).empty());
    EXPECT_TRUE(rowsOf(image, (f.left + x4) / 2, kRed).empty());
    EXPECT_FALSE(rowsOf(image, f.right - 5, kRed).empty());  // between x = 5 and 6

    // On a linear axis 0 and negative values are used; NaN and infinities are not.
    const Image linear = plotLines({{"", {}, {kNan, -1, kInf, 1, -kInf}, kRed}}, linearOptions());
    EXPECT_GT(countColor(linear, kRed), 0);
}

// Only white (background) and black (frame) pixels.
void expectFrameOnly(const Image& image, const PlotOptions& o) {
    const Frame f = frameOf(o);
    int black = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const bool isBlack = isColor(image, x, y, Rgb(0.0));
            ASSERT_TRUE(isBlack || isColor(image, x, y, Rgb(1.0))) << x << ", " << y;
            const bool onFrame = (x == f.left || x == f.right) && y >= f.top && y <= f.bottom;
            const bool onFrameRow = (y == f.top || y == f.bottom) && x >= f.left && x <= f.right;
            EXPECT_EQ(isBlack, onFrame || onFrameRow) << x << ", " << y;
            black += isBlack;
        }
    EXPECT_EQ(black, 2 * (f.right - f.left + f.bottom - f.top));
}

TEST(Plot, EmptyInputGivesJustTheFrame) {
    const PlotOptions o;
    expectFrameOnly(plotLines({}, o), o);
    expectFrameOnly(
        plotLines({{"empty", {}, {}, kRed}, {"all skipped", {1, 2}, {kNan, -1}, kBlue}}, o), o);
}

TEST(Plot, TextIsDrawnWhereTheLayoutPutsIt) {
    PlotOptions o;
    o.title = "Training loss";
    const Image titled = plotLines({}, o);
    int blackAbove = 0;  // above the frame, which moves down to row 24
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < o.width; ++x) blackAbove += isColor(titled, x, y, Rgb(0.0));
    EXPECT_GT(blackAbove, 30);
    EXPECT_TRUE(isColor(titled, 56, 24, Rgb(0.0)));  // the frame's top-left corner

    // A legend entry draws its swatch and label inside the frame's top-right corner.
    const Image legend = plotLines({{"train", {0, 1}, {1, 1}, kRed}}, linearOptions());
    const Frame f = frameOf(linearOptions());
    int legendRed = 0, legendBlack = 0;
    for (int y = f.top + 1; y < f.top + 40; ++y)
        for (int x = f.right - 100; x < f.right; ++x) {
            legendRed += isColor(legend, x, y, kRed);
            legendBlack += isColor(legend, x, y, Rgb(0.0));
        }
    EXPECT_GE(legendRed, 15);
    EXPECT_GT(legendBlack, 20);
}

TEST(Plot, UnknownCharactersAndLongTextDoNotCrash) {
    PlotOptions o = linearOptions(64 + 56 + 12, 64 + 34 + 24);
    o.title = std::string(200, '~') + "\x01\xff";
    o.xLabel = std::string(300, 'W');
    o.yLabel = std::string(300, 'y');
    o.textScale = 1;
    const Image image = plotLines({{std::string(100, 'x'), {}, {1e-300, 1e300}, kRed}}, o);
    EXPECT_EQ(image.width, o.width);
    // Extreme but finite linear values.
    EXPECT_NO_THROW(plotLines({{"", {-1e308, 1e308}, {-1.7e308, 1.7e308}, kRed}}, linearOptions()));
    EXPECT_NO_THROW(plotLines({{"", {1, 1}, {1e-5, 1e-5}, kRed}}, linearOptions()));
}

TEST(Plot, BadOptionsThrow) {
    const std::vector<PlotSeries> one = {{"a", {}, {1, 2}, kRed}};
    auto expectInvalid = [&](PlotOptions o, const std::string& field) {
        try {
            plotLines(one, o);
            ADD_FAILURE() << "expected std::invalid_argument for " << field;
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
        }
    };
    PlotOptions o;
    o.width = 63;
    expectInvalid(o, "width");
    o = {}, o.height = 0;
    expectInvalid(o, "height");
    o = {}, o.width = -5;
    expectInvalid(o, "width");
    o = {}, o.width = 1 << 20;
    expectInvalid(o, "width");
    o = {}, o.textScale = 0;
    expectInvalid(o, "textScale");
    o = {}, o.textScale = 5;
    expectInvalid(o, "textScale");
    o = {}, o.lineWidth = 0;
    expectInvalid(o, "lineWidth");
    o = {}, o.lineWidth = kNan;
    expectInvalid(o, "lineWidth");
    o = {}, o.width = 64;  // valid size, but the margins leave no frame
    expectInvalid(o, "frame");
    o = {}, o.height = 100, o.textScale = 4;
    expectInvalid(o, "frame");
    EXPECT_THROW(plotLines({{"a", {1, 2, 3}, {1, 2}, kRed}}, PlotOptions{}), std::invalid_argument);
    EXPECT_NO_THROW(plotLines(one, linearOptions(128, 96)));
}

TEST(Plot, ScaledTextAndPngEncoding) {
    PlotOptions o;
    o.textScale = 2;
    o.title = "Loss";
    const Image image = plotLines({{"a", {}, {3, 2, 1}, defaultPlotColor(0)}}, o);
    EXPECT_FALSE(encodePng(image).empty());
}

TEST(Plot, DefaultPaletteIsDistinctAndCycles) {
    for (size_t i = 0; i < 10; ++i) {
        const Rgb c = defaultPlotColor(i);
        EXPECT_TRUE(c.isFinite() && c.maxComponent() <= 1 && c.r >= 0 && c.g >= 0 && c.b >= 0);
        EXPECT_EQ(defaultPlotColor(i + 10), c);
        for (size_t j = 0; j < i; ++j) EXPECT_NE(defaultPlotColor(j), c);
    }
}

}  // namespace
}  // namespace weft
