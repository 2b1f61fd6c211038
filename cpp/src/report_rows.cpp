// The report writer's rows (report_rows.hpp): written through a cursor into room made once per
// block (`row_bound` chars a row), never checking capacity per character. Each column's
// ",\n<indent>key: " is made once, so a field costs one copy and its value.
#include "meshcol/report_rows.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>

#include "meshcol/batch.hpp"
#include "meshcol/format.hpp"

namespace meshcol {

namespace {

/// A newline and the deepest indent the writer uses (level 64 + 4 nested lines).
constexpr int kMaxIndent = 2 * 70;
const char* const kLine = [] {
    static char line[1 + kMaxIndent];
    line[0] = '\n';
    std::memset(line + 1, ' ', kMaxIndent);
    return line;
}();

inline void put(char*& p, const char* s, std::size_t n) {
    std::memcpy(p, s, n);
    p += n;
}

inline void newline_at(char*& p, int level) { put(p, kLine, 1 + 2 * static_cast<std::size_t>(level)); }

inline void real_at(char*& p, double x) {
    if (!std::isfinite(x)) return put(p, "null", 4);
    p += format_double_repr(x, p);
}

void vector_at(char*& p, const double* v, int level) {
    if (!(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])))
        return put(p, "null", 4);
    *p++ = '[';
    for (int k = 0; k < 3; ++k) {
        if (k) *p++ = ',';
        newline_at(p, level + 1);
        p += format_double_repr(v[k], p);
    }
    newline_at(p, level);
    *p++ = ']';
}

/// A list of `count` numbers at nesting `level`, each non-finite one null.
void numbers_at(char*& p, const double* v, int count, int level) {
    *p++ = '[';
    for (int k = 0; k < count; ++k) {
        if (k) *p++ = ',';
        newline_at(p, level + 1);
        real_at(p, v[k]);
    }
    newline_at(p, level);
    *p++ = ']';
}

/// A 4x4 matrix (16 numbers, row-major) as a list of its 4 rows at nesting `level`.
void matrix_at(char*& p, const double* v, int level) {
    *p++ = '[';
    for (int row = 0; row < 4; ++row) {
        if (row) *p++ = ',';
        newline_at(p, level + 1);
        numbers_at(p, v + 4 * row, 4, level + 1);
    }
    newline_at(p, level);
    *p++ = ']';
}

/// The most chars `cell` writes for a column at nesting `level`.
std::size_t cell_bound(const RowColumn& c, int level) {
    const std::size_t number = kDoubleReprSize;
    auto line = [](int l) { return 1 + 2 * static_cast<std::size_t>(l); };
    auto vector = [&](int l) { return 2 + 3 * (1 + line(l + 1) + number) + line(l); };
    auto numbers = [&](int count, int l) { return 2 + count * (1 + line(l + 1) + number) + line(l); };
    switch (c.kind) {
        case RowColumn::kNumber: return number;
        case RowColumn::kVector: return vector(level);
        case RowColumn::kBox: return 3 + 2 * (line(level + 1) + vector(level + 1)) + line(level);
        case RowColumn::kNumbers3: return numbers(3, level);
        case RowColumn::kMatrix4: return 2 + 4 * (1 + line(level + 1) + numbers(4, level + 1)) + line(level);
        case RowColumn::kString:
        case RowColumn::kRaw: {
            std::size_t most = 4;
            if (c.table)
                for (const auto& entry : *c.table) most = std::max(most, entry.size());
            return most;
        }
        default: return 24;  // an int64, "null", "false"
    }
}

void cell(char*& p, const RowColumn& c, std::size_t i, int level) {
    switch (c.kind) {
        case RowColumn::kNumber: return real_at(p, c.reals[i]);
        case RowColumn::kVector: return vector_at(p, c.reals + 3 * i, level);
        case RowColumn::kBox:
            *p++ = '[';
            newline_at(p, level + 1);
            vector_at(p, c.reals + 6 * i, level + 1);
            *p++ = ',';
            newline_at(p, level + 1);
            vector_at(p, c.reals + 6 * i + 3, level + 1);
            newline_at(p, level);
            *p++ = ']';
            return;
        case RowColumn::kNumbers3: return numbers_at(p, c.reals + 3 * i, 3, level);
        case RowColumn::kMatrix4: return matrix_at(p, c.reals + 16 * i, level);
        case RowColumn::kIndex:
            if (c.integers[i] < 0) return put(p, "null", 4);
            [[fallthrough]];
        case RowColumn::kInteger:
            p = std::to_chars(p, p + 24, c.integers[i]).ptr;
            return;
        case RowColumn::kBoolean: return c.flags[i] ? put(p, "true", 4) : put(p, "false", 5);
        case RowColumn::kString:
        case RowColumn::kRaw: {
            const std::int64_t code = c.integers[i];
            if (code < 0) return put(p, "null", 4);
            const std::string& entry = (*c.table)[static_cast<std::size_t>(code)];
            return put(p, entry.data(), entry.size());
        }
    }
}

/// About this many chars of rows a block of `write_to` takes (at the rows' bound).
constexpr std::size_t kBlockBytes = std::size_t{4} << 20;

/// `RowWriter::write_to`'s blocks: formatted by every thread into a ring of buffers made once
/// (two a thread: no page of it touched for the first time after the first round, and never
/// the whole text in memory); whichever thread finds the block due next ready writes it, and
/// the blocks after it, while the others format on.
class BlockPipe {
public:
    BlockPipe(const RowWriter& rows, std::size_t count, int threads, int fd)
        : rows_(rows), count_(count), fd_(fd) {
        per_block_ = std::max<std::size_t>(1, std::min<std::size_t>(8192, kBlockBytes / rows.row_bound()));
        blocks_ = (count + per_block_ - 1) / per_block_;
        threads_ = resolve_threads(threads, static_cast<long long>(blocks_), 2);
        slots_.resize(threads_ <= 1 ? 1 : 2 * static_cast<std::size_t>(threads_));
        for (auto& slot : slots_) slot.data.reset(new char[per_block_ * rows.row_bound() + 1]);
    }

    int run() {
        std::vector<std::thread> pool;
        try {
            for (int t = 1; t < threads_; ++t) pool.emplace_back([this] { work(); });
        } catch (...) {  // a thread that cannot start: the started ones and this one do it all
        }
        work();
        for (auto& t : pool) t.join();
        return error_;
    }

private:
    struct Slot {
        std::unique_ptr<char[]> data;
        std::size_t size = 0;
        std::size_t block = 0;
        bool ready = false;
    };

    const RowWriter& rows_;
    std::size_t count_;
    int fd_;
    std::size_t per_block_ = 1, blocks_ = 0;
    int threads_ = 1;
    std::vector<Slot> slots_;
    std::mutex lock_;
    std::condition_variable freed_;
    std::size_t next_block_ = 0, next_write_ = 0;
    bool writing_ = false;
    int error_ = 0;

    void work() {
        std::unique_lock<std::mutex> hold(lock_);
        const std::size_t ring = slots_.size();
        while (error_ == 0 && next_block_ < blocks_) {
            const std::size_t k = next_block_;
            if (k >= next_write_ + ring) {  // every slot holds a block not yet written
                freed_.wait(hold);
                continue;
            }
            ++next_block_;
            Slot& slot = slots_[k % ring];
            hold.unlock();
            char* start = slot.data.get();
            char* p = start;
            if (k == 0) *p++ = '[';
            const std::size_t from = k * per_block_;
            slot.size = static_cast<std::size_t>(rows_.write(from, std::min(count_, from + per_block_), p) - start);
            hold.lock();
            slot.block = k;
            slot.ready = true;
            if (writing_) continue;  // the thread writing takes this block when it is due
            writing_ = true;
            for (;;) {
                Slot& due = slots_[next_write_ % ring];
                if (error_ != 0 || next_write_ >= blocks_ || !due.ready || due.block != next_write_) break;
                hold.unlock();
                const int failed = write_all(fd_, due.data.get(), due.size);
                hold.lock();
                due.ready = false;
                if (failed != 0) error_ = failed;
                ++next_write_;
                freed_.notify_all();
            }
            writing_ = false;
        }
        freed_.notify_all();
    }
};

}  // namespace

RowWriter::RowWriter(std::vector<RowColumn> columns, int level)
    : columns_(std::move(columns)), level_(std::clamp(level, 0, 64)) {
    const std::string indent(2 * static_cast<std::size_t>(level_ + 2), ' ');
    row_bound_ = 2 * (1 + 2 * static_cast<std::size_t>(level_ + 1)) + 2;
    for (std::size_t k = 0; k < columns_.size(); ++k) {
        const RowColumn& c = columns_[k];
        prefixes_.push_back((k ? ",\n" : "\n") + indent + c.key + ": ");
        row_bound_ += prefixes_.back().size() + cell_bound(c, level_ + 2);
    }
}

char* RowWriter::write(std::size_t from, std::size_t to, char* p) const {
    const int inner = level_ + 2;
    for (std::size_t i = from; i < to; ++i) {
        if (i) *p++ = ',';
        newline_at(p, level_ + 1);
        *p++ = '{';
        for (std::size_t k = 0; k < columns_.size(); ++k) {
            put(p, prefixes_[k].data(), prefixes_[k].size());
            cell(p, columns_[k], i, inner);
        }
        newline_at(p, level_ + 1);
        *p++ = '}';
    }
    return p;
}

int RowWriter::write_to(int fd, std::size_t count, int threads) const {
    if (count == 0) return write_all(fd, "[]", 2);
    BlockPipe pipe(*this, count, threads, fd);
    if (const int failed = pipe.run()) return failed;
    const std::string tail = std::string(kLine, 1 + 2 * static_cast<std::size_t>(level_)) + "]";
    return write_all(fd, tail.data(), tail.size());
}

int write_all(int fd, const char* data, std::size_t size) {
    while (size > 0) {
        const ssize_t n = ::write(fd, data, std::min<std::size_t>(size, std::size_t{1} << 30));
        if (n < 0) {
            if (errno == EINTR) continue;
            return errno;
        }
        if (n == 0) return EIO;
        data += n;
        size -= static_cast<std::size_t>(n);
    }
    return 0;
}

}  // namespace meshcol
