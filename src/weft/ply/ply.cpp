#include "weft/ply/ply.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"

namespace weft {

namespace {

using Point = std::array<double, 2>;

// Rng stream reserved for fiber placement ("ply-cent"); the user seed picks the offset.
constexpr uint64_t kPlacementStream = 0x706c792d63656e74ULL;

// Placement aims for a spacing of 2r (1 + kSpacingMargin) so that the result
// is strictly >= 2r despite rounding; the acceptance test is d >= 2r.
constexpr double kSpacingMargin = 1e-9;
// Relaxation pushes close pairs to 2r (1 + kRelaxMargin), a little further
// apart than needed: the residual overlaps of the iteration then fall below
// the acceptance spacing far sooner (measured: 2-3x fewer sweeps near rho =
// 0.8 than with a margin of 1e-6, and a higher reachable density).
constexpr double kRelaxMargin = 1e-3;
// Centres projected onto the boundary land this far (relative) inside it.
constexpr double kBoundaryShrink = 1.0 - 1e-12;

// Random sequential placement: attempts per fiber on average, and the most
// consecutive rejections before giving up (near the jamming limit the
// acceptance rate collapses; the relaxation then takes over).
constexpr int64_t kRsaAttemptsPerFiber = 200;
constexpr int64_t kRsaMaxConsecutiveFailures = 4000;
// Best-of-k candidates for each fiber the relaxation has to insert.
constexpr int kInsertCandidates = 16;
// Verlet-list skin of the relaxation, relative to the spacing 2r.
constexpr double kRelaxSkin = 0.2;
// Relaxation work budget in fiber visits (sweeps * N), and the sweep bounds:
// a hopeless N = 2000 case gives up after ~0.5 s on a 2-core dev box.
constexpr int64_t kRelaxVisitBudget = 6000000;
constexpr int64_t kRelaxMinSweeps = 200;
constexpr int64_t kRelaxMaxSweeps = 20000;

std::string formatDouble(double v) {
    std::ostringstream os;
    os << v;
    return os.str();
}

// Uniform grid over the square [-h, h]^2 with cells at least `spacing` wide, so
// that two points closer than the spacing lie in the same or adjacent cells.
// The cell count is capped at about 4 per point (very thin fibers would
// otherwise need a huge grid); larger cells stay correct, just slower.
class Grid {
  public:
    Grid(double halfWidth, double spacing, int points) : halfWidth_(halfWidth) {
        const double cap = std::max(1.0, 2.0 * std::ceil(std::sqrt(static_cast<double>(points))));
        const double wanted = spacing > 0 ? std::ceil(2.0 * halfWidth / spacing) : 1.0;
        dim_ = static_cast<int>(std::clamp(wanted, 1.0, cap));
        cell_ = std::max(spacing, 2.0 * halfWidth / dim_);
        head_.assign(static_cast<size_t>(dim_) * dim_, -1);
        next_.assign(points, -1);
    }

    void clear() { std::fill(head_.begin(), head_.end(), -1); }

    void insert(int i, const Point& p) {
        const int c = cellIndex(cellCoord(p[0]), cellCoord(p[1]));
        next_[i] = head_[c];
        head_[c] = i;
    }

    void rebuild(const std::vector<Point>& pts) {
        clear();
        for (int i = 0; i < static_cast<int>(pts.size()); ++i) insert(i, pts[i]);
    }

    // Calls f(j) for every inserted point j in the 3x3 cells around p.
    template <typename F>
    void forEachNear(const Point& p, F&& f) const {
        const int cx = cellCoord(p[0]), cy = cellCoord(p[1]);
        for (int y = std::max(0, cy - 1); y <= std::min(dim_ - 1, cy + 1); ++y) {
            for (int x = std::max(0, cx - 1); x <= std::min(dim_ - 1, cx + 1); ++x) {
                for (int j = head_[cellIndex(x, y)]; j >= 0; j = next_[j]) f(j);
            }
        }
    }

  private:
    int cellCoord(double v) const {
        const double c = std::floor((v + halfWidth_) / cell_);
        return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(dim_ - 1)));
    }
    int cellIndex(int x, int y) const { return y * dim_ + x; }

    double halfWidth_;
    double cell_ = 1;
    int dim_ = 1;
    std::vector<int> head_, next_;
};

double dist2(const Point& a, const Point& b) { return sqr(a[0] - b[0]) + sqr(a[1] - b[1]); }

Point samplePointInDisk(Rng& rng, double diskRadius) {
    const double rad = diskRadius * kBoundaryShrink * std::sqrt(rng.uniform());
    const double phi = kTwoPi * rng.uniform();
    return {rad * std::cos(phi), rad * std::sin(phi)};
}

void projectIntoDisk(Point& p, double diskRadius) {
    const double r2 = sqr(p[0]) + sqr(p[1]);
    if (r2 <= sqr(diskRadius * kBoundaryShrink)) return;
    const double scale = diskRadius * kBoundaryShrink / std::sqrt(r2);
    p[0] *= scale;
    p[1] *= scale;
}

// Most points with pairwise distance >= 1 in a compact convex set of area A and
// perimeter P: A 2/sqrt(3) + P/2 + 1 (Oler 1961; Folkman and Graham 1969).
// Applied to the disk of radius R - r in units of the spacing 2r.
double maxPointsInDisk(double diskRadius, double spacing) {
    if (spacing <= 0) return std::numeric_limits<double>::infinity();
    const double d = diskRadius / spacing;
    return 2.0 / std::sqrt(3.0) * kPi * d * d + kPi * d + 1.0;
}

struct PackingCheck {
    int violations = 0;       // pairs closer than the spacing, plus centres outside the disk
    double worstOverlap = 0;  // largest (spacing - d) / spacing over the pairs
};

PackingCheck checkPacking(const std::vector<Point>& pts, double diskRadius, double spacing,
                          Grid& grid) {
    PackingCheck check;
    grid.rebuild(pts);
    const double s2 = spacing * spacing;
    for (int i = 0; i < static_cast<int>(pts.size()); ++i) {
        if (sqr(pts[i][0]) + sqr(pts[i][1]) > sqr(diskRadius)) ++check.violations;
        grid.forEachNear(pts[i], [&](int j) {
            if (j <= i) return;
            const double d2 = dist2(pts[i], pts[j]);
            if (d2 >= s2) return;
            ++check.violations;
            check.worstOverlap = std::max(check.worstOverlap, 1.0 - std::sqrt(d2) / spacing);
        });
    }
    return check;
}

// Random sequential placement: uniform candidates in the disk, kept when at
// least `target` away from every fiber placed so far. Returns the count placed.
int placeRandomSequential(Rng& rng, int n, double diskRadius, double target,
                          std::vector<Point>& pts, Grid& grid) {
    const double t2 = target * target;
    const int64_t budget = kRsaAttemptsPerFiber * n;
    int64_t failures = 0;
    for (int64_t attempt = 0; attempt < budget && static_cast<int>(pts.size()) < n; ++attempt) {
        const Point p = samplePointInDisk(rng, diskRadius);
        bool free = true;
        grid.forEachNear(p, [&](int j) { free = free && dist2(p, pts[j]) >= t2; });
        if (free) {
            grid.insert(static_cast<int>(pts.size()), p);
            pts.push_back(p);
            failures = 0;
        } else if (++failures > kRsaMaxConsecutiveFailures) {
            break;
        }
    }
    return static_cast<int>(pts.size());
}

// Deterministic relaxation: inserts the missing fibers at the least crowded of
// a few random spots, then repeatedly pushes close pairs apart (Gauss-Seidel
// over a Verlet pair list in index order) and projects centres back into the
// disk, within a fixed work budget. Returns true once every pair is at least
// `spacing` apart (checked on a fresh grid).
bool relaxPacking(Rng& rng, int n, double diskRadius, double spacing, std::vector<Point>& pts,
                  Grid& grid) {
    grid.rebuild(pts);
    while (static_cast<int>(pts.size()) < n) {
        Point best{};
        double bestScore = std::numeric_limits<double>::infinity();
        for (int c = 0; c < kInsertCandidates; ++c) {
            const Point p = samplePointInDisk(rng, diskRadius);
            double score = 0;
            grid.forEachNear(
                p, [&](int j) { score += std::max(0.0, spacing - std::sqrt(dist2(p, pts[j]))); });
            if (score < bestScore) {
                bestScore = score;
                best = p;
            }
        }
        grid.insert(static_cast<int>(pts.size()), best);
        pts.push_back(best);
    }

    // Pairs closer than `reach` at the last rebuild; any other pair is still
    // farther apart than `target` while no centre has moved more than half the
    // skin (reach - target) / 2 since then, so only listed pairs need pushing.
    const double target = spacing * (1.0 + kRelaxMargin);
    const double reach = spacing * (1.0 + kRelaxSkin);
    const double t2 = target * target;
    const double accept2 = sqr(spacing * (1.0 + kSpacingMargin));
    const double maxDrift2 = sqr(0.5 * (reach - target));
    Grid pairGrid(diskRadius, reach, n);
    std::vector<std::array<int, 2>> pairs;
    std::vector<Point> anchors;
    bool stale = true;
    const int64_t sweeps =
        std::clamp(kRelaxVisitBudget / std::max(n, 1), kRelaxMinSweeps, kRelaxMaxSweeps);
    for (int64_t sweep = 0; sweep < sweeps; ++sweep) {
        if (stale) {
            pairs.clear();
            pairGrid.rebuild(pts);
            for (int i = 0; i < n; ++i) {
                pairGrid.forEachNear(pts[i], [&](int j) {
                    if (j > i && dist2(pts[i], pts[j]) < reach * reach) pairs.push_back({i, j});
                });
            }
            anchors = pts;
            stale = false;
        }
        bool tooClose = false;
        for (const auto& [i, j] : pairs) {
            Point& a = pts[i];
            Point& b = pts[j];
            const double d2 = dist2(a, b);
            if (d2 >= t2) continue;
            tooClose = tooClose || d2 < accept2;
            double ux = b[0] - a[0], uy = b[1] - a[1];
            const double d = std::sqrt(d2);
            if (d > 0) {
                ux /= d;
                uy /= d;
            } else {
                // Coincident centres: separate along a direction fixed by the pair.
                const uint64_t h = mixBits(static_cast<uint64_t>(i) * n + j);
                const double phi = kTwoPi * static_cast<double>(h >> 11) * 0x1.0p-53;
                ux = std::cos(phi);
                uy = std::sin(phi);
            }
            const double push = 0.5 * (target - d);
            a[0] -= push * ux;
            a[1] -= push * uy;
            b[0] += push * ux;
            b[1] += push * uy;
            projectIntoDisk(a, diskRadius);
            projectIntoDisk(b, diskRadius);
        }
        for (int i = 0; i < n && !stale; ++i) stale = dist2(pts[i], anchors[i]) > maxDrift2;
        if (!tooClose && checkPacking(pts, diskRadius, spacing, grid).violations == 0) return true;
    }
    // The last sweep's pushes may have fixed everything it saw.
    return checkPacking(pts, diskRadius, spacing, grid).violations == 0;
}

std::vector<Point> placeFiberCentres(const PlyParams& params, double radius, double fiberRadius,
                                     uint64_t seed) {
    const int n = params.fibers;
    const double diskRadius = radius - fiberRadius;
    const double spacing = 2.0 * fiberRadius;
    const std::string what = "cannot pack N=" + std::to_string(n) +
                             " fibers of density rho=" + formatDouble(params.density) +
                             " into the ply";
    const std::string advice = "; use a lower density (random packing works up to about 0.7)";

    if (!(diskRadius >= 0)) {
        throw InputError(what + ": the fiber radius r = R sqrt(rho/N) exceeds the ply radius" +
                         advice);
    }
    const double maxPoints = maxPointsInDisk(diskRadius, spacing);
    if (n > maxPoints * (1.0 + 1e-9)) {
        throw InputError(what + ": fibers of radius r = R sqrt(rho/N) need centres at least 2r " +
                         "apart within R - r of the axis, and no packing holds more than " +
                         std::to_string(static_cast<int64_t>(maxPoints)) + " of them" + advice);
    }

    Rng rng(kPlacementStream, seed);
    std::vector<Point> pts;
    pts.reserve(n);
    Grid grid(diskRadius, spacing, n);
    const int placed =
        placeRandomSequential(rng, n, diskRadius, spacing * (1.0 + kSpacingMargin), pts, grid);
    if (placed == n) return pts;
    if (relaxPacking(rng, n, diskRadius, spacing, pts, grid)) return pts;

    const PackingCheck left = checkPacking(pts, diskRadius, spacing, grid);
    std::ostringstream os;
    os << what << " (placed " << placed << " with minimum spacing 2r; relaxing all " << n
       << " left " << left.violations << " overlaps, the deepest " << 100.0 * left.worstOverlap
       << "% of 2r)" << advice;
    throw InputError(os.str());
}

}  // namespace

void PlyParams::validate() const {
    if (fibers < 1 || fibers > kMaxPlyFibers) {
        throw InputError("ply: fibers (N) must be an integer in [1, " +
                         std::to_string(kMaxPlyFibers) + "], got " + std::to_string(fibers));
    }
    if (!(density > 0.0 && density < 1.0)) {
        throw InputError("ply: density (rho) must be in the open interval (0, 1), got " +
                         formatDouble(density));
    }
    if (!(twist >= 0.0 && std::isfinite(twist))) {
        throw InputError("ply: twist (alpha) must be finite and >= 0, got " + formatDouble(twist));
    }
}

double PlyGeometry::twistRate() const { return kPi * params.twist / radius; }

double PlyGeometry::twistPeriod() const {
    return params.twist > 0 ? 2.0 * radius / params.twist : std::numeric_limits<double>::infinity();
}

Vec3 PlyGeometry::fiberCentre(int i, double z) const {
    if (i < 0 || i >= static_cast<int>(centres.size())) {
        throw std::out_of_range("PlyGeometry::fiberCentre: fiber index " + std::to_string(i) +
                                " out of range [0, " + std::to_string(centres.size()) + ")");
    }
    const double angle = twistRate() * z;
    const double c = std::cos(angle), s = std::sin(angle);
    const auto& p = centres[i];
    return {c * p[0] - s * p[1], s * p[0] + c * p[1], z};
}

Vec3 PlyGeometry::fiberTangent(int i, double z) const {
    // d/dz of the rotated centre: k (-y, x) plus the axial 1.
    const Vec3 p = fiberCentre(i, z);
    const double k = twistRate();
    return normalize(Vec3(-k * p.y, k * p.x, 1.0));
}

std::vector<std::vector<Vec3>> PlyGeometry::polylines(int pointsPerTwist) const {
    if (pointsPerTwist < 16) {
        throw InputError("ply polylines: pointsPerTwist must be >= 16, got " +
                         std::to_string(pointsPerTwist));
    }
    double maxStep = 2.0 * radius;
    const double period = twistPeriod();
    if (std::isfinite(period)) maxStep = std::min(maxStep, period / pointsPerTwist);
    const double segments = std::max(1.0, std::ceil(length / maxStep));
    const double fibers = static_cast<double>(centres.size());
    if (!(fibers * (segments + 1.0) <= static_cast<double>(kMaxPlyPolylinePoints))) {
        std::ostringstream os;
        os << "ply polylines: " << centres.size() << " fibers of length L=" << length
           << " with pointsPerTwist=" << pointsPerTwist << " need " << fibers * (segments + 1.0)
           << " points, more than the limit " << kMaxPlyPolylinePoints
           << "; use a shorter length or fewer points per twist";
        throw InputError(os.str());
    }
    const int64_t count = static_cast<int64_t>(segments);
    std::vector<std::vector<Vec3>> lines(centres.size());
    for (int i = 0; i < static_cast<int>(centres.size()); ++i) {
        lines[i].reserve(count + 1);
        for (int64_t j = 0; j <= count; ++j) {
            const double z = j == count ? length : length * static_cast<double>(j) / count;
            lines[i].push_back(fiberCentre(i, z));
        }
    }
    return lines;
}

PlyGeometry generatePly(const PlyParams& params, double radius, double length, uint64_t seed) {
    params.validate();
    if (!(radius > 0.0 && std::isfinite(radius))) {
        throw InputError("ply: radius (R) must be finite and > 0, got " + formatDouble(radius));
    }
    if (!(length > 0.0 && std::isfinite(length))) {
        throw InputError("ply: length (L) must be finite and > 0, got " + formatDouble(length));
    }
    PlyGeometry ply;
    ply.params = params;
    ply.radius = radius;
    ply.length = length;
    ply.seed = seed;
    ply.fiberRadius = radius * std::sqrt(params.density / params.fibers);
    const std::vector<Point> centres = placeFiberCentres(params, radius, ply.fiberRadius, seed);
    ply.centres.assign(centres.begin(), centres.end());
    return ply;
}

}  // namespace weft
