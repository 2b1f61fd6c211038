#pragma once
/// Broad phase: find the few overlapping pairs among many axis-aligned boxes.
///
/// Two structures, as the classic literature describes them (Ericson 2004, ch. 6 and 7):
/// - `sort_and_sweep` / `SortAndSweep`: sort the boxes on one axis and sweep (Baraff 1992;
///   Cohen et al. 1995, I-COLLIDE), refined by a coarse grid on the two other axes
///   ("multi box pruning", Terdiman's PhysX MBP) so a uniform 3D cloud does not degrade into
///   a quadratic scan of one long slab.
/// - `AabbTree`: a dynamic bounding volume tree with SAH insertion, tree rotations and a
///   binned-SAH top-down rebuild, after Box2D v3 `dynamic_tree.c` (Catto).
///
/// Boxes come as two row-major (n, 3) arrays of doubles: `lo` (minimum corners) and `hi`
/// (maximum corners), world frame. Intervals are closed: touching boxes overlap. Pairs come
/// out as a flat vector [i0, j0, i1, j1, ...] with i < j, sorted lexicographically.

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "meshcol/aabb.hpp"

namespace meshcol {

/// Throws std::invalid_argument naming the first box that is not finite or has lo > hi, e.g.
/// "aabb_min/aabb_max: box 7 is not finite".
void validate_boxes(const double* lo, const double* hi, std::int64_t n);

/// The axis (0, 1, 2) along which the box centres have the largest variance (lowest axis on
/// ties; 0 for fewer than two boxes).
int choose_sweep_axis(const double* lo, const double* hi, std::int64_t n);

/// Sorts pair keys ((i << 32) | j) ascending, by LSD radix sort on 16-bit digits.
void sort_pair_keys(std::vector<std::uint64_t>& keys);

/// All overlapping pairs, by sort and sweep along `axis` (-1: `choose_sweep_axis`).
/// `threads` <= 0 means all cores. With `groups` (n group ids, or nullptr), boxes of the same
/// group are never paired (the parts of one body). Validates the boxes first
/// (std::invalid_argument). With `max_pairs` >= 0 and more pairs than that, stops early,
/// sets `*exceeded` (when given) and returns no pairs, holding at most about `threads` x
/// `max_pairs` pairs on the way: a cap on the memory a pile of boxes can take.
std::vector<std::int64_t> sort_and_sweep(const double* lo, const double* hi, std::int64_t n,
                                         int axis, int threads,
                                         const std::int64_t* groups = nullptr,
                                         std::int64_t max_pairs = -1, bool* exceeded = nullptr);

/// Receives one block of candidate pairs from `sort_and_sweep_stream`: the block's place in
/// the sweep's order, its pair keys ((i << 32) | j, i < j, in sweep order, not sorted) and
/// their count. Returns false to stop the sweep. Called on the worker threads.
using PairBlockConsumer = std::function<bool(std::int64_t block, const std::uint64_t* keys, std::int64_t count)>;

/// The pairs `sort_and_sweep` finds (no groups, no cap), streamed instead of collected: the
/// memory held is the boxes' entries and, per thread, one block of keys, never every pair.
/// The rows of each grid cell are cut into blocks of at most about `block_pairs` candidate
/// pairs (one row may hold more), numbered in cell and row order: the blocks depend on the
/// boxes alone, not on `threads`. Each block is handed to `consume` once, on one of `threads`
/// threads (<= 0: all cores), and blocks are handed out in increasing order, so the blocks
/// consumed are always a prefix of the order: all of them unless a call returned false, after
/// which no thread takes a new block (those under way finish). Returns the number of blocks.
/// Validates the boxes first (std::invalid_argument).
std::int64_t sort_and_sweep_stream(const double* lo, const double* hi, std::int64_t n, int axis,
                                   int threads, std::int64_t block_pairs, const PairBlockConsumer& consume);

/// Incremental sort and sweep for a moving scene: keeps the grid of the first step and the
/// sorted order of every grid cell, so a step where boxes move a little costs an insertion
/// sort over nearly sorted cells (plus moving the few boxes that changed cells) instead of a
/// fresh grid, scatter and sort (Baraff 1992; Cohen et al. 1995).
class SortAndSweep {
public:
    /// Sorts the boxes from scratch. `axis` -1 chooses by variance, then stays fixed.
    SortAndSweep(const double* lo, const double* hi, std::int64_t n, int axis, int threads);
    ~SortAndSweep();
    SortAndSweep(SortAndSweep&&) noexcept;
    SortAndSweep& operator=(SortAndSweep&&) noexcept;

    /// Replaces the boxes (same count) and returns the overlapping pairs.
    const std::vector<std::int64_t>& update(const double* lo, const double* hi, std::int64_t n);

    const std::vector<std::int64_t>& pairs() const { return *pairs_; }  ///< pairs of the last step
    /// The pairs of the last step, shared: a later update() makes a new vector and leaves this
    /// one alone, so a caller may keep it (the Python binding hands it to numpy without a copy).
    std::shared_ptr<const std::vector<std::int64_t>> shared_pairs() const { return pairs_; }
    int axis() const { return axis_; }                                 ///< the sweep axis
    std::int64_t size() const { return n_; }                           ///< n
    /// Element moves the last insertion sorts made (-1 when the step rebuilt the grid and
    /// sorted afresh because too many boxes moved too far).
    std::int64_t last_shifts() const { return last_shifts_; }

private:
    struct State;  ///< the grid and the sorted cells (sort_and_sweep.cpp)
    int axis_;
    int threads_;
    std::int64_t n_;
    std::unique_ptr<State> state_;
    std::shared_ptr<const std::vector<std::int64_t>> pairs_;
    std::int64_t last_shifts_ = 0;
};

/// Dynamic AABB tree (Box2D v3 `b2DynamicTree`, extended to 3D and to exact leaf boxes).
///
/// Each object ("proxy") has an id, its exact box and a fat box (the exact box grown by
/// `margin`) stored in a leaf. Internal nodes bound their children. Queries traverse the fat
/// boxes and confirm with the exact ones, so results never depend on the margin.
/// Ids of removed objects are reused by later insertions.
class AabbTree {
public:
    explicit AabbTree(double margin);

    /// Inserts one box (already validated); returns its id. Rotates to stay balanced.
    std::int32_t insert(const Aabb& box);
    /// Removes an object. `id` must be live (`contains`).
    void remove(std::int32_t id);
    /// Sets an object's box. When it still fits in its fat box only the exact box changes and
    /// this returns false; otherwise the leaf is reinserted with a new fat box (true).
    bool move(std::int32_t id, const Aabb& box);
    /// Drops every object.
    void clear();

    /// Replaces the content by `n` boxes built top-down (ids 0..n-1). Boxes must be valid.
    void build(const double* lo, const double* hi, std::int64_t n, int threads);
    /// Rebuilds the whole tree top-down by binned SAH, keeping the ids.
    void rebuild(int threads);

    /// Ids of the objects whose exact box overlaps `box`, ascending.
    std::vector<std::int64_t> query(const Aabb& box) const;
    /// All overlapping pairs of objects within the tree, as sorted pair keys (i < j).
    std::vector<std::uint64_t> query_pairs(int threads) const;
    /// All overlapping pairs (id in this tree, id in `other`), as sorted pair keys.
    std::vector<std::uint64_t> query_pairs(const AabbTree& other, int threads) const;
    /// Every object whose exact box the segment origin + t * direction, t in [0, max_fraction],
    /// meets: ids and entry fractions t (0 when the origin is inside), sorted by (t, id).
    void ray_cast(const Vec3& origin, const Vec3& direction, double max_fraction,
                  std::vector<std::int64_t>& ids, std::vector<double>& fractions) const;

    /// Throws std::runtime_error on any broken invariant (links, bounds, heights, counts,
    /// free lists, exact box inside fat box).
    void validate() const;

    int height() const;  ///< edges on the longest root-to-leaf path (0 for 0 or 1 object)
    std::int64_t size() const { return proxy_count_; }  ///< live objects
    double margin() const { return margin_; }
    bool contains(std::int64_t id) const;  ///< true when `id` is a live object
    Aabb box(std::int32_t id) const { return proxies_[static_cast<size_t>(id)].box; }
    Aabb fat_box(std::int32_t id) const;
    /// Sum of internal node half areas over the root's: the SAH quality measure (lower is
    /// better), as Box2D's b2DynamicTree_GetAreaRatio.
    double area_ratio() const;

private:
    static constexpr std::int32_t null_node = -1;

    struct Node {
        Aabb box;              ///< fat box of a leaf, or the union of the children
        std::int32_t parent;   ///< parent node, or next free node when free
        std::int32_t child1;   ///< first child, null_node for a leaf
        std::int32_t child2;   ///< second child, or the proxy id of a leaf
        std::int32_t height;   ///< 0 for a leaf, -1 when free
        bool is_leaf() const { return child1 == null_node; }
    };
    struct Proxy {
        Aabb box;           ///< exact box
        std::int32_t node;  ///< its leaf node, null_node when free
    };

    std::int32_t allocate_node();
    void free_node(std::int32_t node);
    std::int32_t find_best_sibling(const Aabb& box) const;
    void insert_leaf(std::int32_t leaf);
    void remove_leaf(std::int32_t leaf);
    void refit_upwards(std::int32_t node);
    void rotate(std::int32_t node);
    void swap_children(std::int32_t a, int slot_down, int slot_up);
    void build_from_proxies(std::vector<std::int32_t>& ids, int threads);
    void collect_pairs(const AabbTree& other, bool self, int threads,
                       std::vector<std::uint64_t>& keys) const;

    double margin_;
    std::vector<Node> nodes_;
    std::vector<Proxy> proxies_;
    std::vector<std::int32_t> free_proxies_;  ///< LIFO of free proxy ids
    std::int32_t root_ = null_node;
    std::int32_t free_list_ = null_node;
    std::int64_t node_count_ = 0;   ///< allocated nodes
    std::int64_t proxy_count_ = 0;  ///< live objects
};

}  // namespace meshcol
