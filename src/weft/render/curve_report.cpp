#include "weft/render/curve_report.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <tuple>
#include <utility>

#include "weft/core/error.h"
#include "weft/core/json_message.h"
#include "weft/core/limits.h"

namespace weft::render {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Pieces per leaf of the hierarchy.
constexpr size_t kLeafSize = 4;
// At most this many pieces per segment on average, and in all (unless there
// are more segments): piecesPerSegment.
constexpr double kMaxPiecesPerSegment = 32, kMaxPieces = 1 << 21;
// Bytes per piece while the hierarchy is built and searched: the piece, its
// sort key and order, and half a node.
constexpr double kBytesPerPiece = 112;

double clamp01(double v) { return std::clamp(v, 0.0, 1.0); }

}  // namespace

SegmentClosestPoints closestPointsOnSegments(const Vec3& p1, const Vec3& q1, const Vec3& p2,
                                             const Vec3& q2) {
    const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
    const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    double s = 0, t = 0;
    if (a == 0 && e == 0) {
        // Two points.
    } else if (a == 0) {
        t = clamp01(f / e);
    } else {
        const double c = dot(d1, r);
        if (e == 0) {
            s = clamp01(-c / a);
        } else {
            // The lines' closest points, then each parameter clamped and the
            // other one recomputed for it. Near-parallel segments (denominator
            // lost to rounding) take s = 0: any s is then as good.
            const double b = dot(d1, d2);
            const double denom = a * e - b * b;
            s = denom > 1e-14 * a * e ? clamp01((b * f - c * e) / denom) : 0.0;
            t = (b * s + f) / e;
            if (t < 0) {
                t = 0;
                s = clamp01(-c / a);
            } else if (t > 1) {
                t = 1;
                s = clamp01((b - c) / a);
            }
        }
    }
    SegmentClosestPoints cp;
    cp.s = s;
    cp.t = t;
    cp.p = p1 + d1 * s;
    cp.q = p2 + d2 * t;
    cp.distance = length(cp.p - cp.q);
    return cp;
}

namespace {

// One straight span of a curve's polyline, in the units analysed (scene
// units for a scene's yarns).
struct Segment {
    Vec3 a, b;
    double arcStart = 0;  // arc length along the curve from its first point to a
    double length = 0;
    uint32_t curve = 0;  // into CurveTable::curves (every entry's curves, in order)
    uint32_t index = 0;  // position in curve order: equal distances keep the first pair
};

struct CurveInfo {
    double length = 0;  // the whole polyline, closing segment included
    bool closed = false;
    uint32_t yarn = 0;   // the entry it belongs to
    uint32_t local = 0;  // its index in that entry's CurveSet
    double radius = 0;   // the entry's yarn radius (0: none given)
};

// Distance along a curve between arc positions a and b (the shorter way round
// on a closed curve).
double arcSeparation(const CurveInfo& curve, double a, double b) {
    const double s = std::fabs(a - b);
    return curve.closed ? std::min(s, curve.length - s) : s;
}

// An upper bound on arcSeparation between [aLo, aHi] and [bLo, bHi].
double maxArcSeparation(const CurveInfo& curve, double aLo, double aHi, double bLo, double bHi) {
    const double s = std::max(aHi - bLo, bHi - aLo);
    return curve.closed ? std::min(s, 0.5 * curve.length) : s;
}

double boxDistance(const Bounds3& a, const Bounds3& b) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
        const double gap = std::max({0.0, b.lo[k] - a.hi[k], a.lo[k] - b.hi[k]});
        d2 += gap * gap;
    }
    return std::sqrt(d2);
}

// The point at parameter u of a segment, computed as every search computes
// it (closestPointsOnSegments, the samples, the nearest partner), so that a
// box around the points at u0 and u1 holds every computed point in between
// (each coordinate of a + (b - a) u is monotonic in u, in floating point too).
Vec3 pointAt(const Segment& s, double u) { return s.a + (s.b - s.a) * u; }

// A box around every point the searches compute on s: its ends a and b and
// a + (b - a) 1, which may differ from b in the last bit.
Bounds3 segmentBox(const Segment& s) {
    Bounds3 box;
    box.extend(s.a);
    box.extend(s.b);
    box.extend(pointAt(s, 1.0));
    return box;
}

// A stretch [part / parts, (part + 1) / parts] of one segment's parameter:
// what the hierarchy holds. A segment much longer than the spacing of the
// curves around it is held as several pieces, so that its box does not
// overlap everything (random segments across a box made the search
// quadratic: issue 41); the searches still measure whole segments, a piece
// only says where to look.
struct Piece {
    uint32_t segment = 0;
    uint32_t part = 0, parts = 1;
};

double pieceStart(const Piece& p) { return static_cast<double>(p.part) / p.parts; }
double pieceEnd(const Piece& p) { return static_cast<double>(p.part + 1) / p.parts; }

// Around the piece's points as computed on the segment (pointAt), and the
// segment's own ends where the piece reaches them.
Bounds3 pieceBox(const Piece& p, const Segment& s) {
    if (p.parts == 1) return segmentBox(s);
    Bounds3 box;
    box.extend(p.part == 0 ? s.a : pointAt(s, pieceStart(p)));
    box.extend(pointAt(s, pieceEnd(p)));
    if (p.part + 1 == p.parts) box.extend(s.b);
    return box;
}

// The arc positions the piece spans, computed as the searches compute a
// point's (arcStart + u length).
double pieceArcLo(const Piece& p, const Segment& s) {
    return s.arcStart + pieceStart(p) * s.length;
}
double pieceArcHi(const Piece& p, const Segment& s) { return s.arcStart + pieceEnd(p) * s.length; }

// A bounding volume hierarchy over pieces of segments. Besides its box, each
// node records what the same-curve pruning needs: the one curve all its
// pieces belong to (-1 when several) and their arc range, plus the range of
// yarn entries, the largest radius among its segments and the smallest
// segment index (for the first of several pairs at the same distance).
struct Node {
    Bounds3 box;
    double arcLo = kInf, arcHi = -kInf;
    int64_t curve = -1;
    uint32_t yarnLo = 0, yarnHi = 0;
    double radiusMax = 0;
    uint32_t indexLo = 0;
    // Leaf: pieces [first, first + count). Inner (count 0): children at
    // this node + 1 and at `first`.
    uint32_t first = 0, count = 0;
};

// Each segment's piece count (above). L segments' worth of length spread
// evenly over the curves' box (of diagonal D; D^3 bounds its volume) would
// lie about sqrt(D^3 / L) apart: a segment longer than that is cut into
// pieces of about that length, at most kMaxPiecesPerSegment per segment on
// average and kMaxPieces in all (or one per segment). Yarn curves, whose
// segments are a fraction of a radius and whose yarns fill their box, are
// held whole (the same hierarchy, the same order of the overlap sums as
// before pieces); segments criss-crossing a box no longer all overlap.
std::vector<uint32_t> piecesPerSegment(const std::vector<Segment>& segments) {
    std::vector<uint32_t> parts(segments.size(), 1);
    if (segments.empty()) return parts;
    Bounds3 box;
    double total = 0;
    for (const Segment& s : segments) {
        box.extend(s.a);
        box.extend(s.b);
        total += s.length;
    }
    const double n = static_cast<double>(segments.size());
    const double allowed = std::max(n, std::min(kMaxPiecesPerSegment * n, kMaxPieces));
    const double diagonal = length(box.hi - box.lo);
    double piece = diagonal * std::sqrt(diagonal / total);
    // ceil(l / piece) <= l / piece + 1: at most total / piece + n pieces.
    if (allowed > n) piece = std::max(piece, total / (allowed - n));
    if (allowed == n || !(piece > 0) || !std::isfinite(piece)) return parts;
    for (size_t i = 0; i < segments.size(); ++i)
        if (segments[i].length > piece)
            parts[i] = static_cast<uint32_t>(std::min(std::ceil(segments[i].length / piece), allowed));
    return parts;
}

// Steps of the searches (node visits and segment tests), against their limit.
class StepBudget {
  public:
    // `name` begins the message: the file or scene checked.
    StepBudget(uint64_t limit, const std::string& name) : limit_(limit), name_(name) {}
    void spend(uint64_t n = 1) {
        steps_ += n;
        if (steps_ > limit_)
            throw CurveReportLimit(
                name_ + ": the curve overlap check stopped after " + std::to_string(limit_) +
                " steps (at most " + std::to_string(kMaxReportStepsPerItem) +
                " per segment and overlap sample, and at least " +
                std::to_string(kMinReportSteps) +
                ", docs/limits.md): its segments are long compared with the distances between "
                "them and crowd every part of the search, as no yarn curves do");
    }
    uint64_t steps() const { return steps_; }

  private:
    uint64_t limit_, steps_ = 0;
    const std::string& name_;
};

class SegmentTree {
  public:
    SegmentTree(const std::vector<Segment>& segments, const std::vector<CurveInfo>& curves)
        : segments_(segments), curves_(curves) {
        const std::vector<uint32_t> parts = piecesPerSegment(segments);
        size_t total = 0;
        for (uint32_t p : parts) total += p;
        checkMemoryBudget(static_cast<double>(segments.size()) * sizeof(Segment) +
                              static_cast<double>(total) * kBytesPerPiece,
                          "the curve overlap check (" + std::to_string(segments.size()) +
                              " segments in " + std::to_string(total) + " pieces)");
        if (total >= std::numeric_limits<uint32_t>::max())
            throw InputError("the curves have more than " +
                             std::to_string(std::numeric_limits<uint32_t>::max() - 1) +
                             " segment pieces, more than the curve report handles");
        pieces_.reserve(total);
        for (size_t i = 0; i < segments.size(); ++i)
            for (uint32_t k = 0; k < parts[i]; ++k)
                pieces_.push_back({static_cast<uint32_t>(i), k, parts[i]});
        // Twice each piece's midpoint, the key of the median split: a + b for
        // a whole segment (the order of the hierarchy over segments before).
        std::vector<Vec3> sums(pieces_.size());
        for (size_t i = 0; i < pieces_.size(); ++i) {
            const Piece& p = pieces_[i];
            const Segment& s = segments[p.segment];
            const Vec3 lo = p.part == 0 ? s.a : pointAt(s, pieceStart(p));
            const Vec3 hi = p.part + 1 == p.parts ? s.b : pointAt(s, pieceEnd(p));
            sums[i] = lo + hi;
        }
        std::vector<uint32_t> order(pieces_.size());
        for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<uint32_t>(i);
        if (!pieces_.empty()) {
            nodes_.reserve(2 * pieces_.size() / kLeafSize + 2);
            build(sums, order, 0, order.size());
        }
        std::vector<Piece> sorted;
        sorted.reserve(pieces_.size());
        for (uint32_t i : order) sorted.push_back(pieces_[i]);
        pieces_ = std::move(sorted);
        // Children come after their parent (pre-order): summarise backwards.
        for (size_t i = nodes_.size(); i-- > 0;) summarise(i);
    }

    bool empty() const { return nodes_.empty(); }
    const Node& node(uint32_t i) const { return nodes_[i]; }
    size_t pieceCount() const { return pieces_.size(); }
    const Piece& piece(uint32_t i) const { return pieces_[i]; }
    const Segment& segmentOf(uint32_t piece) const { return segments_[pieces_[piece].segment]; }
    const CurveInfo& curveOf(const Segment& s) const { return curves_[s.curve]; }
    const CurveInfo& curve(int64_t i) const { return curves_[static_cast<size_t>(i)]; }

  private:
    // Median split on the longest axis of the piece midpoints; pre-order.
    uint32_t build(const std::vector<Vec3>& sums, std::vector<uint32_t>& order, size_t begin,
                   size_t end) {
        const auto index = static_cast<uint32_t>(nodes_.size());
        nodes_.emplace_back();
        if (end - begin <= kLeafSize) {
            nodes_[index].first = static_cast<uint32_t>(begin);
            nodes_[index].count = static_cast<uint32_t>(end - begin);
            return index;
        }
        Bounds3 mids;
        for (size_t i = begin; i < end; ++i) mids.extend(0.5 * sums[order[i]]);
        const Vec3 extent = mids.hi - mids.lo;
        const int axis =
            extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
        const size_t middle = begin + (end - begin) / 2;
        const auto at = [&](size_t i) { return order.begin() + static_cast<std::ptrdiff_t>(i); };
        std::nth_element(at(begin), at(middle), at(end), [&](uint32_t x, uint32_t y) {
            const double mx = sums[x][axis];
            const double my = sums[y][axis];
            return mx < my || (mx == my && x < y);
        });
        build(sums, order, begin, middle);
        const uint32_t right = build(sums, order, middle, end);
        nodes_[index].first = right;
        return index;
    }

    // A leaf from its pieces, an inner node from its two children.
    void summarise(size_t i) {
        Node& node = nodes_[i];
        node.yarnLo = std::numeric_limits<uint32_t>::max();
        node.indexLo = std::numeric_limits<uint32_t>::max();
        const auto add = [&node](const Bounds3& box, int64_t curve, double arcLo, double arcHi,
                                 uint32_t yarnLo, uint32_t yarnHi, double radius, uint32_t indexLo,
                                 bool first) {
            node.box.extend(box.lo);
            node.box.extend(box.hi);
            node.curve = first || node.curve == curve ? curve : -1;
            node.arcLo = std::min(node.arcLo, arcLo);
            node.arcHi = std::max(node.arcHi, arcHi);
            node.yarnLo = std::min(node.yarnLo, yarnLo);
            node.yarnHi = std::max(node.yarnHi, yarnHi);
            node.radiusMax = std::max(node.radiusMax, radius);
            node.indexLo = std::min(node.indexLo, indexLo);
        };
        if (node.count == 0) {
            for (const size_t child : {i + 1, size_t{node.first}}) {
                const Node& c = nodes_[child];
                add(c.box, c.curve, c.arcLo, c.arcHi, c.yarnLo, c.yarnHi, c.radiusMax, c.indexLo,
                    child == i + 1);
            }
            return;
        }
        for (uint32_t k = node.first; k < node.first + node.count; ++k) {
            const Piece& p = pieces_[k];
            const Segment& s = segments_[p.segment];
            const CurveInfo& c = curves_[s.curve];
            add(pieceBox(p, s), s.curve, pieceArcLo(p, s), pieceArcHi(p, s), c.yarn, c.yarn,
                c.radius, s.index, k == node.first);
        }
    }

    const std::vector<Segment>& segments_;
    const std::vector<CurveInfo>& curves_;
    std::vector<Piece> pieces_;
    std::vector<Node> nodes_;
};

// The closest contact pair, by a traversal of the tree against itself: the
// smallest distance, and of the pairs at that distance the first in segment
// order (the pair a search over all pairs in order keeps). `yarn` >= 0 keeps
// only pairs with a segment of that entry.
class ContactSearch {
  public:
    ContactSearch(const SegmentTree& tree, int64_t yarn, StepBudget& budget)
        : tree_(tree), yarn_(yarn), budget_(budget) {
        if (!tree.empty()) visit(0, 0);
    }

    bool found() const { return best_ < kInf; }
    double distance() const { return best_; }
    const Segment& segmentA() const { return *a_; }
    const Segment& segmentB() const { return *b_; }
    const SegmentClosestPoints& points() const { return points_; }

  private:
    bool involvesYarn(const Node& n) const {
        return yarn_ < 0 || (n.yarnLo <= yarn_ && yarn_ <= n.yarnHi);
    }

    // Whether a pair of the two nodes could still replace the best pair: at
    // a smaller distance than `gap` allows, or at the same distance but
    // earlier. A pair (s, t), s < t, of a segment from each node has s >= the
    // smaller of the two nodes' first indices and t >= the larger one. (Many
    // pairs at one distance, e.g. coincident segments, made the search
    // quadratic when only a smaller distance pruned: issue 41.)
    bool mayImprove(double gap, const Node& a, const Node& b) const {
        if (gap < best_) return true;
        if (gap > best_) return false;
        const uint32_t lo = std::min(a.indexLo, b.indexLo), hi = std::max(a.indexLo, b.indexLo);
        return std::tie(lo, hi) < std::tie(a_->index, b_->index);
    }

    void visit(uint32_t ia, uint32_t ib) {
        budget_.spend();
        const Node& a = tree_.node(ia);
        const Node& b = tree_.node(ib);
        if (!involvesYarn(a) && !involvesYarn(b)) return;
        if (ia != ib) {
            const double gap = boxDistance(a.box, b.box);
            if (!mayImprove(gap, a, b)) return;
            // One stretch of one curve against another: every contact needs
            // sep > 2 d >= 2 gap.
            if (a.curve >= 0 && a.curve == b.curve &&
                maxArcSeparation(tree_.curve(a.curve), a.arcLo, a.arcHi, b.arcLo, b.arcHi) <=
                    2 * gap)
                return;
        }
        if (a.count != 0 && b.count != 0) {
            for (uint32_t i = a.first; i < a.first + a.count; ++i)
                for (uint32_t j = b.first; j < b.first + b.count; ++j)
                    if ((ia != ib || i < j) && tree_.piece(i).segment != tree_.piece(j).segment)
                        test(tree_.segmentOf(i), tree_.segmentOf(j));
            return;
        }
        if (ia == ib) {
            const uint32_t l = ia + 1, r = a.first;
            visit(l, l);
            visit(r, r);
            visit(l, r);
            return;
        }
        // Open the node with the larger box (a leaf never), nearer child first.
        const bool openA = b.count != 0 || (a.count == 0 && diagonal(a) >= diagonal(b));
        const Node& open = openA ? a : b;
        const Node& other = openA ? b : a;
        const uint32_t io = openA ? ib : ia;
        uint32_t first = (openA ? ia : ib) + 1, second = open.first;
        if (boxDistance(tree_.node(second).box, other.box) <
            boxDistance(tree_.node(first).box, other.box))
            std::swap(first, second);
        for (uint32_t child : {first, second}) openA ? visit(child, io) : visit(io, child);
    }

    static double diagonal(const Node& n) { return length(n.box.hi - n.box.lo); }

    void test(const Segment& x, const Segment& y) {
        budget_.spend();
        const Segment& s = x.index < y.index ? x : y;
        const Segment& t = x.index < y.index ? y : x;
        if (yarn_ >= 0 && tree_.curveOf(s).yarn != yarn_ && tree_.curveOf(t).yarn != yarn_) return;
        const SegmentClosestPoints cp = closestPointsOnSegments(s.a, s.b, t.a, t.b);
        if (cp.distance > best_) return;
        if (cp.distance == best_ && std::tie(s.index, t.index) >= std::tie(a_->index, b_->index))
            return;
        if (s.curve == t.curve && !(arcSeparation(tree_.curveOf(s), s.arcStart + cp.s * s.length,
                                                  t.arcStart + cp.t * t.length) > 2 * cp.distance))
            return;
        best_ = cp.distance;
        a_ = &s;
        b_ = &t;
        points_ = cp;
    }

    const SegmentTree& tree_;
    int64_t yarn_;
    StepBudget& budget_;
    double best_ = kInf;
    const Segment *a_ = nullptr, *b_ = nullptr;
    SegmentClosestPoints points_;
};

double pointBoxDistance(const Vec3& x, const Bounds3& box) {
    Bounds3 point;
    point.lo = point.hi = x;
    return boxDistance(point, box);
}

// Overlap sums of one yarn entry.
struct OverlapSums {
    double length = 0, overlapping = 0, maxDepth = 0;
};

// overlapping / length, 0 for no length, at most 1 (the weights are summed
// in another order than the lengths).
double overlapFraction(const OverlapSums& sums) {
    return sums.length > 0 ? std::min(1.0, sums.overlapping / sums.length) : 0.0;
}

// Samples every segment and finds, for each sample, its deepest partner.
class OverlapSampler {
  public:
    OverlapSampler(const SegmentTree& tree, StepBudget& budget) : tree_(tree), budget_(budget) {}

    void addSegment(const Segment& s, OverlapSums& sums, std::vector<char>& curveOverlaps) {
        const CurveInfo& curve = tree_.curveOf(s);
        const double r = curve.radius;
        sums.length += s.length;
        // The partner distance minus its radius below which a sample counts.
        const double bound = r * (1 - 2 * kOverlapTolerance);
        const double intervals =
            std::clamp(std::ceil(s.length / (0.25 * r)), 1.0, double{kMaxSamplesPerSegment});
        const int n = static_cast<int>(intervals);
        // A long segment first asks whether anything is near it at all; for
        // one or two samples that costs as much as the samples themselves.
        if (n > 2 && !anyPartnerNear(s, bound)) return;
        for (int k = 0; k <= n; ++k) {
            const double u = static_cast<double>(k) / n;
            const double weight = s.length / n * (k == 0 || k == n ? 0.5 : 1.0);
            const Vec3 x = pointAt(s, u);
            const double g = nearestPartner(x, s.curve, s.arcStart + u * s.length, bound);
            if (!(g < bound)) continue;
            sums.overlapping += weight;
            sums.maxDepth = std::max(sums.maxDepth, 0.5 - 0.5 * g / r);
            curveOverlaps[s.curve] = 1;
        }
    }

  private:
    // Whether a node may hold a partner of a point or segment of `curve` at
    // arc positions [arcLo, arcHi]: not when it is a stretch of the same
    // curve within 4 R of them along it.
    bool mayHoldPartner(const Node& n, uint32_t curve, double arcLo, double arcHi) const {
        if (n.curve != static_cast<int64_t>(curve)) return true;
        const CurveInfo& c = tree_.curve(n.curve);
        return maxArcSeparation(c, n.arcLo, n.arcHi, arcLo, arcHi) > 4 * c.radius;
    }

    // Whether any segment that may be a partner of a point of s comes within
    // bound + its radius of s's box (a quick test before sampling).
    bool anyPartnerNear(const Segment& s, double bound) {
        const Bounds3 box = segmentBox(s);
        const double arcHi = s.arcStart + s.length;
        stack_.assign(1, 0);
        while (!stack_.empty()) {
            budget_.spend();
            const uint32_t index = stack_.back();
            stack_.pop_back();
            const Node& n = tree_.node(index);
            if (boxDistance(n.box, box) - n.radiusMax >= bound) continue;
            if (!mayHoldPartner(n, s.curve, s.arcStart, arcHi)) continue;
            if (n.count == 0) {
                stack_.push_back(index + 1);
                stack_.push_back(n.first);
                continue;
            }
            for (uint32_t i = n.first; i < n.first + n.count; ++i) {
                const Piece& p = tree_.piece(i);
                const Segment& t = tree_.segmentOf(i);
                if (t.index == s.index) continue;
                const double radius = tree_.curveOf(t).radius;
                if (boxDistance(pieceBox(p, t), box) - radius >= bound) continue;
                if (t.curve == s.curve &&
                    !(maxArcSeparation(tree_.curveOf(t), pieceArcLo(p, t), pieceArcHi(p, t),
                                       s.arcStart, arcHi) > 4 * radius))
                    continue;
                return true;
            }
        }
        return false;
    }

    // min over partner segments of (distance from x - the partner's radius),
    // searched below `bound` (kInf when nothing is).
    double nearestPartner(const Vec3& x, uint32_t curve, double arc, double bound) {
        double best = bound;
        bool found = false;
        stack_.assign(1, 0);
        while (!stack_.empty()) {
            budget_.spend();
            const uint32_t index = stack_.back();
            stack_.pop_back();
            const Node& n = tree_.node(index);
            if (pointBoxDistance(x, n.box) - n.radiusMax >= best) continue;
            if (!mayHoldPartner(n, curve, arc, arc)) continue;
            if (n.count == 0) {
                // Nearer child last, so that it is taken first.
                uint32_t nearer = index + 1, farther = n.first;
                if (pointBoxDistance(x, tree_.node(farther).box) <
                    pointBoxDistance(x, tree_.node(nearer).box))
                    std::swap(nearer, farther);
                stack_.push_back(farther);
                stack_.push_back(nearer);
                continue;
            }
            for (uint32_t i = n.first; i < n.first + n.count; ++i) {
                const Segment& t = tree_.segmentOf(i);
                const CurveInfo& c = tree_.curveOf(t);
                const Vec3 d = t.b - t.a;
                const double len2 = dot(d, d);
                const double u = len2 > 0 ? clamp01(dot(x - t.a, d) / len2) : 0.0;
                if (t.curve == curve &&
                    !(arcSeparation(c, arc, t.arcStart + u * t.length) > 4 * c.radius))
                    continue;
                const double g = length(x - (t.a + d * u)) - c.radius;
                if (g < best) {
                    best = g;
                    found = true;
                }
            }
        }
        return found ? best : kInf;
    }

    const SegmentTree& tree_;
    StepBudget& budget_;
    std::vector<uint32_t> stack_;
};

// The segments and curves of every entry, scaled.
struct CurveTable {
    std::vector<Segment> segments;
    std::vector<CurveInfo> curves;
};

CurveTable curveTable(const std::vector<YarnCurves>& yarns) {
    double segments = 0;
    for (const YarnCurves& y : yarns)
        for (const Curve& c : y.curves->curves) segments += static_cast<double>(segmentCount(c));
    // Before the first allocation; the hierarchy checks again with its pieces.
    checkMemoryBudget(segments * (sizeof(Segment) + kBytesPerPiece),
                      "the curve overlap check (" + formatNumber(segments) + " segments)");
    CurveTable table;
    table.segments.reserve(static_cast<size_t>(segments));
    for (size_t y = 0; y < yarns.size(); ++y) {
        const std::vector<Curve>& curves = yarns[y].curves->curves;
        for (size_t c = 0; c < curves.size(); ++c) {
            const std::vector<Vec3>& p = curves[c].points;
            CurveInfo info;
            info.closed = curves[c].closed;
            info.yarn = static_cast<uint32_t>(y);
            info.local = static_cast<uint32_t>(c);
            info.radius = yarns[y].radius;
            const auto curveIndex = static_cast<uint32_t>(table.curves.size());
            const size_t spans = segmentCount(curves[c]);
            for (size_t k = 0; k < spans; ++k) {
                Segment s;
                s.a = p[k] * yarns[y].scale;
                s.b = p[(k + 1) % p.size()] * yarns[y].scale;
                s.length = length(s.b - s.a);
                s.arcStart = info.length;
                s.curve = curveIndex;
                // Indices are 32-bit: no input weft reads holds 4 billion segments.
                if (table.segments.size() >= std::numeric_limits<uint32_t>::max())
                    throw InputError("the curves have more than " +
                                     std::to_string(std::numeric_limits<uint32_t>::max() - 1) +
                                     " segments, more than the curve report handles");
                s.index = static_cast<uint32_t>(table.segments.size());
                info.length += s.length;
                table.segments.push_back(s);
            }
            table.curves.push_back(info);
        }
    }
    return table;
}

// Each segment once, in the order of the hierarchy (of its first piece): the
// order in which the overlap sums are added.
template <class F>
void forEachSegment(const SegmentTree& tree, const F& f) {
    for (uint32_t i = 0; i < tree.pieceCount(); ++i)
        if (tree.piece(i).part == 0) f(tree.segmentOf(i));
}

// The step limit of each search: kMaxReportStepsPerItem per segment and per
// overlap sample (OverlapSampler's sample count, when `sampled`), at least
// kMinReportSteps.
uint64_t stepLimit(const CurveTable& table, bool sampled) {
    double items = static_cast<double>(table.segments.size());
    if (sampled)
        for (const Segment& s : table.segments)
            items += std::clamp(std::ceil(s.length / (0.25 * table.curves[s.curve].radius)), 1.0,
                                double{kMaxSamplesPerSegment}) +
                     1;
    const double limit = std::max(static_cast<double>(kMinReportSteps),
                                  static_cast<double>(kMaxReportStepsPerItem) * items);
    return limit >= 1.8e19 ? std::numeric_limits<uint64_t>::max() : static_cast<uint64_t>(limit);
}

std::string formatPercent(double fraction) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f%%", 100 * fraction);
    return buf;
}

std::string formatShort(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

nlohmann::json finiteOrNull(double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

nlohmann::json vecJson(const Vec3& v) { return {v.x, v.y, v.z}; }

}  // namespace

void checkOverlapRadius(double radius, const std::string& label) {
    if (!(std::isfinite(radius) && radius > 0))
        throw InputError(label + " " + formatNumber(radius) +
                         " is out of range: allowed finite and > 0");
}

CurveReport curveReport(const CurveSet& set, std::optional<double> radius,
                        const std::string& name) {
    if (radius) checkOverlapRadius(*radius, "radius");
    const CurveTable table = curveTable({{&set, 1.0, radius.value_or(0.0)}});
    CurveReport report;
    report.curves = set.curves.size();
    report.points = set.pointCount();
    for (const Curve& c : set.curves) report.closedCurves += c.closed ? 1 : 0;
    if (!set.curves.empty()) report.basis = set.curves.front().basis;
    report.bounds = bounds(set);
    report.segments = table.segments.size();
    report.segmentLengthMin = table.segments.empty() ? 0 : kInf;
    for (const Segment& s : table.segments) {
        report.totalLength += s.length;
        report.degenerateSegments += s.length == 0 ? 1 : 0;
        report.segmentLengthMin = std::min(report.segmentLengthMin, s.length);
        report.segmentLengthMax = std::max(report.segmentLengthMax, s.length);
    }
    if (!table.segments.empty())
        report.segmentLengthMean = report.totalLength / static_cast<double>(table.segments.size());

    const SegmentTree tree(table.segments, table.curves);
    const uint64_t limit = stepLimit(table, radius.has_value());
    StepBudget contactSteps(limit, name);
    const ContactSearch search(tree, -1, contactSteps);
    report.steps = contactSteps.steps();
    if (search.found()) {
        CurveContact& c = report.closest.emplace();
        c.distance = search.distance();
        c.curveA = table.curves[search.segmentA().curve].local;
        c.curveB = table.curves[search.segmentB().curve].local;
        c.pointA = search.points().p;
        c.pointB = search.points().q;
    }
    if (radius) {
        OverlapSums sums;
        std::vector<char> curveOverlaps(table.curves.size(), 0);
        StepBudget overlapSteps(limit, name);
        OverlapSampler sampler(tree, overlapSteps);
        forEachSegment(tree, [&](const Segment& s) { sampler.addSegment(s, sums, curveOverlaps); });
        report.steps += overlapSteps.steps();
        CurveOverlap& o = report.overlap.emplace();
        o.radius = *radius;
        o.fraction = overlapFraction(sums);
        o.maxDepth = sums.maxDepth;
        o.curvesOverlapping =
            static_cast<size_t>(std::count(curveOverlaps.begin(), curveOverlaps.end(), char{1}));
    }
    return report;
}

std::vector<YarnOverlap> yarnOverlaps(const std::vector<YarnCurves>& yarns,
                                     const std::string& name) {
    for (const YarnCurves& y : yarns)
        if (!(std::isfinite(y.radius) && y.radius > 0))
            throw std::invalid_argument("yarnOverlaps: radius " + formatNumber(y.radius));
    const CurveTable table = curveTable(yarns);
    const SegmentTree tree(table.segments, table.curves);
    const uint64_t limit = stepLimit(table, true);
    std::vector<OverlapSums> sums(yarns.size());
    std::vector<char> curveOverlaps(table.curves.size(), 0);
    StepBudget overlapSteps(limit, name);
    OverlapSampler sampler(tree, overlapSteps);
    forEachSegment(tree, [&](const Segment& s) {
        sampler.addSegment(s, sums[table.curves[s.curve].yarn], curveOverlaps);
    });
    std::vector<YarnOverlap> result(yarns.size());
    for (size_t y = 0; y < yarns.size(); ++y) {
        YarnOverlap& o = result[y];
        o.radius = yarns[y].radius;
        o.fraction = overlapFraction(sums[y]);
        o.maxDepth = sums[y].maxDepth;
        // One entry: every contact involves it.
        StepBudget contactSteps(limit, name);
        const ContactSearch search(tree, yarns.size() == 1 ? -1 : static_cast<int64_t>(y),
                                   contactSteps);
        o.largestRadiusWithoutOverlap = 0.5 * search.distance();
    }
    return result;
}

nlohmann::json toJson(const CurveReport& r) {
    nlohmann::json j = {
        {"curves", r.curves},
        {"points", r.points},
        {"closed_curves", r.closedCurves},
        {"basis", r.basis == CurveBasis::CatmullRom ? "catmull_rom" : "polyline"},
        {"segments", r.segments},
        {"degenerate_segments", r.degenerateSegments},
        {"total_length", r.totalLength},
        {"bounds", {{"min", vecJson(r.bounds.lo)}, {"max", vecJson(r.bounds.hi)}}},
        {"segment_length",
         {{"min", r.segmentLengthMin}, {"mean", r.segmentLengthMean}, {"max", r.segmentLengthMax}}},
        {"min_distance", finiteOrNull(r.minDistance())},
        {"closest", nullptr},
        {"largest_radius_without_overlap", finiteOrNull(r.largestRadiusWithoutOverlap())},
        {"overlap", nullptr},
    };
    if (r.closest)
        j["closest"] = {{"curves", {r.closest->curveA, r.closest->curveB}},
                        {"points", {vecJson(r.closest->pointA), vecJson(r.closest->pointB)}}};
    if (r.overlap)
        j["overlap"] = {{"radius", r.overlap->radius},
                        {"fraction", r.overlap->fraction},
                        {"max_overlap", r.overlap->maxDepth},
                        {"curves_overlapping", r.overlap->curvesOverlapping}};
    return j;
}

namespace {

// The segment of `curve` (index k: points k, k + 1; the last one of a closed
// curve joins its last point to its first) nearest to p, and its length.
std::pair<size_t, double> nearestSegment(const Curve& curve, const Vec3& p) {
    const size_t n = curve.points.size(), segments = curve.closed ? n : n - 1;
    size_t best = 0;
    double bestDistance = std::numeric_limits<double>::infinity(), bestLength = 0;
    for (size_t k = 0; k < segments; ++k) {
        const Vec3 &a = curve.points[k], &b = curve.points[(k + 1) % n];
        const double d = closestPointsOnSegments(a, b, p, p).distance;
        if (d < bestDistance) bestDistance = d, best = k, bestLength = length(b - a);
    }
    return {best, bestLength};
}

// A point as "(x, y, z)" in short numbers.
std::string pointText(const Vec3& p) {
    // Appended, not "(" + ...: g++ 12 warns (-Wrestrict) on a literal plus a temporary.
    std::string text = "(";
    text += formatShort(p.x) + ", " + formatShort(p.y) + ", " + formatShort(p.z) + ")";
    return text;
}

}  // namespace

std::string zeroRadiusExplanation(const CurveSet& set, const CurveReport& report) {
    if (!report.closest) return "the curves have no contact pair";
    const CurveContact& c = *report.closest;
    std::string text = c.curveA == c.curveB
                           ? "curve " + std::to_string(c.curveA) + " comes back onto itself at " +
                                 pointText(c.pointA)
                           : "curves " + std::to_string(c.curveA) + " and " +
                                 std::to_string(c.curveB) + " touch or cross at " +
                                 pointText(c.pointA);
    text += " (largest radius without overlap " +
            formatShort(report.largestRadiusWithoutOverlap()) + ")";
    for (const auto& [index, point] :
         {std::pair{c.curveA, c.pointA}, std::pair{c.curveB, c.pointB}}) {
        const Curve& curve = set.curves.at(index);
        const size_t n = curve.points.size();
        if (!curve.closed || n < 3) continue;
        const auto [segment, span] = nearestSegment(curve, point);
        if (segment != n - 1) continue;
        double others = 0;
        for (size_t k = 0; k + 1 < n; ++k) others += length(curve.points[k + 1] - curve.points[k]);
        const double mean = others / static_cast<double>(n - 1);
        if (span <= kLongClosingSegment * mean) continue;
        text += "; there curve " + std::to_string(index) +
                " is closed (a negative point count in BCC, \"# closed\" in text) and its "
                "closing segment, from its last point back to its first, spans " +
                formatShort(span) + " where its other segments average " + formatShort(mean) +
                ": if the yarn is open, write it as open";
        break;
    }
    return text;
}

std::string yarnOverlapWarning(const std::string& scene, size_t yarn, const std::string& curves,
                               const YarnOverlap& o) {
    const std::string entry = (scene.empty() ? std::string("scene") : scene) + ": yarns[" +
                              std::to_string(yarn) + "] (" + curves + "): ";
    if (!o.overlaps()) {
        // Far thinner than the curves allow: most likely a unit mistake.
        if (!std::isfinite(o.largestRadiusWithoutOverlap) ||
            o.radius >= kThinYarnFraction * o.largestRadiusWithoutOverlap)
            return "";
        return entry + "the yarns cover little of the space between the curves: radius " +
               formatNumber(o.radius) + " is " +
               formatPercent(o.radius / o.largestRadiusWithoutOverlap) +
               " of the largest radius without overlap, " +
               formatShort(o.largestRadiusWithoutOverlap) +
               " (curve units or scale wrong? docs/curves.md, \"Choosing a radius and a scale\")";
    }
    char depth[32];
    std::snprintf(depth, sizeof depth, "%.0f%%", 100 * o.maxDepth);
    return entry + formatPercent(o.fraction) +
           " of the yarn length lies inside other yarns (up to " + depth +
           " of the diameter) at radius " + formatNumber(o.radius) +
           "; the largest radius without overlap is " +
           (std::isfinite(o.largestRadiusWithoutOverlap)
                ? formatShort(o.largestRadiusWithoutOverlap)
                : std::string("unbounded"));
}

nlohmann::json toJson(const YarnOverlap& o, size_t yarn, const std::string& curves) {
    return {{"yarn", yarn},
            {"curves", curves},
            {"radius", o.radius},
            {"overlap_fraction", o.fraction},
            {"max_overlap", o.maxDepth},
            {"largest_radius_without_overlap", finiteOrNull(o.largestRadiusWithoutOverlap)}};
}

}  // namespace weft::render
