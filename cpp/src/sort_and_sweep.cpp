// Sort and sweep (Baraff 1992; Cohen et al. 1995, I-COLLIDE; Ericson 2004, 7.5.2), with a
// coarse grid over the two cross axes: "multi box pruning" as in PhysX MBP (Terdiman).
//
// One sorted axis alone prunes badly in 3D: for n boxes spread in a cube, each box's slab
// along the sweep axis holds O(n^(2/3)) others. So the cross axes get a coarse grid whose
// cells are a few box extents wide; each cell is swept on its own, and a pair found in
// several cells is reported only in the cell holding the minimum corner of the pairs'
// intersection (a box spans a contiguous block of cells, and the cell of a max of
// coordinates is the max of their cells because cell_of is monotonic). The result is exact
// whatever the grid; the grid only decides the speed.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "meshcol/batch.hpp"
#include "meshcol/broadphase.hpp"
#include "meshcol/defaults.hpp"

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
    const size_t n = keys.size();
    if (n < 1024) {
        std::sort(keys.begin(), keys.end());
        return;
    }
    // LSD radix sort on 16-bit digits; digits equal in every key are skipped (pair keys of
    // n < 2^20 boxes vary in only part of their bits).
    std::uint64_t varying = 0;
    for (const std::uint64_t k : keys) varying |= k ^ keys[0];
    std::vector<std::uint64_t> tmp(n);
    std::vector<std::uint32_t> count(65536);
    for (int shift = 0; shift < 64; shift += 16) {
        if (((varying >> shift) & 0xFFFFu) == 0) continue;
        std::fill(count.begin(), count.end(), 0u);
        for (const std::uint64_t k : keys) ++count[(k >> shift) & 0xFFFFu];
        std::uint32_t sum = 0;
        for (std::uint32_t& c : count) {
            const std::uint32_t c0 = c;
            c = sum;
            sum += c0;
        }
        for (const std::uint64_t k : keys) tmp[count[(k >> shift) & 0xFFFFu]++] = k;
        keys.swap(tmp);
    }
}

namespace {

/// One box entered in one grid cell. The sweep reads `lo_a` in order, then the rest.
struct Entry {
    double lo_a, hi_a;  ///< interval on the sweep axis
    double lo_u, hi_u;  ///< interval on the first cross axis
    double lo_v, hi_v;  ///< interval on the second cross axis
    std::uint32_t id;   ///< box index
    std::uint16_t cu0;  ///< grid cell of lo_u
    std::uint16_t cv0;  ///< grid cell of lo_v
};

inline int clamp_cell(double t, int cells) {
    // Monotonic in t: this is what makes the duplicate rule exact. NaN maps to 0.
    if (!(t > 0.0)) return 0;
    if (t >= static_cast<double>(cells)) return cells - 1;
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

std::int64_t count_entries(const double* lo, const double* hi, std::int64_t n, const Grid& g) {
    std::int64_t total = 0;
    for (std::int64_t i = 0; i < n; ++i) {
        const std::int64_t su = g.cell_u(hi[3 * i + g.u]) - g.cell_u(lo[3 * i + g.u]) + 1;
        const std::int64_t sv = g.cell_v(hi[3 * i + g.v]) - g.cell_v(lo[3 * i + g.v]) + 1;
        total += su * sv;
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

Grid make_grid(const double* lo, const double* hi, std::int64_t n, int axis) {
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
        static_cast<double>(n) * 2.0 * median[axis] / range[axis] < d::sweep_min_candidates_for_grid)
        return g;
    auto cells_for = [&](int k) {
        if (!std::isfinite(range[k]) || !(range[k] > 0.0)) return 1;
        const double width = std::max(d::sweep_cell_extent_ratio * median[k],
                                      range[k] / d::sweep_max_cells_per_axis);
        const double c = std::floor(range[k] / width);
        return static_cast<int>(std::clamp(c, 1.0, static_cast<double>(d::sweep_max_cells_per_axis)));
    };
    g.cells_u = cells_for(g.u);
    g.cells_v = cells_for(g.v);
    const std::int64_t max_cells = std::max<std::int64_t>(1, n / d::sweep_min_boxes_per_cell);
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
    const double max_entries = d::sweep_max_entries_per_box * static_cast<double>(n);
    while (g.cells() > 1 && static_cast<double>(count_entries(lo, hi, n, g)) > max_entries) {
        g.cells_u = std::max(1, g.cells_u / 2);
        g.cells_v = std::max(1, g.cells_v / 2);
        set_scale();
    }
    return g;
}

/// Enters every box in the cells it spans, visiting boxes in `order` (all of 0..n-1 when
/// null). Entries of one cell are contiguous: [offsets[c], offsets[c + 1]).
void fill_cells(const double* lo, const double* hi, std::int64_t n, const Grid& g,
                const std::uint32_t* order, std::vector<Entry>& entries,
                std::vector<std::int64_t>& offsets) {
    const int cells = g.cells();
    offsets.assign(static_cast<size_t>(cells) + 1, 0);
    if (cells == 1) {
        offsets[1] = n;
    } else {
        for (std::int64_t i = 0; i < n; ++i) {
            const int u0 = g.cell_u(lo[3 * i + g.u]), u1 = g.cell_u(hi[3 * i + g.u]);
            const int v0 = g.cell_v(lo[3 * i + g.v]), v1 = g.cell_v(hi[3 * i + g.v]);
            for (int cu = u0; cu <= u1; ++cu)
                for (int cv = v0; cv <= v1; ++cv) ++offsets[static_cast<size_t>(cu * g.cells_v + cv) + 1];
        }
        for (int c = 0; c < cells; ++c) offsets[c + 1] += offsets[c];
    }
    entries.resize(static_cast<size_t>(offsets[cells]));
    std::vector<std::int64_t> next(offsets.begin(), offsets.end() - 1);
    for (std::int64_t k = 0; k < n; ++k) {
        const std::int64_t i = order ? order[k] : k;
        const double* a = lo + 3 * i;
        const double* b = hi + 3 * i;
        const int u0 = g.cell_u(a[g.u]), u1 = g.cell_u(b[g.u]);
        const int v0 = g.cell_v(a[g.v]), v1 = g.cell_v(b[g.v]);
        const Entry e{a[g.axis], b[g.axis], a[g.u], b[g.u], a[g.v], b[g.v],
                      static_cast<std::uint32_t>(i), static_cast<std::uint16_t>(u0),
                      static_cast<std::uint16_t>(v0)};
        for (int cu = u0; cu <= u1; ++cu)
            for (int cv = v0; cv <= v1; ++cv) entries[static_cast<size_t>(next[cu * g.cells_v + cv]++)] = e;
    }
}

/// Sweeps one cell whose entries are sorted by lo_a, appending pair keys.
void sweep_cell(const Entry* e, std::int64_t count, int cu, int cv, bool single_cell,
                std::vector<std::uint64_t>& out) {
    for (std::int64_t i = 0; i < count; ++i) {
        const Entry& a = e[i];
        for (std::int64_t j = i + 1; j < count && e[j].lo_a <= a.hi_a; ++j) {
            const Entry& b = e[j];
            // Non-short-circuit tests: about half the candidates fail, at random, so a branch
            // per test would mispredict often.
            const bool hit = (b.lo_u <= a.hi_u) & (a.lo_u <= b.hi_u) & (b.lo_v <= a.hi_v) &
                             (a.lo_v <= b.hi_v);
            if (!hit) continue;
            if (!single_cell && (std::max(a.cu0, b.cu0) != cu || std::max(a.cv0, b.cv0) != cv))
                continue;  // reported by the cell holding the intersection's minimum corner
            const std::uint64_t i0 = std::min(a.id, b.id), j0 = std::max(a.id, b.id);
            out.push_back(i0 << 32 | j0);
        }
    }
}

/// Sorts the entries of one cell by lo_a: sorts 16-byte (key, slot) records, then moves the
/// 56-byte entries once.
void sort_cell(Entry* e, std::int64_t count, std::vector<std::pair<double, std::uint32_t>>& keys,
               std::vector<Entry>& scratch) {
    if (count < 2) return;
    keys.resize(static_cast<size_t>(count));
    for (std::int64_t k = 0; k < count; ++k) keys[k] = {e[k].lo_a, static_cast<std::uint32_t>(k)};
    std::sort(keys.begin(), keys.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    scratch.assign(e, e + count);
    for (std::int64_t k = 0; k < count; ++k) e[k] = scratch[keys[k].second];
}

/// Sorts (when asked) and sweeps every cell on `threads` threads; returns sorted pair keys.
std::vector<std::uint64_t> sweep_all(const Grid& g, std::vector<Entry>& entries,
                                     const std::vector<std::int64_t>& offsets, bool sort_cells,
                                     int threads) {
    const int cells = g.cells();
    // Tasks of consecutive cells holding similar numbers of entries.
    const std::int64_t total = offsets[cells];
    const std::int64_t target = std::max<std::int64_t>(1, total / (std::max(1, threads) * 16));
    std::vector<int> task_begin{0};
    for (int c = 0; c < cells; ++c)
        if (offsets[c + 1] - offsets[task_begin.back()] >= target && c + 1 < cells)
            task_begin.push_back(c + 1);
    task_begin.push_back(cells);
    const long long tasks = static_cast<long long>(task_begin.size()) - 1;
    std::vector<std::vector<std::uint64_t>> found(static_cast<size_t>(tasks));
    parallel_for(tasks, threads > 1 ? threads : 1, [&](long long t0, long long t1) {
        std::vector<std::pair<double, std::uint32_t>> keys;
        std::vector<Entry> scratch;
        for (long long t = t0; t < t1; ++t)
            for (int c = task_begin[t]; c < task_begin[t + 1]; ++c) {
                Entry* first = entries.data() + offsets[c];
                const std::int64_t count = offsets[c + 1] - offsets[c];
                if (sort_cells) sort_cell(first, count, keys, scratch);
                sweep_cell(first, count, c / g.cells_v, c % g.cells_v, cells == 1,
                           found[static_cast<size_t>(t)]);
            }
    });
    size_t k = 0;
    for (const auto& f : found) k += f.size();
    std::vector<std::uint64_t> keys;
    keys.reserve(k);
    for (const auto& f : found) keys.insert(keys.end(), f.begin(), f.end());
    sort_pair_keys(keys);
    return keys;
}

std::vector<std::int64_t> unpack(const std::vector<std::uint64_t>& keys) {
    std::vector<std::int64_t> pairs(2 * keys.size());
    for (size_t k = 0; k < keys.size(); ++k) {
        pairs[2 * k] = static_cast<std::int64_t>(keys[k] >> 32);
        pairs[2 * k + 1] = static_cast<std::int64_t>(keys[k] & 0xFFFFFFFFu);
    }
    return pairs;
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
                                         int axis, int threads) {
    check_axis(axis);
    check_count(n);
    validate_boxes(lo, hi, n);
    if (axis < 0) axis = choose_sweep_axis(lo, hi, n);
    threads = resolve_threads(threads, n, defaults::broadphase_min_boxes_per_thread);
    const Grid g = make_grid(lo, hi, n, axis);
    std::vector<Entry> entries;
    std::vector<std::int64_t> offsets;
    fill_cells(lo, hi, n, g, nullptr, entries, offsets);
    return unpack(sweep_all(g, entries, offsets, /*sort_cells=*/true, threads));
}

SweepAndPrune::SweepAndPrune(const double* lo, const double* hi, std::int64_t n, int axis,
                             int threads) {
    check_axis(axis);
    check_count(n);
    validate_boxes(lo, hi, n);
    axis_ = axis < 0 ? choose_sweep_axis(lo, hi, n) : axis;
    threads_ = threads;
    order_.resize(static_cast<size_t>(n));
    keys_.resize(static_cast<size_t>(n));
    for (std::int64_t i = 0; i < n; ++i) order_[i] = static_cast<std::uint32_t>(i);
    std::sort(order_.begin(), order_.end(), [&](std::uint32_t a, std::uint32_t b) {
        return lo[3 * a + axis_] < lo[3 * b + axis_];
    });
    for (std::int64_t k = 0; k < n; ++k) keys_[k] = lo[3 * order_[k] + axis_];
    last_shifts_ = -1;
    const int t = resolve_threads(threads_, n, defaults::broadphase_min_boxes_per_thread);
    const Grid g = make_grid(lo, hi, n, axis_);
    std::vector<Entry> entries;
    std::vector<std::int64_t> offsets;
    fill_cells(lo, hi, n, g, order_.data(), entries, offsets);
    pairs_ = unpack(sweep_all(g, entries, offsets, /*sort_cells=*/false, t));
}

const std::vector<std::int64_t>& SweepAndPrune::update(const double* lo, const double* hi,
                                                       std::int64_t n) {
    if (n != size())
        throw std::invalid_argument("aabb_min must hold the same " + std::to_string(size()) +
                                    " boxes as before, got " + std::to_string(n));
    validate_boxes(lo, hi, n);
    for (std::int64_t k = 0; k < n; ++k) keys_[k] = lo[3 * order_[k] + axis_];
    // Insertion sort of the previous order: O(n + moves) on nearly sorted keys. A budget
    // bounds the moves; past it the motion was not small and a full sort is cheaper.
    const std::int64_t budget = defaults::sweep_max_shifts_per_box * std::max<std::int64_t>(n, 1);
    std::int64_t shifts = 0;
    bool gave_up = false;
    for (std::int64_t k = 1; k < n && !gave_up; ++k) {
        const double key = keys_[k];
        const std::uint32_t id = order_[k];
        std::int64_t j = k;
        while (j > 0 && keys_[j - 1] > key) {
            keys_[j] = keys_[j - 1];
            order_[j] = order_[j - 1];
            --j;
        }
        keys_[j] = key;
        order_[j] = id;
        shifts += k - j;
        gave_up = shifts > budget;
    }
    if (gave_up) {
        std::sort(order_.begin(), order_.end(), [&](std::uint32_t a, std::uint32_t b) {
            return lo[3 * a + axis_] < lo[3 * b + axis_];
        });
        for (std::int64_t k = 0; k < n; ++k) keys_[k] = lo[3 * order_[k] + axis_];
    }
    last_shifts_ = gave_up ? -1 : shifts;
    const int t = resolve_threads(threads_, n, defaults::broadphase_min_boxes_per_thread);
    const Grid g = make_grid(lo, hi, n, axis_);
    std::vector<Entry> entries;
    std::vector<std::int64_t> offsets;
    // Entering boxes in sorted order leaves every cell sorted: no per-cell sort.
    fill_cells(lo, hi, n, g, order_.data(), entries, offsets);
    pairs_ = unpack(sweep_all(g, entries, offsets, /*sort_cells=*/false, t));
    return pairs_;
}

}  // namespace meshcol
