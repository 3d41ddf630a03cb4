// weft/core/plot.h — a small dependency-free line-chart rasteriser (training loss curves).
//
// plotLines draws series of (x, y) points as anti-aliased polylines on a white
// background, inside an axes frame with ticks, numeric tick labels, a title,
// axis labels and a legend; text uses a built-in 5x7 bitmap font (digits,
// A-Z, a-z, space and . , - + = : ( ) / _ % ?; other characters draw as '?').
// The result is a linear-RGB Image, so series colours are linear too (see
// defaultPlotColor); writePng applies the sRGB encoding.
//
// Data. A point is used when x and y are finite (and y > 0 on a log axis);
// any other point is skipped and breaks the polyline there. An empty x means
// x = 0, 1, 2, ... (the step index). A point with no used neighbour is drawn
// as a dot.
//
// Layout, in pixels, with s = textScale and pixel centres at integer
// coordinates (column c, row r; row 0 at the top). The frame is the
// rectangle of columns [left, right] and rows [top, bottom], 1 pixel wide:
//   left   = s * (yLabel.empty() ? 56 : 70)
//   right  = width - 1 - 12 * s
//   top    = s * (title.empty() ? 10 : 24)
//   bottom = height - 1 - s * (xLabel.empty() ? 22 : 34)
//
// Axis ranges [xMin, xMax] and [vMin, vMax] cover the used points of all
// series, with v = log10(y) on a log axis and v = y otherwise:
//   linear: step = the smallest {1, 2, 5} * 10^k >= (max - min) / 5, and the
//           range is [floor(min / step), ceil(max / step)] * step; ticks sit
//           at every multiple of step;
//   log:    the range is [floor(log10 min), ceil(log10 max)] (whole decades);
//           10^j is a labelled tick when j is a multiple of k = ceil(decades / 8)
//           (at most 9 labels), other powers of ten are minor ticks, and so are
//           2..9 * 10^j when the range spans at most 6 decades.
// A range of zero width widens first: a linear [u, u] to [u - d, u + d] with
// d = |u| / 10 (d = 1 for u = 0) before the rounding to steps, a log [k, k]
// to [k, k + 1]. Labelled ticks get a light grey grid line across the frame.
//
// Mapping of a point (x, y) to pixel coordinates:
//   column = left   + (x - xMin) / (xMax - xMin) * (right - left)
//   row    = bottom - (v - vMin) / (vMax - vMin) * (bottom - top)
// Lines are lineWidth * s pixels wide, with pixel coverage
// clamp(width / 2 + 1/2 - distance to the polyline, 0, 1) blended over what is
// there, clipped to the frame (inclusive), and drawn after the frame and grid
// in series order: a horizontal line at an integer row has exactly the series
// colour on that row.
//
// The legend (series with a non-empty label) sits in the top-right corner
// inside the frame. With no used point at all the image holds the frame, the
// title and the axis labels only (no ticks, no legend).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "weft/core/image.h"
#include "weft/core/rgb.h"

namespace weft {

struct PlotSeries {
    std::string label;      // legend entry; empty: not listed
    std::vector<double> x;  // empty: 0, 1, 2, ...; else as many as y
    std::vector<double> y;
    Rgb color{0.0, 0.0, 0.0};  // linear RGB, each component in [0, 1]
};

struct PlotOptions {
    int width = 800, height = 500;  // pixels, each >= 64 (and the frame >= 32 x 32)
    bool logY = true;               // log10 y axis; y <= 0 is skipped
    std::string title, xLabel, yLabel;
    int textScale = 1;       // integer scale of the 5x7 font and of the margins, 1..4
    double lineWidth = 1.5;  // series line width before textScale, in (0, 16]
};

// The chart of the series; throws std::invalid_argument naming the field and its
// allowed range for bad options, or for a series whose x and y differ in length.
Image plotLines(const std::vector<PlotSeries>& series, const PlotOptions& options);

// A palette of 10 distinguishable linear-RGB colours (matplotlib's "tab10"),
// cycling with index.
Rgb defaultPlotColor(size_t index);

}  // namespace weft
