// Sort and sweep (Baraff 1992; Cohen et al. 1995, I-COLLIDE; Ericson 2004, 7.5.2), with a
// coarse grid over the two cross axes: "multi box pruning" as in PhysX MBP (Terdiman).
//
// One sorted axis alone prunes badly in 3D: for n boxes spread in a cube, each box's slab
// along the sweep axis holds O(n^(2/3)) others. So the cross axes get a coarse grid whose
// cells are a few box extents wide; each cell is swept on its own, and a pair found in
// several cells is reported only in the cell holding the minimum corner of the pairs'
// intersection (a box spans a contiguous block of cells, and the cell of a max of
// coordinates is the max of their cells because cell_of is monotonic). The result is exact
// whatever the grid; the grid only decides the speed. In cell (cu, cv) that rule reads
// max(a.cu0, b.cu0) == cu and the same on v; as cu0 <= cu for both, it is "a or b starts in
// column cu" and "a or b starts in row cv": two bits per entry, or-ed.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "meshcol/batch.hpp"
#include "meshcol/broadphase.hpp"
#include "meshcol/defaults.hpp"
#include "radix_sort.hpp"

namespace meshcol {

void validate_boxes(const double* lo, const double* hi, std::int64_t n) {
    for (std::int64_t i = 0; i < n; ++i) {
        const double* a = lo + 3 * i;
        const double* b = hi + 3 * i;
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(a[k]) || !std::isfinite(b[k]))
                throw std::invalid_argument("aabb_min/aabb_max: box " + std::to_string(i) +
                                            " is not finite");
        for (int k = 0; k < 3; ++k)
            if (a[k] > b[k])
                throw std::invalid_argument("aabb_min/aabb_max: box " + std::to_string(i) +
                                            " has min > max");
    }
}

int choose_sweep_axis(const double* lo, const double* hi, std::int64_t n) {
    if (n < 2) return 0;
    // Two passes (mean, then squared deviations): no cancellation at 1e12 coordinates.
    // Centres as lo/2 + hi/2 so that finite boxes near the double range cannot overflow.
    double mean[3] = {0, 0, 0};
    for (std::int64_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) mean[k] += 0.5 * lo[3 * i + k] + 0.5 * hi[3 * i + k];
    for (double& m : mean) m /= static_cast<double>(n);
    double var[3] = {0, 0, 0};
    for (std::int64_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const double d = 0.5 * lo[3 * i + k] + 0.5 * hi[3 * i + k] - mean[k];
            var[k] += d * d;
        }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (var[k] > var[axis]) axis = k;
    return axis;
}

void sort_pair_keys(std::vector<std::uint64_t>& keys) {
    if (keys.size() < 1024) {
        std::sort(keys.begin(), keys.end());
        return;
    }
    lsd_radix_sort<16>(keys, [](std::uint64_t k) { return k; });
}

namespace {

/// One box entered in one grid cell. The sweep reads `lo_a` in order, then the rest.
struct Entry {
    double lo_a, hi_a;  ///< interval on the sweep axis
    double lo_u, hi_u;  ///< interval on the first cross axis
    double lo_v, hi_v;  ///< interval on the second cross axis
    std::uint32_t id;   ///< box index
    std::uint8_t home;  ///< bit 0: lo_u falls in this cell's column; bit 1: lo_v in its row
};

/// A hint to load the cache line holding `p` (no effect where the compiler has no builtin).
inline void prefetch(const void* p) {
#if defined(__GNUC__) || defined(__clang__)
    __builtin_prefetch(p);
#else
    (void)p;
#endif
}

inline int clamp_cell(double t, int cells) {
    // Monotonic in t: this is what makes the duplicate rule exact. NaN maps to 0. Written
    // without branches: cell boundaries fall at random for random boxes.
    t = t > 0.0 ? t : 0.0;
    t = t < static_cast<double>(cells - 1) ? t : static_cast<double>(cells - 1);
    return static_cast<int>(t);
}

/// The coarse grid over the cross axes u and v (1 x 1 means a plain sweep).
struct Grid {
    int axis = 0, u = 1, v = 2;
    double origin_u = 0.0, origin_v = 0.0, inv_u = 0.0, inv_v = 0.0;
    int cells_u = 1, cells_v = 1;

    int cell_u(double x) const { return clamp_cell((x - origin_u) * inv_u, cells_u); }
    int cell_v(double x) const { return clamp_cell((x - origin_v) * inv_v, cells_v); }
    int cells() const { return cells_u * cells_v; }
};

/// Writes the block of cells each box spans (u0, u1, v0, v1 per box) and returns the number
/// of (box, cell) entries.
std::int64_t compute_spans(const double* lo, const double* hi, std::int64_t n, const Grid& g,
                           std::vector<std::uint16_t>& span) {
    span.resize(4 * static_cast<size_t>(n));
    std::int64_t total = 0;
    for (std::int64_t i = 0; i < n; ++i) {
        std::uint16_t* s = span.data() + 4 * i;
        const int u0 = g.cell_u(lo[3 * i + g.u]), u1 = g.cell_u(hi[3 * i + g.u]);
        const int v0 = g.cell_v(lo[3 * i + g.v]), v1 = g.cell_v(hi[3 * i + g.v]);
        s[0] = static_cast<std::uint16_t>(u0), s[1] = static_cast<std::uint16_t>(u1);
        s[2] = static_cast<std::uint16_t>(v0), s[3] = static_cast<std::uint16_t>(v1);
        total += static_cast<std::int64_t>(u1 - u0 + 1) * (v1 - v0 + 1);
    }
    return total;
}

/// Median extent of a strided sample of at most 1024 boxes along `axis`.
double median_extent(const double* lo, const double* hi, std::int64_t n, int axis) {
    const std::int64_t step = std::max<std::int64_t>(1, n / 1024);
    std::vector<double> ext;
    ext.reserve(1025);
    for (std::int64_t i = 0; i < n; i += step) ext.push_back(hi[3 * i + axis] - lo[3 * i + axis]);
    const auto mid = ext.begin() + static_cast<std::ptrdiff_t>(ext.size() / 2);
    std::nth_element(ext.begin(), mid, ext.end());
    return *mid;
}

/// The grid for these boxes; when it has several cells, `span` holds every box's block of
/// cells in it (compute_spans).
Grid make_grid(const double* lo, const double* hi, std::int64_t n, int axis,
               std::vector<std::uint16_t>& span) {
    namespace d = defaults;
    Grid g;
    g.axis = axis;
    g.u = (axis + 1) % 3;
    g.v = (axis + 2) % 3;
    if (n < 256) return g;
    double min_lo[3], max_hi[3], range[3], median[3];
    for (int k = 0; k < 3; ++k) {
        min_lo[k] = lo[k];
        max_hi[k] = hi[k];
    }
    for (std::int64_t i = 1; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            min_lo[k] = std::min(min_lo[k], lo[3 * i + k]);
            max_hi[k] = std::max(max_hi[k], hi[3 * i + k]);
        }
    for (int k = 0; k < 3; ++k) {
        range[k] = max_hi[k] - min_lo[k];
        median[k] = median_extent(lo, hi, n, k);
    }
    // Candidates per box left by the sweep axis alone: few means the grid cannot pay.
    if (std::isfinite(range[axis]) && range[axis] > 0.0 &&
        static_cast<double>(n) * 2.0 * median[axis] / range[axis] < d::sort_and_sweep_min_candidates_for_grid)
        return g;
    auto cells_for = [&](int k) {
        if (!std::isfinite(range[k]) || !(range[k] > 0.0)) return 1;
        const double width = std::max(d::sort_and_sweep_cell_extent_ratio * median[k],
                                      range[k] / d::sort_and_sweep_max_cells_per_axis);
        const double c = std::floor(range[k] / width);
        return static_cast<int>(std::clamp(c, 1.0, static_cast<double>(d::sort_and_sweep_max_cells_per_axis)));
    };
    g.cells_u = cells_for(g.u);
    g.cells_v = cells_for(g.v);
    const std::int64_t max_cells = std::max<std::int64_t>(1, n / d::sort_and_sweep_min_boxes_per_cell);
    while (static_cast<std::int64_t>(g.cells_u) * g.cells_v > max_cells) {
        if (g.cells_u >= g.cells_v) g.cells_u = std::max(1, g.cells_u / 2);
        else g.cells_v = std::max(1, g.cells_v / 2);
    }
    auto set_scale = [&]() {
        g.origin_u = min_lo[g.u];
        g.origin_v = min_lo[g.v];
        g.inv_u = g.cells_u > 1 ? g.cells_u / range[g.u] : 0.0;
        g.inv_v = g.cells_v > 1 ? g.cells_v / range[g.v] : 0.0;
    };
    set_scale();
    // Boxes much larger than the median (a level's floor) enter many cells: coarsen until
    // the duplicates stay bounded.
    const double max_entries = d::sort_and_sweep_max_entries_per_box * static_cast<double>(n);
    while (g.cells() > 1 && static_cast<double>(compute_spans(lo, hi, n, g, span)) > max_entries) {
        g.cells_u = std::max(1, g.cells_u / 2);
        g.cells_v = std::max(1, g.cells_v / 2);
        set_scale();
    }
    return g;
}

/// A box entered in one cell before the cell is sorted: the sort key and what rebuilds the
/// entry. 16 bytes instead of an Entry's 56: the scatter into thousands of cells is the
/// costly step at a million boxes (each write lands on another page), so it moves little.
struct Slot {
    double lo_a;        ///< sort key
    std::uint32_t id;   ///< box index
    std::uint32_t home; ///< Entry::home
};

/// Enters every box in the cells it spans (`span`, unused for a single cell), in box order.
/// Slots of one cell are contiguous: [offsets[c], offsets[c + 1]).
void fill_cells(const double* lo, std::int64_t n, const Grid& g,
                const std::vector<std::uint16_t>& span, std::unique_ptr<Slot[]>& slots,
                std::vector<std::int64_t>& offsets) {
    const int cells = g.cells();
    offsets.assign(static_cast<size_t>(cells) + 1, 0);
    if (cells == 1) {
        offsets[1] = n;
        slots.reset(new Slot[static_cast<size_t>(n)]);  // no zeroing: all written below
        for (std::int64_t i = 0; i < n; ++i) slots[i] = {lo[3 * i + g.axis], static_cast<std::uint32_t>(i), 3u};
        return;
    }
    for (std::int64_t i = 0; i < n; ++i) {
        const std::uint16_t* s = span.data() + 4 * i;
        for (int cu = s[0]; cu <= s[1]; ++cu)
            for (int cv = s[2]; cv <= s[3]; ++cv) ++offsets[static_cast<size_t>(cu * g.cells_v + cv) + 1];
    }
    for (int c = 0; c < cells; ++c) offsets[c + 1] += offsets[c];
    slots.reset(new Slot[static_cast<size_t>(offsets[cells])]);
    std::vector<std::int64_t> next(offsets.begin(), offsets.end() - 1);
    for (std::int64_t i = 0; i < n; ++i) {
        const std::uint16_t* s = span.data() + 4 * i;
        const double key = lo[3 * i + g.axis];
        for (int cu = s[0]; cu <= s[1]; ++cu)
            for (int cv = s[2]; cv <= s[3]; ++cv)
                slots[next[cu * g.cells_v + cv]++] = {key, static_cast<std::uint32_t>(i),
                                                      static_cast<std::uint32_t>((cu == s[0]) | (cv == s[2]) << 1)};
    }
}

/// Pair keys found by one task: a growable array that is never zeroed (every key is written
/// before it is read).
struct KeyBuffer {
    std::unique_ptr<std::uint64_t[]> data;
    size_t capacity = 0;
    size_t size = 0;

    /// Room for `more` keys past `size`.
    void reserve_more(size_t more) {
        if (size + more <= capacity) return;
        const size_t grown = std::max(2 * capacity, size + more + 1024);
        std::unique_ptr<std::uint64_t[]> bigger(new std::uint64_t[grown]);
        std::copy(data.get(), data.get() + size, bigger.get());
        data.swap(bigger);
        capacity = grown;
    }
};

/// Sweeps one cell whose entries are sorted by lo_a, appending pair keys to `out`.
///
/// The candidates of a box (the entries that start inside its interval on the sweep axis) are
/// tested without a branch: about one in five passes, at random, so a branch on the tests
/// would mispredict often. Every candidate's key is written and the end advanced by the
/// test's result.
///
/// Stops once the buffer holds more than `limit` keys (the caller's cap on pairs: a pile of
/// boxes in one cell would otherwise fill memory with quadratically many), returning false.
///
/// Only the rows [first, last) are swept (the pairs whose first entry in sweep order is one of
/// them; -1: to the end): a cell's rows may be shared out between threads.
bool sweep_cell(const Entry* e, std::int64_t count, KeyBuffer& out, const std::int64_t* groups = nullptr,
                size_t limit = SIZE_MAX, std::int64_t first = 0, std::int64_t last = -1) {
    size_t k = out.size;  // a local: the key stores could alias the member
    const Entry* const end = e + count;
    const Entry* const rows_end = e + (last < 0 ? count : last);
    for (const Entry* a = e + first; a < rows_end; ++a) {
        if (k > limit) {
            out.size = k;
            return false;
        }
        const double hi_a = a->hi_a, lo_u = a->lo_u, hi_u = a->hi_u, lo_v = a->lo_v, hi_v = a->hi_v;
        const std::uint64_t id = a->id;
        const unsigned home = a->home;
        // Boxes of one group (the parts of one body) never pair.
        const std::int64_t group = groups ? groups[id] : 0;
        // Room for every later entry of the cell: one comparison per box, a reallocation
        // seldom. The loop then stores without a capacity check.
        out.size = k;
        out.reserve_more(static_cast<size_t>(end - a - 1));
        std::uint64_t* w = out.data.get();
        for (const Entry* b = a + 1; b < end && b->lo_a <= hi_a; ++b) {
            // Overlap on the cross axes, and this cell reports the pair (see the top).
            const std::uint64_t bid = b->id;
            const bool hit = (b->lo_u <= hi_u) & (lo_u <= b->hi_u) & (b->lo_v <= hi_v) &
                             (lo_v <= b->hi_v) & ((home | b->home) == 3u) &
                             (!groups || groups[bid] != group);
            w[k] = id < bid ? (id << 32 | bid) : (bid << 32 | id);
            k += hit;
        }
    }
    out.size = k;
    return k <= limit;
}

/// Writes the `count` entries of `src` to `dst` sorted by lo_a: sorts 16-byte (key, slot)
/// records, then moves each 56-byte entry once.
void sort_into(const Entry* src, std::int64_t count, Entry* dst,
               std::vector<std::pair<double, std::uint32_t>>& keys) {
    keys.resize(static_cast<size_t>(count));
    for (std::int64_t k = 0; k < count; ++k) keys[k] = {src[k].lo_a, static_cast<std::uint32_t>(k)};
    std::sort(keys.begin(), keys.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    for (std::int64_t k = 0; k < count; ++k) dst[k] = src[keys[k].second];
}

/// Splits cells 0..cells-1 into runs of consecutive cells holding similar numbers of entries
/// (`size(c)`), about 16 per thread, so parallel_for balances uneven cells.
template <class Size>
std::vector<int> make_tasks(int cells, std::int64_t total, int threads, Size size) {
    const std::int64_t target = std::max<std::int64_t>(1, total / (std::max(1, threads) * 16));
    std::vector<int> task_begin{0};
    std::int64_t run = 0;
    for (int c = 0; c < cells; ++c) {
        run += size(c);
        if (run >= target && c + 1 < cells) {
            task_begin.push_back(c + 1);
            run = 0;
        }
    }
    task_begin.push_back(cells);
    return task_begin;
}

/// The pair keys ((i << 32) | j, i < j, no duplicates) found by every task, as flat sorted
/// pairs [i0, j0, i1, j1, ...]. A counting sort on i (rows are short: a box overlaps a few
/// others) writes straight into the output, then each row is sorted on j: three passes
/// instead of the four 16-bit digits a radix sort of the keys needs past 2^16 boxes.
/// `row` is scratch of n + 1 counters.
std::vector<std::int64_t> sorted_pairs(const std::vector<KeyBuffer>& found,
                                       std::int64_t n, std::vector<std::uint32_t>& row) {
    size_t k = 0;
    for (const auto& f : found) k += f.size;
    std::vector<std::int64_t> pairs(2 * k);
    if (k == 0) return pairs;
    if (static_cast<std::int64_t>(k) * 8 < n) {  // few pairs among many boxes: sort the keys
        std::vector<std::uint64_t> keys;
        keys.reserve(k);
        for (const auto& f : found) keys.insert(keys.end(), f.data.get(), f.data.get() + f.size);
        sort_pair_keys(keys);
        for (size_t p = 0; p < k; ++p) {
            pairs[2 * p] = static_cast<std::int64_t>(keys[p] >> 32);
            pairs[2 * p + 1] = static_cast<std::int64_t>(keys[p] & 0xFFFFFFFFu);
        }
        return pairs;
    }
    row.assign(static_cast<size_t>(n) + 1, 0u);
    for (const auto& f : found)
        for (size_t q = 0; q < f.size; ++q) ++row[(f.data[q] >> 32) + 1];
    for (std::int64_t i = 0; i < n; ++i) row[i + 1] += row[i];
    for (const auto& f : found)
        for (size_t q = 0; q < f.size; ++q) {
            const std::uint64_t key = f.data[q];
            pairs[2 * static_cast<size_t>(row[key >> 32]++) + 1] = static_cast<std::int64_t>(key & 0xFFFFFFFFu);
        }
    // row[i] is now the end of row i, which is the start of row i + 1.
    std::vector<std::int64_t> js;
    size_t begin = 0;
    for (std::int64_t i = 0; i < n; ++i) {
        const size_t end = row[i];
        std::int64_t* p = pairs.data() + 2 * begin;
        const size_t len = end - begin;
        if (len > 32) {  // a large box (a level's floor) overlaps many: no quadratic sort
            js.resize(len);
            for (size_t q = 0; q < len; ++q) js[q] = p[2 * q + 1];
            std::sort(js.begin(), js.end());
            for (size_t q = 0; q < len; ++q) p[2 * q + 1] = js[q];
        } else {
            for (size_t q = 1; q < len; ++q) {
                const std::int64_t j = p[2 * q + 1];
                size_t r = q;
                for (; r > 0 && p[2 * r - 1] > j; --r) p[2 * r + 1] = p[2 * r - 1];
                p[2 * r + 1] = j;
            }
        }
        for (size_t q = 0; q < len; ++q) p[2 * q] = i;
        begin = end;
    }
    return pairs;
}

/// Builds the entry of a slot from the boxes.
inline Entry make_entry(const double* lo, const double* hi, const Grid& g, const Slot& s) {
    const double* a = lo + 3 * static_cast<size_t>(s.id);
    const double* b = hi + 3 * static_cast<size_t>(s.id);
    return {a[g.axis], b[g.axis], a[g.u], b[g.u], a[g.v], b[g.v], s.id, static_cast<std::uint8_t>(s.home)};
}

/// Sorts the `count` slots of one cell by lo_a and writes their entries, in that order, to
/// `out`.
void sort_cell(const double* lo, const double* hi, const Grid& g, Slot* first, std::int64_t count,
               Entry* out) {
    std::sort(first, first + count, [](const Slot& x, const Slot& y) { return x.lo_a < y.lo_a; });
    // The boxes of a cell are scattered over the input: fetch a few ahead.
    constexpr std::int64_t ahead = 8;
    for (std::int64_t q = 0; q < count; ++q) {
        if (q + ahead < count) {
            prefetch(lo + 3 * static_cast<size_t>(first[q + ahead].id));
            prefetch(hi + 3 * static_cast<size_t>(first[q + ahead].id));
        }
        out[q] = make_entry(lo, hi, g, first[q]);
    }
}

/// Sorts the slots of every cell, builds the cell's entries in a per-thread buffer (one cell
/// at a time: it stays in cache) and sweeps it, on `threads` threads; returns the sorted
/// pairs. With `keep`, each sorted cell is also copied to (*keep)[c]. With `max_pairs` >= 0,
/// the sweep stops once more than that many pairs are found (every thread's count is added
/// up after each cell, and one thread alone stops inside a cell), sets `*exceeded` and
/// returns no pairs: the memory held stays about `threads` x `max_pairs` keys.
std::vector<std::int64_t> sort_and_sweep_cells(const double* lo, const double* hi, const Grid& g, Slot* slots,
                                               const std::vector<std::int64_t>& offsets,
                                               std::int64_t n, int threads,
                                               std::vector<std::vector<Entry>>* keep,
                                               const std::int64_t* groups = nullptr,
                                               std::int64_t max_pairs = -1, bool* exceeded = nullptr) {
    const size_t limit = max_pairs < 0 ? SIZE_MAX : static_cast<size_t>(max_pairs);
    std::atomic<size_t> total{0};
    std::atomic<bool> over{false};
    const int cells = g.cells();
    const std::vector<int> task_begin = make_tasks(
        cells, offsets[cells], threads, [&](int c) { return offsets[c + 1] - offsets[c]; });
    const long long tasks = static_cast<long long>(task_begin.size()) - 1;
    std::vector<KeyBuffer> found(static_cast<size_t>(tasks));
    parallel_for(tasks, threads > 1 ? threads : 1, [&](long long t0, long long t1) {
        std::vector<Entry> sorted;
        for (long long t = t0; t < t1; ++t) {
            auto& out = found[static_cast<size_t>(t)];
            // About 1.2 pairs per entry for boxes that overlap 2 to 3 others: one allocation.
            out.reserve_more(static_cast<size_t>(offsets[task_begin[t + 1]] - offsets[task_begin[t]]) * 3 / 2);
            for (int c = task_begin[t]; c < task_begin[t + 1]; ++c) {
                if (over.load(std::memory_order_relaxed)) return;
                const std::int64_t count = offsets[c + 1] - offsets[c];
                if (static_cast<std::int64_t>(sorted.size()) < count) sorted.resize(static_cast<size_t>(count));
                sort_cell(lo, hi, g, slots + offsets[c], count, sorted.data());
                const size_t before = out.size;
                if (!sweep_cell(sorted.data(), count, out, groups, limit) ||
                    total.fetch_add(out.size - before) + (out.size - before) > limit) {
                    over.store(true);
                    return;
                }
                if (keep) {
                    std::vector<Entry>& cell = (*keep)[static_cast<size_t>(c)];
                    cell.reserve(static_cast<size_t>(count + count / 8 + 8));  // room for boxes moving in
                    cell.assign(sorted.data(), sorted.data() + count);
                }
            }
        }
    });
    if (over.load()) {
        if (exceeded) *exceeded = true;
        return {};
    }
    if (exceeded) *exceeded = false;
    std::vector<std::uint32_t> row;
    return sorted_pairs(found, n, row);
}

void check_axis(int axis) {
    if (axis < -1 || axis > 2)
        throw std::invalid_argument("axis must be None, 0, 1 or 2, got " + std::to_string(axis));
}

void check_count(std::int64_t n) {
    if (n > 0xFFFFFFFFll) throw std::invalid_argument("aabb_min: more than 2^32 boxes");
}

}  // namespace

std::vector<std::int64_t> sort_and_sweep(const double* lo, const double* hi, std::int64_t n,
                                         int axis, int threads, const std::int64_t* groups,
                                         std::int64_t max_pairs, bool* exceeded) {
    check_axis(axis);
    check_count(n);
    validate_boxes(lo, hi, n);
    if (axis < 0) axis = choose_sweep_axis(lo, hi, n);
    threads = resolve_threads(threads, n, defaults::broadphase_min_boxes_per_thread);
    std::vector<std::uint16_t> span;
    const Grid g = make_grid(lo, hi, n, axis, span);
    std::unique_ptr<Slot[]> slots;
    std::vector<std::int64_t> offsets;
    fill_cells(lo, n, g, span, slots, offsets);
    return sort_and_sweep_cells(lo, hi, g, slots.get(), offsets, n, threads, nullptr, groups, max_pairs,
                                exceeded);
}

std::int64_t sort_and_sweep_stream(const double* lo, const double* hi, std::int64_t n, int axis,
                                   int threads, std::int64_t block_pairs, const PairBlockConsumer& consume) {
    check_axis(axis);
    check_count(n);
    validate_boxes(lo, hi, n);
    if (axis < 0) axis = choose_sweep_axis(lo, hi, n);
    const int sort_threads = resolve_threads(threads, n, defaults::broadphase_min_boxes_per_thread);
    std::vector<std::uint16_t> span;
    const Grid g = make_grid(lo, hi, n, axis, span);
    std::unique_ptr<Slot[]> slots;
    std::vector<std::int64_t> offsets;
    fill_cells(lo, n, g, span, slots, offsets);
    // Every cell sorted and its entries built once, before any sweep: the rows of one cell
    // (the whole mesh, for a fan whose faces all meet at one point) go to several threads.
    const int cells = g.cells();
    std::unique_ptr<Entry[]> entries(new Entry[static_cast<size_t>(offsets[cells])]);
    parallel_for(cells, sort_threads, [&](long long c0, long long c1) {
        for (long long c = c0; c < c1; ++c)
            sort_cell(lo, hi, g, slots.get() + offsets[c], offsets[c + 1] - offsets[c], entries.get() + offsets[c]);
    });
    slots.reset();
    // Blocks: runs of rows of one cell with at most about block_pairs candidates (a row of a
    // cell of `count` entries has fewer than `count`), in cell order; fixed by the boxes alone.
    std::vector<std::int64_t> block_cell, block_row;
    const std::int64_t per_block = std::max<std::int64_t>(1, block_pairs);
    for (int c = 0; c < cells; ++c) {
        const std::int64_t count = offsets[c + 1] - offsets[c];
        const std::int64_t rows = std::clamp<std::int64_t>(per_block / std::max<std::int64_t>(1, count - 1), 1,
                                                           std::max<std::int64_t>(1, count));
        for (std::int64_t r = 0; r < count; r += rows) {
            block_cell.push_back(c);
            block_row.push_back(r);
        }
    }
    const auto blocks = static_cast<std::int64_t>(block_cell.size());
    const int workers = resolve_threads(threads, blocks, 1);
    std::atomic<std::int64_t> next{0};
    std::atomic<bool> stop{false};
    // One worker per index: each takes the next block until none is left, so the blocks
    // handed out are always a prefix of the order.
    parallel_for(workers, workers, [&](long long, long long) {
        KeyBuffer out;
        while (!stop.load(std::memory_order_relaxed)) {
            const std::int64_t b = next.fetch_add(1);
            if (b >= blocks) return;
            const std::int64_t c = block_cell[b];
            const std::int64_t count = offsets[c + 1] - offsets[c];
            const std::int64_t last = b + 1 < blocks && block_cell[b + 1] == c ? block_row[b + 1] : count;
            out.size = 0;
            sweep_cell(entries.get() + offsets[c], count, out, nullptr, SIZE_MAX, block_row[b], last);
            if (!consume(b, out.data.get(), static_cast<std::int64_t>(out.size))) stop.store(true);
        }
    });
    return blocks;
}

/// The incremental sweep's memory between steps: the grid of the first step (or of the last
/// rebuild), each cell's entries sorted by lo_a, and the block of cells each box spans.
struct SortAndSweep::State {
    Grid grid;
    std::vector<std::vector<Entry>> cells;
    std::vector<std::uint16_t> span;  ///< per box: u0, u1, v0, v1
    std::vector<std::uint8_t> moved;  ///< per box: left its block of cells this step
    std::vector<std::uint32_t> row;   ///< scratch of sorted_pairs
    std::vector<KeyBuffer> found;  ///< scratch: pair keys of each task

    /// Grid, cells and spans from scratch; returns the pairs.
    std::vector<std::int64_t> build(const double* lo, const double* hi, std::int64_t n, int axis,
                                    int threads) {
        grid = make_grid(lo, hi, n, axis, span);
        const Grid& g = grid;
        if (g.cells() == 1) span.clear();  // update() needs no spans for a single cell
        moved.assign(static_cast<size_t>(n), 0);
        std::unique_ptr<Slot[]> slots;
        std::vector<std::int64_t> offsets;
        fill_cells(lo, n, g, span, slots, offsets);
        cells.assign(static_cast<size_t>(g.cells()), {});
        return sort_and_sweep_cells(lo, hi, g, slots.get(), offsets, n, threads, &cells);
    }
};

namespace {

/// Insertion sort of a nearly sorted cell by lo_a; gives up past `budget` element moves
/// (then returns -1 and leaves the cell partly sorted).
std::int64_t insertion_sort(Entry* e, std::int64_t count, std::int64_t budget) {
    std::int64_t shifts = 0;
    for (std::int64_t k = 1; k < count; ++k) {
        if (!(e[k].lo_a < e[k - 1].lo_a)) continue;
        const Entry x = e[k];
        std::int64_t j = k;
        do {
            e[j] = e[j - 1];
            --j;
        } while (j > 0 && x.lo_a < e[j - 1].lo_a);
        e[j] = x;
        shifts += k - j;
        if (shifts > budget) return -1;
    }
    return shifts;
}

}  // namespace

SortAndSweep::SortAndSweep(const double* lo, const double* hi, std::int64_t n, int axis,
                             int threads) {
    check_axis(axis);
    check_count(n);
    validate_boxes(lo, hi, n);
    axis_ = axis < 0 ? choose_sweep_axis(lo, hi, n) : axis;
    threads_ = threads;
    n_ = n;
    state_ = std::make_unique<State>();
    last_shifts_ = -1;
    const int t = resolve_threads(threads_, n, defaults::broadphase_min_boxes_per_thread);
    pairs_ = std::make_shared<const std::vector<std::int64_t>>(state_->build(lo, hi, n, axis_, t));
}

SortAndSweep::~SortAndSweep() = default;
SortAndSweep::SortAndSweep(SortAndSweep&&) noexcept = default;
SortAndSweep& SortAndSweep::operator=(SortAndSweep&&) noexcept = default;

const std::vector<std::int64_t>& SortAndSweep::update(const double* lo, const double* hi,
                                                       std::int64_t n) {
    if (n != size())
        throw std::invalid_argument("aabb_min must hold the same " + std::to_string(size()) +
                                    " boxes as before, got " + std::to_string(n));
    validate_boxes(lo, hi, n);
    const int threads = resolve_threads(threads_, n, defaults::broadphase_min_boxes_per_thread);
    State& st = *state_;
    const Grid& g = st.grid;
    // Boxes that left their block of cells are removed from the old cells and entered in the
    // new ones. The grid keeps the bounds of the step that built it; boxes outside clamp to
    // the border cells, which stays exact (cell_of is monotonic) and only slows those cells.
    std::vector<std::uint32_t> changed;
    if (g.cells() > 1) {
        for (std::int64_t i = 0; i < n; ++i) {
            std::uint16_t* s = st.span.data() + 4 * i;
            const auto u0 = static_cast<std::uint16_t>(g.cell_u(lo[3 * i + g.u]));
            const auto u1 = static_cast<std::uint16_t>(g.cell_u(hi[3 * i + g.u]));
            const auto v0 = static_cast<std::uint16_t>(g.cell_v(lo[3 * i + g.v]));
            const auto v1 = static_cast<std::uint16_t>(g.cell_v(hi[3 * i + g.v]));
            const bool left = (u0 != s[0]) | (u1 != s[1]) | (v0 != s[2]) | (v1 != s[3]);
            st.moved[i] = left;
            if (!left) continue;
            changed.push_back(static_cast<std::uint32_t>(i));
            s[0] = u0, s[1] = u1, s[2] = v0, s[3] = v1;
        }
    }
    if (static_cast<double>(changed.size()) > defaults::sort_and_sweep_max_cell_changes * static_cast<double>(n)) {
        pairs_ = std::make_shared<const std::vector<std::int64_t>>(st.build(lo, hi, n, axis_, threads));
        last_shifts_ = -1;
        return *pairs_;
    }
    // New entries of the boxes that changed cells, grouped by cell, sorted by lo_a.
    const int cells = g.cells();
    std::vector<std::pair<int, Entry>> added;
    for (const std::uint32_t i : changed) {
        const double* a = lo + 3 * static_cast<size_t>(i);
        const double* b = hi + 3 * static_cast<size_t>(i);
        const std::uint16_t* s = st.span.data() + 4 * static_cast<size_t>(i);
        Entry e{a[g.axis], b[g.axis], a[g.u], b[g.u], a[g.v], b[g.v], i, 0};
        for (int cu = s[0]; cu <= s[1]; ++cu)
            for (int cv = s[2]; cv <= s[3]; ++cv) {
                e.home = static_cast<std::uint8_t>((cu == s[0]) | (cv == s[2]) << 1);
                added.push_back({cu * g.cells_v + cv, e});
            }
    }
    std::sort(added.begin(), added.end(), [](const auto& x, const auto& y) {
        return x.first != y.first ? x.first < y.first : x.second.lo_a < y.second.lo_a;
    });
    std::vector<size_t> added_begin(static_cast<size_t>(cells) + 1, 0);
    for (const auto& a : added) ++added_begin[static_cast<size_t>(a.first) + 1];
    for (int c = 0; c < cells; ++c) added_begin[c + 1] += added_begin[c];

    std::int64_t total = 0;
    for (const auto& cell : st.cells) total += static_cast<std::int64_t>(cell.size());
    const std::vector<int> task_begin = make_tasks(
        cells, total, threads, [&](int c) { return static_cast<std::int64_t>(st.cells[c].size()); });
    const long long tasks = static_cast<long long>(task_begin.size()) - 1;
    // Kept between steps: the key buffers are allocated (and their pages touched) once.
    std::vector<KeyBuffer>& found = st.found;
    found.resize(static_cast<size_t>(tasks));
    for (KeyBuffer& f : found) f.size = 0;
    std::vector<std::uint8_t> gave_up(static_cast<size_t>(tasks), 0);
    std::vector<std::int64_t> shifts(static_cast<size_t>(tasks), 0);
    parallel_for(tasks, threads > 1 ? threads : 1, [&](long long t0, long long t1) {
        std::vector<std::pair<double, std::uint32_t>> keys;
        std::vector<Entry> scratch;
        for (long long t = t0; t < t1; ++t)
            for (int c = task_begin[t]; c < task_begin[t + 1]; ++c) {
                std::vector<Entry>& cell = st.cells[c];
                // Refresh the coordinates in the kept order; drop the boxes that left.
                // The boxes of a cell are scattered over the input arrays: fetch a few
                // entries ahead, or every entry waits for two cache misses in turn.
                size_t w = 0;
                constexpr size_t ahead = 8;
                for (size_t r = 0; r < cell.size(); ++r) {
                    if (r + ahead < cell.size()) {
                        const size_t f = 3 * static_cast<size_t>(cell[r + ahead].id);
                        prefetch(lo + f);
                        prefetch(hi + f);
                        prefetch(st.moved.data() + cell[r + ahead].id);
                    }
                    const std::uint32_t i = cell[r].id;
                    if (st.moved[i]) continue;
                    const double* a = lo + 3 * static_cast<size_t>(i);
                    const double* b = hi + 3 * static_cast<size_t>(i);
                    const std::uint8_t home = cell[r].home;
                    cell[w++] = {a[g.axis], b[g.axis], a[g.u], b[g.u], a[g.v], b[g.v], i, home};
                }
                cell.resize(w);
                const auto count = static_cast<std::int64_t>(w);
                const std::int64_t moves =
                    insertion_sort(cell.data(), count, defaults::sort_and_sweep_max_shifts_per_box * count);
                if (moves < 0) {  // not nearly sorted after all
                    scratch.assign(cell.begin(), cell.end());
                    sort_into(scratch.data(), count, cell.data(), keys);
                    gave_up[t] = 1;
                } else {
                    shifts[t] += moves;
                }
                // Merge the sorted newcomers in, from the back.
                const size_t m = added_begin[c + 1] - added_begin[c];
                if (m > 0) {
                    const auto* in = added.data() + added_begin[c];
                    cell.resize(w + m);
                    auto x = static_cast<std::int64_t>(w) - 1;
                    auto y = static_cast<std::int64_t>(m) - 1;
                    for (auto out = static_cast<std::int64_t>(w + m) - 1; y >= 0; --out)
                        cell[out] = (x >= 0 && cell[x].lo_a > in[y].second.lo_a) ? cell[x--] : in[y--].second;
                }
                sweep_cell(cell.data(), static_cast<std::int64_t>(cell.size()), found[static_cast<size_t>(t)]);
            }
    });
    std::int64_t total_shifts = 0;
    for (const std::int64_t s : shifts) total_shifts += s;
    const bool any_gave_up = std::find(gave_up.begin(), gave_up.end(), 1) != gave_up.end();
    last_shifts_ = any_gave_up ? -1 : total_shifts;
    pairs_ = std::make_shared<const std::vector<std::int64_t>>(sorted_pairs(found, n, st.row));
    return *pairs_;
}

}  // namespace meshcol
