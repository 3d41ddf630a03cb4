// libFuzzer harness: gather folders and the parts of a sharded gather
// (gather/gather_folder.h), as `weft gather merge`, `weft gather recolour`,
// `weft fit` and Python read them. The input is a set of files in sections,
//     === p0/meta.json\n<bytes>\n=== p0/count.npy\n<bytes>\n=== p1/meta.json\n...
// (each section's bytes run to the next "\n=== "), written into the folders
// p0, p1 and p2 of a temporary directory; a section "=== link p1/sum_m.npy
// p0/sum_m.npy" makes the first a symbolic link to the second. Then the
// folders are merged as parts (mergeGatherParts, then normaliseGather of the
// result) and each is read as a whole gather (loadRdm; for an any-colour one
// also loadColourPaths and a recolouring, normalised). Each step must return
// normally or throw weft::InputError; anything else is a finding.
//
// Seeds (fuzz/seeds/gather_part/): two parts of a tiny any-colour gather and
// the whole gather of the same walks, packed into sections:
//     weft gather --params fiber.json --fibers 5 --density 0.3 --twist 0.3 \
//         --segments-per-twist 16 --paths 64 --bins 1,2,2,2 --max-depth 4 \
//         --seed 1 --any-colour --quiet [--shard K/2] --out DIR
// with fiber.json {"c_r": 0.04, "c_tt": [0.5, 0.7, 0.9], "beta_r_deg": 7,
// "beta_tt_deg": 12, "gamma_tt_deg": 25}.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_util.h"
#include "weft/core/rgb.h"
#include "weft/gather/colour_paths.h"
#include "weft/gather/gather.h"
#include "weft/gather/gather_merge.h"
#include "weft/gather/rdm_io.h"

namespace {

namespace fs = std::filesystem;

constexpr std::string_view kFolders[] = {"p0", "p1", "p2"};
// The files of a gather or a part: nothing else is written.
constexpr std::string_view kFiles[] = {
    "meta.json",      "ply.txt",        "count.npy",     "count_t.npy",       "depth.npy",
    "sum_r.npy",      "sum_m.npy",      "sum_truncated.npy", "sum_exit_distance.npy",
    "paths_bins.npy", "paths_kind.npy", "paths_weight.npy",  "p_t.npy",
    "rdm_r.npy",      "rdm_m.npy",      "truncated.npy", "exit_distance.npy"};

template <size_t N>
bool oneOf(std::string_view s, const std::string_view (&list)[N]) {
    for (std::string_view x : list)
        if (s == x) return true;
    return false;
}

// "p1/sum_m.npy" -> true when it names a known file of a known folder.
bool validName(std::string_view name) {
    const size_t slash = name.find('/');
    return slash != std::string_view::npos && oneOf(name.substr(0, slash), kFolders) &&
           oneOf(name.substr(slash + 1), kFiles);
}

// A temporary directory of this process, removed at exit.
struct TempRoot {
    fs::path dir;
    TempRoot() {
        std::string tmpl = (fs::temp_directory_path() / "weft-gather-fuzz-XXXXXX").string();
        if (!::mkdtemp(tmpl.data())) std::abort();
        dir = tmpl;
    }
    ~TempRoot() {
        std::error_code ec;
        fs::remove_all(dir, ec);
    }
};

const fs::path& root() {
    static const TempRoot r;
    return r.dir;
}

// Writes the sections of `input` under root(); returns the folders written.
std::vector<std::string> writeSections(std::string_view input) {
    for (std::string_view f : kFolders) fs::remove_all(root() / f);
    std::vector<std::string> folders;
    constexpr std::string_view kMarker = "=== ", kSeparator = "\n=== ";
    if (input.substr(0, kMarker.size()) != kMarker) return folders;
    size_t pos = kMarker.size();
    while (pos <= input.size()) {
        const size_t eol = input.find('\n', pos);
        if (eol == std::string_view::npos) break;
        const std::string_view name = input.substr(pos, eol - pos);
        const size_t next = input.find(kSeparator, eol + 1);
        const std::string_view bytes = input.substr(
            eol + 1, next == std::string_view::npos ? std::string_view::npos : next - eol - 1);
        std::string_view target = name.substr(0, 5) == "link " ? name.substr(5) : name;
        std::string_view linkTo;
        if (target != name) {
            const size_t space = target.find(' ');
            linkTo = space == std::string_view::npos ? "" : target.substr(space + 1);
            target = target.substr(0, space);
        }
        if (validName(target) && (linkTo.empty() || validName(linkTo))) {
            const std::string folder(target.substr(0, target.find('/')));
            fs::create_directories(root() / folder);
            bool known = false;
            for (const std::string& f : folders) known = known || f == folder;
            if (!known) folders.push_back(folder);
            const fs::path file = root() / std::string(target);
            std::error_code ec;
            fs::remove(file, ec);
            if (linkTo.empty()) {
                std::ofstream(file, std::ios::binary)
                    .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
            } else {
                fs::create_symlink(root() / std::string(linkTo), file, ec);
            }
        }
        if (next == std::string_view::npos) break;
        pos = next + kSeparator.size();
    }
    return folders;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string input = weft::fuzz::bytesOf(data, size);
    const std::vector<std::string> folders = writeSections(input);
    if (folders.empty()) return 0;
    std::vector<std::string> dirs;
    for (const std::string& f : folders) dirs.push_back((root() / f).string());
    weft::fuzz::expectOnlyInputErrors([&] {
        weft::MergedGather m = weft::mergeGatherParts(dirs);
        weft::normaliseGather(std::move(m.sums), m.options, m.shards);
    });
    for (const std::string& dir : dirs) {
        weft::fuzz::expectOnlyInputErrors([&] { weft::loadRdm(dir); });
        weft::fuzz::expectOnlyInputErrors([&] {
            weft::GatherOptions o;
            weft::loadColourPaths(dir, &o);
            weft::RecolouredGather r = weft::recolourGather(dir, weft::Rgb(0.25, 0.5, 1.0));
            weft::normaliseGather(std::move(r.sums), r.options);
        });
    }
    return 0;
}
