#include "weft/core/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace weft {

namespace {

constexpr int64_t kTtyIntervalNs = 100'000'000;      // 10 redraws per second
constexpr int64_t kPlainIntervalNs = 5'000'000'000;  // a log line every 5 s
constexpr int kBarWidth = 20;

// 850, 12.3k, 4.56M, 7.89G
std::string formatRate(double r) {
    char buf[32];
    if (r < 1e3)
        std::snprintf(buf, sizeof buf, "%.0f", r);
    else if (r < 1e6)
        std::snprintf(buf, sizeof buf, "%.1fk", r / 1e3);
    else if (r < 1e9)
        std::snprintf(buf, sizeof buf, "%.2fM", r / 1e6);
    else
        std::snprintf(buf, sizeof buf, "%.2fG", r / 1e9);
    return buf;
}

// 3.2s, 47s, 3m05s, 2h07m
std::string formatDuration(double seconds) {
    char buf[32];
    seconds = std::max(0.0, seconds);
    if (seconds < 9.95) {
        std::snprintf(buf, sizeof buf, "%.1fs", seconds);
        return buf;
    }
    const auto s = static_cast<long long>(std::llround(seconds));
    if (s < 60)
        std::snprintf(buf, sizeof buf, "%llds", s);
    else if (s < 3600)
        std::snprintf(buf, sizeof buf, "%lldm%02llds", s / 60, s % 60);
    else
        std::snprintf(buf, sizeof buf, "%lldh%02lldm", s / 3600, (s / 60) % 60);
    return buf;
}

std::mutex sinkMutex;
ProgressSink& installedSink() {
    static ProgressSink* const sink = new ProgressSink;  // never destroyed
    return *sink;
}

ProgressSink currentSink() {
    const std::lock_guard<std::mutex> lock(sinkMutex);
    return installedSink();
}

}  // namespace

ScopedProgressSink::ScopedProgressSink(ProgressSink sink) {
    const std::lock_guard<std::mutex> lock(sinkMutex);
    previous_ = std::exchange(installedSink(), std::move(sink));
}

ScopedProgressSink::~ScopedProgressSink() {
    const std::lock_guard<std::mutex> lock(sinkMutex);
    installedSink() = std::move(previous_);
}

Progress::Progress(std::string label, uint64_t total, bool quiet)
    : label_(std::move(label)),
      total_(total),
      sink_(currentSink()),
      quiet_(quiet),
      tty_(!sink_ && ::isatty(STDERR_FILENO) != 0),
      intervalNs_(tty_ ? kTtyIntervalNs : kPlainIntervalNs),
      start_(Clock::now()),
      nextPrintNs_(quiet ? std::numeric_limits<int64_t>::max() : intervalNs_) {}

Progress::~Progress() { finish(); }

int64_t Progress::nowNs() const {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - start_).count();
}

void Progress::add(uint64_t n) {
    done_.fetch_add(n, std::memory_order_relaxed);
    int64_t next = nextPrintNs_.load(std::memory_order_relaxed);
    if (next == std::numeric_limits<int64_t>::max()) return;  // quiet or finished
    const int64_t now = nowNs();
    if (now < next) return;
    // Only one thread per interval wins; the others go straight back to work.
    if (!nextPrintNs_.compare_exchange_strong(next, now + intervalNs_, std::memory_order_relaxed))
        return;
    print(now, false);
}

void Progress::finish() {
    nextPrintNs_.store(std::numeric_limits<int64_t>::max(), std::memory_order_relaxed);
    if (quiet_) return;
    print(nowNs(), true);
}

void Progress::setStatus(std::string status) {
    std::lock_guard<std::mutex> lock(printMutex_);
    status_ = std::move(status);
}

void Progress::print(int64_t now, bool final) {
    std::lock_guard<std::mutex> lock(printMutex_);
    if (finished_) return;
    if (final) finished_ = true;

    const uint64_t done = done_.load(std::memory_order_relaxed);
    const double seconds = static_cast<double>(now) * 1e-9;
    const double rate = seconds > 0 ? static_cast<double>(done) / seconds : 0.0;
    const bool known = total_ > 0;
    const double fraction =
        known ? std::min(1.0, static_cast<double>(done) / static_cast<double>(total_)) : 0.0;

    std::string tail = formatRate(rate) + "/s";
    if (final) {
        tail += " in " + formatDuration(seconds);
    } else if (known) {
        const double remaining = static_cast<double>(total_ - std::min(done, total_));
        tail += " ETA " + (rate > 0 ? formatDuration(remaining / rate) : std::string("?"));
    }
    if (!status_.empty()) tail += " " + status_;

    char buf[96];
    std::string line;
    if (tty_) {
        line = "\r";
        line += label_;
        line += ' ';
        if (known) {
            const int filled = static_cast<int>(fraction * kBarWidth);
            line += '[';
            line.append(filled, '#');
            line.append(kBarWidth - filled, '.');
            line += "] ";
            std::snprintf(buf, sizeof buf, "%5.1f%% %llu/%llu ", 100.0 * fraction,
                          static_cast<unsigned long long>(done),
                          static_cast<unsigned long long>(total_));
        } else {
            std::snprintf(buf, sizeof buf, "%llu ", static_cast<unsigned long long>(done));
        }
        line += buf;
        line += tail;
        // Blank out what is left of a longer previous line.
        const size_t length = line.size();
        if (length < lastLineLength_) line.append(lastLineLength_ - length, ' ');
        lastLineLength_ = length;
        if (final) line += '\n';
    } else {
        line = label_;
        line += ": ";
        if (known) {
            std::snprintf(buf, sizeof buf, "%d%% (%llu/%llu) ",
                          static_cast<int>(std::floor(100.0 * fraction)),
                          static_cast<unsigned long long>(done),
                          static_cast<unsigned long long>(total_));
        } else {
            std::snprintf(buf, sizeof buf, "%llu ", static_cast<unsigned long long>(done));
        }
        line += buf;
        line += tail;
        line += '\n';
    }
    // One write per line so that other stderr output does not split it.
    if (sink_) {
        sink_(line);
        return;
    }
    std::fwrite(line.data(), 1, line.size(), out_);
    std::fflush(out_);
}

}  // namespace weft
