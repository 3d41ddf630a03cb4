// Writes tests/data/yarn-bsdf-values.json (README.md): YarnBsdf values of the given models.
#include <cstdio>
#include <string>
#include <vector>
#include <nlohmann/json.hpp>
#include "weft/yarn/yarn_bsdf.h"
#include "weft/core/rng.h"
using namespace weft;
static Vec3 dir(Rng& r, bool anyHemisphere) {
    const double z = anyHemisphere ? 1 - 2 * r.uniform() : r.uniform();
    const double s = std::sqrt(std::max(0.0, 1 - z * z)), p = 2 * M_PI * r.uniform();
    return {s * std::cos(p), s * std::sin(p), z};
}
int main(int argc, char** argv) {
    nlohmann::json out = nlohmann::json::object();
    for (int a = 1; a < argc; ++a) {
        const std::string path = argv[a];
        const YarnBsdf bsdf = YarnBsdf::load(path);
        Rng rng(12345, 7);
        nlohmann::json rows = nlohmann::json::array();
        std::vector<Vec3> wis = {{0, 0, 1}, {0.6, 0, 0.8}, {0, 0.6, -0.8}, {0.999, 0.0, 0.0447101778}};
        for (int k = 0; k < 12; ++k) wis.push_back(dir(rng, k % 3 == 0));
        for (const Vec3& wi : wis) {
            for (int k = 0; k < 4; ++k) {
                const Vec3 wo = dir(rng, true);
                const Rgb f = bsdf.eval(wi, wo);
                rows.push_back({{"wi", {wi.x, wi.y, wi.z}}, {"wo", {wo.x, wo.y, wo.z}},
                                {"eval", {f[0], f[1], f[2]}}, {"pdf", bsdf.pdf(wi, wo)},
                                {"p_t", bsdf.transmission(wi)}});
            }
        }
        nlohmann::json samples = nlohmann::json::array();
        for (const Vec3& wi : wis) {
            for (int k = 0; k < 4; ++k) {
                const BsdfSampleInput u = {rng.uniform(), rng.uniform(), rng.uniform()};
                const BsdfSample s = bsdf.sample(wi, u);
                samples.push_back({{"wi", {wi.x, wi.y, wi.z}}, {"u", {u[0], u[1], u[2]}},
                                   {"wo", {s.wo.x, s.wo.y, s.wo.z}},
                                   {"weight", {s.weight[0], s.weight[1], s.weight[2]}},
                                   {"pdf", s.pdf}, {"lobe", s.lobe}});
            }
        }
        std::string name = path.substr(path.find_last_of('/') + 1);
        out[name] = {{"pairs", rows}, {"samples", samples}};
    }
    std::printf("%s\n", out.dump().c_str());
}
