// weft/yarn/sampling_table.h — a tabulated sampling density over outgoing
// directions that follows a given function of (wi, wo) (the yarn BSDF's
// smooth part, yarn_bsdf.h), for every incident direction.
//
// Built once from a non-negative function f(wi, wo) (the yarn's channel mean;
// yarn frame, wi in the upper hemisphere); sampled and evaluated exactly: pdf() is the
// density sample() draws from, a piecewise-constant function of wo that is
// positive everywhere and integrates to 1 over the sphere.
//
// Coordinates: the surface fiber frame (yarn_lobes.h), where the yarn's
// lobes sit on cones about the tilted fiber t~: z = sin(theta) = w.t~ and the
// azimuth phi from n. Cells are uniform in solid angle inside (dw = dz dphi).
//   Outgoing cells: kRows rows in z times kColumns equal azimuth columns. The
//     row edges follow the specular cone z = -z_i of the incident direction:
//     they are equal steps of A(z) = atan((z + z_i) / gamma) between
//     A(-1) and A(1) (a Cauchy quantile warp), fine near the cone and wide far
//     from it, with gamma = max(kWarpWidth cos(theta_i), kWarpWidthMin), since
//     a lobe of angular width beta has width beta cos(theta) in z. Because
//     the rows move with wi, a table built at one incident direction is a
//     good density at a nearby one: its lobes keep their cells.
//   Incident nodes: kIncidentTheta x kIncidentPhi, equal steps of the surface
//     fiber angles theta_i in [-pi/2, pi/2] and phi_i in [-pi/2, pi/2] (the
//     upper hemisphere). A node stores the probability of every cell of its
//     own row layout, computed by the midpoint rule per cell, with a
//     floor of kFloor times the uniform density (so the density is positive
//     wherever f is), each cell's mass as an 8-bit code of its log2 relative
//     to the node's largest cell (kCodeStep codes per factor 2; the decoded
//     masses are what pdf and sample use), and the cumulative row sums of the
//     decoded masses in float.
//   At an incident direction between nodes, the density is the bilinear
//     mixture of the four neighbouring nodes' cell probabilities laid out on
//     this wi's own rows: pdf(wo) = sum_n w_n P_n(row, column) / (dz dphi),
//     and sample() picks the node n with probability w_n. Both use the same
//     stored numbers, so pdf is exactly the sampled density.
// 19 x 19 nodes of 64 x 32 cells take 839 KB (tried and measured worse by
// `weft yarn check`: 48 x 24 and 64 x 24 cells; half the nodes through the
// half turn about n, which the fitted models do not obey closely enough).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "weft/core/vec.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

class SamplingTable {
  public:
    static constexpr int kIncidentTheta = 19;
    static constexpr int kIncidentPhi = 19;
    static constexpr int kNodes = kIncidentTheta * kIncidentPhi;
    static constexpr int kRows = 64;
    static constexpr int kColumns = 32;
    static constexpr int kCells = kRows * kColumns;
    static constexpr double kWarpWidth = 0.45;
    static constexpr double kWarpWidthMin = 0.15;
    static constexpr double kFloor = 0.03;
    static constexpr double kCodeStep = 12;  // codes per factor 2 of a cell's mass

    // The table laid out for one wi: its row edges and the four nodes it
    // blends, with their weights.
    struct Layout {
        double zc = 0, gamma = 1, atanLo = 0,
               atanStep = 1;  // rows: z = zc + gamma tan(atanLo + k atanStep)
        double tanStep = 0;   // tan(atanStep): the next row edge without another tan
        double invGamma = 1, invAtanStep = 1;
        int node[4] = {0, 0, 0, 0};
        double weight[4] = {1, 0, 0, 0};
        double density[4] = {0, 0, 0, 0};  // weight / the node's total mass
    };

    // f as a sum of `parts` terms: for one incident direction and many
    // outgoing ones (yarn frame), values[k * parts + q] = term q at wo[k]; all
    // finite and >= 0. The table follows their sum; nodeEnergy() integrates each.
    using Function = std::function<void(const Vec3& wi, const std::vector<Vec3>& wo,
                                        std::vector<double>& values)>;

    SamplingTable() = default;
    // Builds the nodes in parallel (TBB).
    SamplingTable(const SurfaceFiberFrame& frame, int parts, const Function& f);

    bool empty() const { return codes_.empty(); }

    // wi: yarn frame, upper hemisphere (wi.z >= 0).
    Layout layout(const Vec3& wi) const;
    // The same from wi's surface fiber angles, for a caller that has them:
    // sin(theta), theta and phi = atan2(y, max(z, 0)) of the local direction.
    Layout layout(double sinTheta, double theta, double phi) const;
    // Density per unit solid angle of sample() at the yarn-frame direction wo.
    double pdf(const Layout& in, const Vec3& wo) const;
    // uNode picks the node, u1 the cell and z in it, u2 the azimuth in it.
    Vec3 sample(const Layout& in, double uNode, double u1, double u2) const;
    // The integral of term `part` over the sphere at node n (kNodes of them).
    double nodeEnergy(int node, int part) const {
        return energy_[static_cast<size_t>(node) * parts_ + part];
    }
    // Any per-node quantity (kNodes values, theta-major) bilinear between the nodes.
    double blend(const Layout& in, const std::vector<double>& perNode) const;

    // The yarn-frame direction of node (a, b).
    static Vec3 nodeDirection(const SurfaceFiberFrame& frame, int a, int b);

    // Bytes of the tables.
    size_t bytes() const;

  private:
    static Layout rowsOf(double zi);
    // Row k and its edges z0 < z1; rowSpan from one tan, rowAt (the row
    // holding z) from none: the same edges up to rounding.
    struct RowSpan {
        int row;
        double z0, z1;
    };
    static RowSpan rowSpan(const Layout& in, int k);
    static RowSpan rowAt(const Layout& in, double z);
    static RowSpan spanOf(const Layout& in, int k, double tanLower);
    static int columnOf(double phi);

    SurfaceFiberFrame frame_;
    int parts_ = 1;
    // Per node: kCells codes of the cell masses (row-major); kRows + 1
    // cumulative row sums of the decoded masses (the last is their total);
    // the integral of each term.
    std::vector<uint8_t> codes_;
    std::vector<float> rowCdf_;
    std::vector<double> energy_;
};

}  // namespace weft
