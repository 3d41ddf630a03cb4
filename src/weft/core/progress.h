// weft/core/progress.h — a progress report on stderr for long loops.
//
// On a terminal: one line redrawn in place ('\r') at most 10 times a second,
//     render [##########..........]  42.0% 420000/1000000 12.3k/s ETA 47s [status]
// Otherwise (a log file, CI): a plain line about every 5 seconds,
//     render: 42% (420000/1000000) 12.3k/s ETA 47s
// and in both cases a final line from finish(). total == 0 means unknown:
// no percentage or ETA.
//
// add() is safe and cheap from many threads: one relaxed atomic add and a
// clock read; only the thread that wins a compare-exchange on the next print
// time formats and prints.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>

namespace weft {

// Where progress lines go instead of stderr, for a host that owns the
// standard error stream (the Python module sends them to sys.stderr, which
// Jupyter shows). While a sink is installed, new Progress objects print plain
// lines (no '\r' redraws) to it, one call per line, under their print lock.
using ProgressSink = std::function<void(const std::string& line)>;
class ScopedProgressSink {
  public:
    explicit ScopedProgressSink(ProgressSink sink);  // the previous one comes back after
    ~ScopedProgressSink();
    ScopedProgressSink(const ScopedProgressSink&) = delete;
    ScopedProgressSink& operator=(const ScopedProgressSink&) = delete;

  private:
    ProgressSink previous_;
};

class Progress {
public:
    // quiet: print nothing at all (counting still works).
    Progress(std::string label, uint64_t total, bool quiet = false);
    // Calls finish() if it was not called.
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    // Counts n more items done; thread-safe.
    void add(uint64_t n = 1);
    // Prints the final line (count, rate, elapsed time); later calls do nothing.
    void finish();
    // A short status shown after the ETA from the next print on (e.g. the
    // current training loss); thread-safe.
    void setStatus(std::string status);

    uint64_t done() const { return done_.load(std::memory_order_relaxed); }
    uint64_t total() const { return total_; }

private:
    using Clock = std::chrono::steady_clock;
    int64_t nowNs() const;
    void print(int64_t now, bool final);

    std::string label_;
    uint64_t total_;
    ProgressSink sink_;  // the installed sink at construction, or none
    bool quiet_, tty_;
    int64_t intervalNs_;
    Clock::time_point start_;
    std::atomic<uint64_t> done_{0};
    std::atomic<int64_t> nextPrintNs_;  // since start_; INT64_MAX once finished
    std::mutex printMutex_;             // serialises the rare prints
    bool finished_ = false;             // guarded by printMutex_
    size_t lastLineLength_ = 0;         // guarded by printMutex_ (tty redraw)
    std::string status_;                // guarded by printMutex_
    std::FILE* out_ = stderr;
};

}  // namespace weft
