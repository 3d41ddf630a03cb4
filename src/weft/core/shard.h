// weft/core/shard.h — one part of a job split for a cluster (docs/cluster.md).
//
// Shard K of N (written "K/N", K counted from 0 as Slurm's array indices
// usually are) covers the items [floor(K T / N), floor((K + 1) T / N)) of a
// job of T items: random walks of a gather, samples per pixel of a render.
// The N ranges are disjoint and cover [0, T) whatever N; their sizes differ
// by at most one. Each item draws from a random stream that depends only on
// (seed, global item index), so the merged shards are the unsharded job.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace weft {

struct Shard {
    static constexpr int64_t kMaxCount = 65536;

    int64_t index = 0, count = 1;

    // "K/N" with integers 0 <= K < N <= kMaxCount; InputError naming `what`
    // ("--shard") and the allowed form otherwise.
    static Shard parse(const std::string& text, const std::string& what);
    std::string toString() const;  // "K/N"

    // InputError naming `what` unless every shard of a job of `total` items
    // gets at least one (N <= total): an empty shard is a mistake in a job script.
    void validate(int64_t total, const std::string& what, const std::string& items) const;

    // The first item of this shard and one past its last.
    int64_t begin(int64_t total) const { return first(index, total); }
    int64_t end(int64_t total) const { return first(index + 1, total); }
    bool whole() const { return count == 1; }

  private:
    // floor(k total / count) without overflow (total < 2^47 here).
    int64_t first(int64_t k, int64_t total) const {
        return static_cast<int64_t>((static_cast<__int128>(k) * total) / count);
    }
};

// Checks that `shards` (of parts named `names`, same size) are shards 0..N-1
// of one N, each once; InputError naming the duplicate parts, or the missing
// shards, otherwise. Different N are the caller's check (it names the field).
void checkCompleteShardSet(const std::vector<Shard>& shards, const std::vector<std::string>& names);

}  // namespace weft
