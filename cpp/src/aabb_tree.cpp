// Dynamic AABB tree after Box2D v3 `dynamic_tree.c` (Catto): greedy SAH sibling search with
// branch-and-bound on insertion (Bittner et al. 2013, "Fast insertion-based optimization of
// bounding volume hierarchies"), tree rotations on the way up (Kopta et al. 2012, "Fast, effective
// BVH updates for animated scenes"), and a binned SAH top-down rebuild (Wald 2007, "On fast
// construction of SAH-based bounding volume hierarchies"). Extended to 3D (half surface area
// instead of perimeter), to exact leaf boxes behind the fat ones, and with a height guard on the
// rotations so degenerate inputs (all areas equal) cannot grow a linear chain.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "meshcol/batch.hpp"
#include "meshcol/broadphase.hpp"
#include "meshcol/defaults.hpp"

namespace meshcol {

namespace {

[[noreturn]] void broken(const std::string& what) {
    throw std::runtime_error("AabbTree invariant broken: " + what);
}

/// Clips the segment t in [t0, t1] of origin + t * direction against a box (slab test,
/// Ericson 2004, 5.3.3). Axes with a zero direction component need the origin inside the slab.
inline bool clip_segment(const Aabb& b, const Vec3& o, const Vec3& d, double& t0, double& t1) {
    const double lo[3] = {b.lo.x, b.lo.y, b.lo.z}, hi[3] = {b.hi.x, b.hi.y, b.hi.z};
    const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
    for (int k = 0; k < 3; ++k) {
        if (dd[k] == 0.0) {
            if (oo[k] < lo[k] || oo[k] > hi[k]) return false;
            continue;
        }
        double ta = (lo[k] - oo[k]) / dd[k], tb = (hi[k] - oo[k]) / dd[k];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) return false;
    }
    return true;
}

}  // namespace

AabbTree::AabbTree(double margin) : margin_(margin) {
    if (!std::isfinite(margin) || margin < 0.0)
        throw std::invalid_argument("margin must be finite and >= 0, got " + std::to_string(margin));
}

std::int32_t AabbTree::allocate_node() {
    std::int32_t n;
    if (free_list_ != null_node) {
        n = free_list_;
        free_list_ = nodes_[static_cast<size_t>(n)].parent;
    } else {
        n = static_cast<std::int32_t>(nodes_.size());
        nodes_.emplace_back();
    }
    nodes_[static_cast<size_t>(n)] = Node{Aabb{}, null_node, null_node, null_node, 0};
    ++node_count_;
    return n;
}

void AabbTree::free_node(std::int32_t n) {
    Node& node = nodes_[static_cast<size_t>(n)];
    node.parent = free_list_;
    node.child1 = node.child2 = null_node;
    node.height = -1;
    free_list_ = n;
    --node_count_;
}

void AabbTree::clear() {
    nodes_.clear();
    proxies_.clear();
    free_proxies_.clear();
    root_ = free_list_ = null_node;
    node_count_ = proxy_count_ = 0;
}

bool AabbTree::contains(std::int64_t id) const {
    return id >= 0 && id < static_cast<std::int64_t>(proxies_.size()) &&
           proxies_[static_cast<size_t>(id)].node != null_node;
}

Aabb AabbTree::fat_box(std::int32_t id) const {
    return nodes_[static_cast<size_t>(proxies_[static_cast<size_t>(id)].node)].box;
}

int AabbTree::height() const { return root_ == null_node ? 0 : nodes_[static_cast<size_t>(root_)].height; }

double AabbTree::area_ratio() const {
    if (root_ == null_node) return 0.0;
    const double root_area = half_area(nodes_[static_cast<size_t>(root_)].box);
    if (!(root_area > 0.0)) return 0.0;
    double sum = 0.0;
    for (size_t i = 0; i < nodes_.size(); ++i) {
        const Node& n = nodes_[i];
        if (n.height > 0 && static_cast<std::int32_t>(i) != root_) sum += half_area(n.box);
    }
    return sum / root_area;
}

// Greedy descent minimising the SAH cost of the new parent plus the growth of its ancestors,
// with a lower bound to stop early (Box2D v3 b2FindBestSibling; Bittner et al. 2013).
std::int32_t AabbTree::find_best_sibling(const Aabb& box_d) const {
    const Vec3 center_d = center(box_d);
    const double area_d = half_area(box_d);
    const Node* nodes = nodes_.data();
    std::int32_t index = root_;
    double area_base = half_area(nodes[index].box);
    double direct_cost = half_area(merge(nodes[index].box, box_d));
    double inherited_cost = 0.0;
    std::int32_t best_sibling = root_;
    double best_cost = direct_cost;
    while (!nodes[index].is_leaf()) {
        const std::int32_t child1 = nodes[index].child1, child2 = nodes[index].child2;
        // Cost of making `index` the sibling.
        const double cost = direct_cost + inherited_cost;
        if (cost < best_cost) {
            best_sibling = index;
            best_cost = cost;
        }
        // Every node below sees its ancestors grow by this much.
        inherited_cost += direct_cost - area_base;

        const bool leaf1 = nodes[child1].is_leaf(), leaf2 = nodes[child2].is_leaf();
        double lower1 = std::numeric_limits<double>::max(), area1 = 0.0;
        const double direct1 = half_area(merge(nodes[child1].box, box_d));
        if (leaf1) {
            const double cost1 = direct1 + inherited_cost;
            if (cost1 < best_cost) {
                best_sibling = child1;
                best_cost = cost1;
            }
        } else {
            area1 = half_area(nodes[child1].box);
            // Lower bound below child 1: it is the sibling, or a descendant is (then it grows by
            // at least direct1 - area1 and the new parent costs at least area_d).
            lower1 = inherited_cost + direct1 + std::min(area_d - area1, 0.0);
        }
        double lower2 = std::numeric_limits<double>::max(), area2 = 0.0;
        const double direct2 = half_area(merge(nodes[child2].box, box_d));
        if (leaf2) {
            const double cost2 = direct2 + inherited_cost;
            if (cost2 < best_cost) {
                best_sibling = child2;
                best_cost = cost2;
            }
        } else {
            area2 = half_area(nodes[child2].box);
            lower2 = inherited_cost + direct2 + std::min(area_d - area2, 0.0);
        }
        if (leaf1 && leaf2) break;
        if (best_cost <= lower1 && best_cost <= lower2) break;
        if (lower1 == lower2 && !leaf1) {
            // Both children contain D: no area tells them apart, the nearer centre does.
            const Vec3 d1 = center(nodes[child1].box) - center_d, d2 = center(nodes[child2].box) - center_d;
            lower1 = squared_norm(d1);
            lower2 = squared_norm(d2);
        }
        if (lower1 < lower2 && !leaf1) {
            index = child1;
            area_base = area1;
            direct_cost = direct1;
        } else {
            index = child2;
            area_base = area2;
            direct_cost = direct2;
        }
    }
    return best_sibling;
}

// Swaps the child of `a` at slot_down with the grandchild at slot_up of a's other child:
// (A (X Y (Z W))) -> (A (Z Y (X W))). A's box is unchanged; Y's box and both heights are refit.
void AabbTree::swap_children(std::int32_t a, int slot_down, int slot_up) {
    Node& na = nodes_[static_cast<size_t>(a)];
    const std::int32_t x = slot_down == 0 ? na.child1 : na.child2;
    const std::int32_t y = slot_down == 0 ? na.child2 : na.child1;
    Node& ny = nodes_[static_cast<size_t>(y)];
    const std::int32_t z = slot_up == 0 ? ny.child1 : ny.child2;
    (slot_down == 0 ? na.child1 : na.child2) = z;
    (slot_up == 0 ? ny.child1 : ny.child2) = x;
    nodes_[static_cast<size_t>(z)].parent = a;
    nodes_[static_cast<size_t>(x)].parent = y;
    const Node& y1 = nodes_[static_cast<size_t>(ny.child1)];
    const Node& y2 = nodes_[static_cast<size_t>(ny.child2)];
    ny.box = merge(y1.box, y2.box);
    ny.height = 1 + std::max(y1.height, y2.height);
    na.height = 1 + std::max(nodes_[static_cast<size_t>(z)].height, ny.height);
}

// Box2D v3 b2RotateNodes: among the four swaps of a child of A with a grandchild on the other
// side, take the one that shrinks the internal area most. The swaps also serve as AVL-style
// rotations: a node whose children's heights differ by more than tree_max_height_imbalance
// takes the swap that balances it best, and area swaps may not unbalance past that limit.
void AabbTree::rotate(std::int32_t a) {
    const Node& na = nodes_[static_cast<size_t>(a)];
    if (na.height < 2) return;
    const int limit = defaults::tree_max_height_imbalance;
    const Node& nb = nodes_[static_cast<size_t>(na.child1)];
    const Node& nc = nodes_[static_cast<size_t>(na.child2)];
    const int imbalance = std::abs(nb.height - nc.height);

    int best_down = -1, best_up = 0;
    double best_delta = 0.0;
    int best_balance = imbalance;  // max of the resulting imbalances at A and at the moved-into child
    for (int down = 0; down < 2; ++down) {
        const Node& x = down == 0 ? nb : nc;  // goes down
        const Node& y = down == 0 ? nc : nb;  // receives it
        if (y.is_leaf()) continue;
        const double area_y = half_area(y.box);
        for (int up = 0; up < 2; ++up) {
            const Node& z = nodes_[static_cast<size_t>(up == 0 ? y.child1 : y.child2)];  // goes up
            const Node& w = nodes_[static_cast<size_t>(up == 0 ? y.child2 : y.child1)];  // stays
            const double delta = half_area(merge(x.box, w.box)) - area_y;
            const int height_y = 1 + std::max(x.height, w.height);
            const int balance = std::max(std::abs(z.height - height_y), std::abs(x.height - w.height));
            if (imbalance > limit) {
                // Rebalance first, area second.
                if (balance < best_balance || (balance == best_balance && best_down >= 0 && delta < best_delta)) {
                    best_down = down;
                    best_up = up;
                    best_delta = delta;
                    best_balance = balance;
                }
            } else if (delta < best_delta && balance <= limit) {
                best_down = down;
                best_up = up;
                best_delta = delta;
            }
        }
    }
    if (best_down < 0) return;
    swap_children(a, best_down, best_up);
    // The node that received a subtree may now be the unbalanced one (inserting at the root
    // again and again, as identical boxes do, would otherwise grow a caterpillar below it):
    // fix it the same way, then refresh A's height. Depth is bounded by the height.
    const Node& n = nodes_[static_cast<size_t>(a)];
    const std::int32_t y = best_down == 0 ? n.child2 : n.child1;
    const Node& ny = nodes_[static_cast<size_t>(y)];
    if (std::abs(nodes_[static_cast<size_t>(ny.child1)].height - nodes_[static_cast<size_t>(ny.child2)].height) > limit) {
        rotate(y);
        Node& na2 = nodes_[static_cast<size_t>(a)];
        na2.height = 1 + std::max(nodes_[static_cast<size_t>(na2.child1)].height, nodes_[static_cast<size_t>(na2.child2)].height);
    }
}

void AabbTree::refit_upwards(std::int32_t index) {
    while (index != null_node) {
        Node& n = nodes_[static_cast<size_t>(index)];
        const Node& c1 = nodes_[static_cast<size_t>(n.child1)];
        const Node& c2 = nodes_[static_cast<size_t>(n.child2)];
        n.box = merge(c1.box, c2.box);
        n.height = 1 + std::max(c1.height, c2.height);
        rotate(index);
        index = nodes_[static_cast<size_t>(index)].parent;
    }
}

void AabbTree::insert_leaf(std::int32_t leaf) {
    if (root_ == null_node) {
        root_ = leaf;
        nodes_[static_cast<size_t>(leaf)].parent = null_node;
        return;
    }
    const Aabb box = nodes_[static_cast<size_t>(leaf)].box;
    const std::int32_t sibling = find_best_sibling(box);
    const std::int32_t old_parent = nodes_[static_cast<size_t>(sibling)].parent;
    const std::int32_t parent = allocate_node();  // may reallocate nodes_: no references above
    Node& np = nodes_[static_cast<size_t>(parent)];
    np.parent = old_parent;
    np.box = merge(box, nodes_[static_cast<size_t>(sibling)].box);
    np.height = nodes_[static_cast<size_t>(sibling)].height + 1;
    np.child1 = sibling;
    np.child2 = leaf;
    if (old_parent == null_node) {
        root_ = parent;
    } else {
        Node& op = nodes_[static_cast<size_t>(old_parent)];
        (op.child1 == sibling ? op.child1 : op.child2) = parent;
    }
    nodes_[static_cast<size_t>(sibling)].parent = parent;
    nodes_[static_cast<size_t>(leaf)].parent = parent;
    refit_upwards(parent);
}

void AabbTree::remove_leaf(std::int32_t leaf) {
    if (leaf == root_) {
        root_ = null_node;
        return;
    }
    const std::int32_t parent = nodes_[static_cast<size_t>(leaf)].parent;
    const Node& np = nodes_[static_cast<size_t>(parent)];
    const std::int32_t grand = np.parent;
    const std::int32_t sibling = np.child1 == leaf ? np.child2 : np.child1;
    if (grand == null_node) {
        root_ = sibling;
        nodes_[static_cast<size_t>(sibling)].parent = null_node;
        free_node(parent);
        return;
    }
    Node& ng = nodes_[static_cast<size_t>(grand)];
    (ng.child1 == parent ? ng.child1 : ng.child2) = sibling;
    nodes_[static_cast<size_t>(sibling)].parent = grand;
    free_node(parent);
    refit_upwards(grand);
}

std::int32_t AabbTree::insert(const Aabb& box) {
    if (proxy_count_ >= defaults::tree_max_objects)
        throw std::invalid_argument("AabbTree holds at most " + std::to_string(defaults::tree_max_objects) + " boxes");
    std::int32_t id;
    if (!free_proxies_.empty()) {
        id = free_proxies_.back();
        free_proxies_.pop_back();
    } else {
        id = static_cast<std::int32_t>(proxies_.size());
        proxies_.emplace_back();
    }
    const std::int32_t leaf = allocate_node();
    Node& n = nodes_[static_cast<size_t>(leaf)];
    n.box = inflate(box, margin_);
    n.child1 = null_node;
    n.child2 = id;
    n.height = 0;
    proxies_[static_cast<size_t>(id)] = Proxy{box, leaf};
    insert_leaf(leaf);
    ++proxy_count_;
    return id;
}

void AabbTree::remove(std::int32_t id) {
    Proxy& p = proxies_[static_cast<size_t>(id)];
    remove_leaf(p.node);
    free_node(p.node);
    p.node = null_node;
    free_proxies_.push_back(id);
    --proxy_count_;
}

bool AabbTree::move(std::int32_t id, const Aabb& box) {
    Proxy& p = proxies_[static_cast<size_t>(id)];
    p.box = box;
    const std::int32_t leaf = p.node;
    if (meshcol::contains(nodes_[static_cast<size_t>(leaf)].box, box)) return false;
    remove_leaf(leaf);
    nodes_[static_cast<size_t>(leaf)].box = inflate(box, margin_);
    insert_leaf(leaf);
    return true;
}

// ---------------------------------------------------------------------------------------------
// Top-down build: binned SAH (Wald 2007) along the axis of largest centroid extent, as Box2D v3
// b2PartitionSAH. Nodes are numbered in depth-first pre-order from the ranges alone (a range of
// m leaves owns 2m - 1 consecutive nodes), so the two halves of a split can be built on two
// threads without sharing anything, and queries walk memory mostly forwards.

namespace {

struct BuildInput {
    std::int32_t* ids;  ///< proxy ids, permuted by the partitions
    Aabb* boxes;        ///< their fat boxes, permuted alongside
};

/// Partitions [0, m) and returns the split k in (0, m); `bounds` receives the union box.
std::int64_t partition_sah(std::int32_t* ids, Aabb* boxes, std::int64_t m, Aabb& bounds) {
    bounds = boxes[0];
    Vec3 cmin = center(boxes[0]), cmax = cmin;
    for (std::int64_t i = 1; i < m; ++i) {
        bounds = merge(bounds, boxes[i]);
        const Vec3 c = center(boxes[i]);
        // std::min, not fmin: no NaN here, and fmin is a library call in this hot loop.
        cmin = {std::min(cmin.x, c.x), std::min(cmin.y, c.y), std::min(cmin.z, c.z)};
        cmax = {std::max(cmax.x, c.x), std::max(cmax.y, c.y), std::max(cmax.z, c.z)};
    }
    const Vec3 ext = cmax - cmin;
    int axis = 0;
    if (ext.y > ext[axis]) axis = 1;
    if (ext.z > ext[axis]) axis = 2;
    const double extent = ext[axis];
    if (!(extent > 0.0) || !std::isfinite(extent)) return m / 2;  // all centres equal

    constexpr int bins = defaults::tree_bin_count;
    std::int64_t count[bins] = {};
    Aabb bin_box[bins];
    const double lo = cmin[axis];
    const double scale = bins / extent;
    auto bin_of = [&](const Aabb& b) {
        const double t = (center(b)[axis] - lo) * scale;
        return t >= bins ? bins - 1 : (t > 0.0 ? static_cast<int>(t) : 0);
    };
    for (std::int64_t i = 0; i < m; ++i) {
        const int b = bin_of(boxes[i]);
        bin_box[b] = count[b] == 0 ? boxes[i] : merge(bin_box[b], boxes[i]);
        ++count[b];
    }
    // Plane p puts bins [0, p] left. Cost = n_left * A_left + n_right * A_right.
    double left_area[bins];
    std::int64_t left_count[bins];
    {
        Aabb acc{};
        std::int64_t c = 0;
        for (int p = 0; p < bins - 1; ++p) {
            if (count[p] > 0) acc = c == 0 ? bin_box[p] : merge(acc, bin_box[p]);
            c += count[p];
            left_count[p] = c;
            left_area[p] = c > 0 ? half_area(acc) : 0.0;
        }
    }
    double best_cost = std::numeric_limits<double>::infinity();
    int best_plane = -1;
    std::int64_t best_gap = m;
    {
        Aabb acc{};
        std::int64_t c = 0;
        for (int p = bins - 2; p >= 0; --p) {
            if (count[p + 1] > 0) acc = c == 0 ? bin_box[p + 1] : merge(acc, bin_box[p + 1]);
            c += count[p + 1];
            if (c == 0 || left_count[p] == 0) continue;
            const double cost = static_cast<double>(left_count[p]) * left_area[p] +
                                static_cast<double>(c) * half_area(acc);
            const std::int64_t gap = std::llabs(left_count[p] - c);
            // Equal costs (flat or point-like boxes have zero area): prefer the balanced split.
            if (cost < best_cost || (cost == best_cost && gap < best_gap)) {
                best_cost = cost;
                best_plane = p;
                best_gap = gap;
            }
        }
    }
    if (best_plane < 0) return m / 2;
    // Hoare partition of ids and boxes together.
    std::int64_t i1 = 0, i2 = m;
    while (i1 < i2) {
        while (i1 < i2 && bin_of(boxes[i1]) <= best_plane) ++i1;
        while (i1 < i2 && bin_of(boxes[i2 - 1]) > best_plane) --i2;
        if (i1 < i2) {
            std::swap(ids[i1], ids[i2 - 1]);
            std::swap(boxes[i1], boxes[i2 - 1]);
            ++i1;
            --i2;
        }
    }
    return (i1 > 0 && i1 < m) ? i1 : m / 2;
}

}  // namespace

void AabbTree::build_from_proxies(std::vector<std::int32_t>& ids, int threads) {
    const std::int64_t m = static_cast<std::int64_t>(ids.size());
    nodes_.assign(m > 0 ? static_cast<size_t>(2 * m - 1) : 0, Node{});
    free_list_ = null_node;
    node_count_ = m > 0 ? 2 * m - 1 : 0;
    root_ = m > 0 ? 0 : null_node;
    if (m == 0) return;
    std::vector<Aabb> boxes(static_cast<size_t>(m));
    for (std::int64_t i = 0; i < m; ++i) boxes[i] = inflate(proxies_[static_cast<size_t>(ids[i])].box, margin_);

    struct Item {
        std::int64_t begin, end;
        std::int32_t node, parent;
    };
    auto build_range = [&](Item first) {
        std::vector<Item> stack{first};
        while (!stack.empty()) {
            const Item it = stack.back();
            stack.pop_back();
            const std::int64_t count = it.end - it.begin;
            Node& n = nodes_[static_cast<size_t>(it.node)];
            n.parent = it.parent;
            if (count == 1) {
                const std::int32_t id = ids[static_cast<size_t>(it.begin)];
                n.box = boxes[static_cast<size_t>(it.begin)];
                n.child1 = null_node;
                n.child2 = id;
                n.height = 0;
                proxies_[static_cast<size_t>(id)].node = it.node;
                continue;
            }
            const std::int64_t k = partition_sah(ids.data() + it.begin, boxes.data() + it.begin, count, n.box);
            n.child1 = it.node + 1;
            n.child2 = it.node + static_cast<std::int32_t>(2 * k);
            stack.push_back(Item{it.begin + k, it.end, n.child2, it.node});
            stack.push_back(Item{it.begin, it.begin + k, n.child1, it.node});
        }
    };
    threads = resolve_threads(threads, m, defaults::broadphase_min_boxes_per_thread);
    if (threads > 1 && m >= 4) {
        // Split the root here, then build its two halves on two threads.
        Node& r = nodes_[0];
        r.parent = null_node;
        const std::int64_t k = partition_sah(ids.data(), boxes.data(), m, r.box);
        r.child1 = 1;
        r.child2 = static_cast<std::int32_t>(2 * k);
        std::thread left(build_range, Item{0, k, r.child1, 0});
        build_range(Item{k, m, r.child2, 0});
        left.join();
    } else {
        build_range(Item{0, m, 0, null_node});
    }
    // Pre-order numbering puts children after parents: one backwards pass sets the heights.
    for (std::int64_t i = 2 * m - 2; i >= 0; --i) {
        Node& n = nodes_[static_cast<size_t>(i)];
        if (!n.is_leaf())
            n.height = 1 + std::max(nodes_[static_cast<size_t>(n.child1)].height,
                                    nodes_[static_cast<size_t>(n.child2)].height);
    }
}

void AabbTree::build(const double* lo, const double* hi, std::int64_t n, int threads) {
    if (n > defaults::tree_max_objects)
        throw std::invalid_argument("AabbTree holds at most " + std::to_string(defaults::tree_max_objects) + " boxes");
    clear();
    proxies_.resize(static_cast<size_t>(n));
    std::vector<std::int32_t> ids(static_cast<size_t>(n));
    for (std::int64_t i = 0; i < n; ++i) {
        proxies_[i].box = Aabb{{lo[3 * i], lo[3 * i + 1], lo[3 * i + 2]}, {hi[3 * i], hi[3 * i + 1], hi[3 * i + 2]}};
        ids[i] = static_cast<std::int32_t>(i);
    }
    proxy_count_ = n;
    build_from_proxies(ids, threads);
}

void AabbTree::rebuild(int threads) {
    std::vector<std::int32_t> ids;
    ids.reserve(static_cast<size_t>(proxy_count_));
    for (size_t i = 0; i < proxies_.size(); ++i)
        if (proxies_[i].node != null_node) ids.push_back(static_cast<std::int32_t>(i));
    build_from_proxies(ids, threads);
}

// ---------------------------------------------------------------------------------------------
// Queries.

std::vector<std::int64_t> AabbTree::query(const Aabb& box) const {
    std::vector<std::int64_t> out;
    if (root_ == null_node) return out;
    std::vector<std::int32_t> stack{root_};
    while (!stack.empty()) {
        const Node& n = nodes_[static_cast<size_t>(stack.back())];
        stack.pop_back();
        if (!overlaps(n.box, box)) continue;
        if (n.is_leaf()) {
            if (overlaps(proxies_[static_cast<size_t>(n.child2)].box, box)) out.push_back(n.child2);
        } else {
            stack.push_back(n.child2);
            stack.push_back(n.child1);
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

// Simultaneous descent of two trees (or of one tree against itself), descending the node with
// the larger area first (Ericson 2004, 6.5.2 "descend larger"). Self pairs come from
// self(n) = self(c1) + self(c2) + cross(c1, c2), so no pair is found twice.
void AabbTree::collect_pairs(const AabbTree& other, bool self, int threads,
                             std::vector<std::uint64_t>& keys) const {
    keys.clear();
    if (root_ == null_node || other.root_ == null_node) return;
    const Node* na = nodes_.data();
    const Node* nb = other.nodes_.data();
    const Proxy* pa = proxies_.data();
    const Proxy* pb = other.proxies_.data();
    using Task = std::pair<std::int32_t, std::int32_t>;

    // One step of the descent: pushes the sub-tasks of (a, b) or emits its pair.
    auto step = [&](const Task& t, std::vector<Task>& push, std::vector<std::uint64_t>& out) {
        const auto [a, b] = t;
        const Node& x = na[a];
        if (self && a == b) {
            if (!x.is_leaf()) {
                push.emplace_back(x.child1, x.child1);
                push.emplace_back(x.child2, x.child2);
                push.emplace_back(x.child1, x.child2);
            }
            return;
        }
        const Node& y = nb[b];
        if (!overlaps(x.box, y.box)) return;
        if (x.is_leaf() && y.is_leaf()) {
            const std::uint64_t i = static_cast<std::uint32_t>(x.child2), j = static_cast<std::uint32_t>(y.child2);
            if (overlaps(pa[i].box, pb[j].box))
                out.push_back(self ? (std::min(i, j) << 32 | std::max(i, j)) : (i << 32 | j));
        } else if (y.is_leaf() || (!x.is_leaf() && half_area(x.box) >= half_area(y.box))) {
            push.emplace_back(x.child1, b);
            push.emplace_back(x.child2, b);
        } else {
            push.emplace_back(a, y.child1);
            push.emplace_back(a, y.child2);
        }
    };
    auto run = [&](const Task& start, std::vector<std::uint64_t>& out) {
        std::vector<Task> stack{start};
        while (!stack.empty()) {
            const Task t = stack.back();
            stack.pop_back();
            step(t, stack, out);
        }
    };

    const std::int64_t work = std::min(proxy_count_, other.proxy_count_) + (self ? proxy_count_ : 0);
    threads = resolve_threads(threads, work, defaults::broadphase_min_boxes_per_thread);
    std::vector<Task> tasks{{root_, other.root_}};
    if (threads > 1) {
        // Expand breadth-first into enough independent tasks to balance the threads.
        const size_t target = static_cast<size_t>(threads) * 64;
        std::vector<std::uint64_t> found;
        for (int round = 0; round < 64 && tasks.size() < target && !tasks.empty(); ++round) {
            std::vector<Task> next;
            bool expanded = false;
            for (const Task& t : tasks) {
                const bool leaf_pair = !(self && t.first == t.second) && na[t.first].is_leaf() &&
                                       nb[t.second].is_leaf();
                if (leaf_pair) {
                    next.push_back(t);
                } else {
                    step(t, next, found);
                    expanded = true;
                }
            }
            tasks.swap(next);
            if (!expanded) break;
        }
        std::vector<std::vector<std::uint64_t>> per_task(tasks.size());
        parallel_for(static_cast<long long>(tasks.size()), threads, [&](long long t0, long long t1) {
            for (long long t = t0; t < t1; ++t) run(tasks[static_cast<size_t>(t)], per_task[static_cast<size_t>(t)]);
        });
        size_t total = found.size();
        for (const auto& v : per_task) total += v.size();
        keys.reserve(total);
        keys.insert(keys.end(), found.begin(), found.end());
        for (const auto& v : per_task) keys.insert(keys.end(), v.begin(), v.end());
    } else {
        run(tasks[0], keys);
    }
    sort_pair_keys(keys);
}

std::vector<std::uint64_t> AabbTree::query_pairs(int threads) const {
    std::vector<std::uint64_t> keys;
    collect_pairs(*this, true, threads, keys);
    return keys;
}

std::vector<std::uint64_t> AabbTree::query_pairs(const AabbTree& other, int threads) const {
    std::vector<std::uint64_t> keys;
    collect_pairs(other, &other == this, threads, keys);
    return keys;
}

void AabbTree::ray_cast(const Vec3& origin, const Vec3& direction, double max_fraction,
                        std::vector<std::int64_t>& ids, std::vector<double>& fractions) const {
    ids.clear();
    fractions.clear();
    if (root_ == null_node) return;
    std::vector<std::pair<double, std::int64_t>> hits;
    std::vector<std::int32_t> stack{root_};
    while (!stack.empty()) {
        const Node& n = nodes_[static_cast<size_t>(stack.back())];
        stack.pop_back();
        double t0 = 0.0, t1 = max_fraction;
        if (!clip_segment(n.box, origin, direction, t0, t1)) continue;
        if (n.is_leaf()) {
            t0 = 0.0;
            t1 = max_fraction;
            if (clip_segment(proxies_[static_cast<size_t>(n.child2)].box, origin, direction, t0, t1))
                hits.emplace_back(t0, n.child2);
        } else {
            stack.push_back(n.child2);
            stack.push_back(n.child1);
        }
    }
    std::sort(hits.begin(), hits.end());
    for (const auto& [t, id] : hits) {
        ids.push_back(id);
        fractions.push_back(t);
    }
}

void AabbTree::validate() const {
    // Free lists.
    std::int64_t free_nodes = 0;
    for (std::int32_t f = free_list_; f != null_node; f = nodes_[static_cast<size_t>(f)].parent) {
        if (f < 0 || static_cast<size_t>(f) >= nodes_.size()) broken("free node index out of range");
        if (nodes_[static_cast<size_t>(f)].height != -1) broken("free node " + std::to_string(f) + " not marked free");
        if (++free_nodes > static_cast<std::int64_t>(nodes_.size())) broken("free node list has a cycle");
    }
    if (free_nodes + node_count_ != static_cast<std::int64_t>(nodes_.size())) broken("node count");
    std::int64_t live = 0;
    for (const Proxy& p : proxies_) live += p.node != null_node;
    if (live != proxy_count_) broken("object count");
    if (static_cast<std::int64_t>(free_proxies_.size()) + proxy_count_ != static_cast<std::int64_t>(proxies_.size()))
        broken("free id count");
    for (const std::int32_t id : free_proxies_)
        if (id < 0 || static_cast<size_t>(id) >= proxies_.size() || proxies_[static_cast<size_t>(id)].node != null_node)
            broken("free id " + std::to_string(id) + " is live");
    if (root_ == null_node) {
        if (node_count_ != 0 || proxy_count_ != 0) broken("empty tree holds nodes");
        return;
    }
    if (nodes_[static_cast<size_t>(root_)].parent != null_node) broken("root has a parent");
    // Structure, bounds and heights.
    std::int64_t reached = 0, leaves = 0;
    std::vector<std::int32_t> stack{root_};
    while (!stack.empty()) {
        const std::int32_t i = stack.back();
        stack.pop_back();
        if (i < 0 || static_cast<size_t>(i) >= nodes_.size()) broken("child index out of range");
        if (++reached > node_count_) broken("more nodes reachable than allocated (a cycle?)");
        const Node& n = nodes_[static_cast<size_t>(i)];
        const std::string where = "node " + std::to_string(i);
        if (n.height < 0) broken(where + " is free but linked");
        if (n.is_leaf()) {
            ++leaves;
            if (n.height != 0) broken(where + ": leaf height " + std::to_string(n.height));
            if (!contains(n.child2)) broken(where + ": leaf holds a dead id");
            const Proxy& p = proxies_[static_cast<size_t>(n.child2)];
            if (p.node != i) broken(where + ": id " + std::to_string(n.child2) + " points elsewhere");
            if (!meshcol::contains(n.box, p.box)) broken(where + ": fat box does not hold the exact box");
            continue;
        }
        if (n.child2 < 0) broken(where + ": one child");
        for (const std::int32_t c : {n.child1, n.child2}) {
            if (c < 0 || static_cast<size_t>(c) >= nodes_.size()) broken(where + ": child out of range");
            const Node& cn = nodes_[static_cast<size_t>(c)];
            if (cn.parent != i) broken("node " + std::to_string(c) + ": wrong parent");
            if (!meshcol::contains(n.box, cn.box)) broken(where + ": box does not hold child " + std::to_string(c));
            stack.push_back(c);
        }
        const int h = 1 + std::max(nodes_[static_cast<size_t>(n.child1)].height, nodes_[static_cast<size_t>(n.child2)].height);
        if (n.height != h) broken(where + ": height " + std::to_string(n.height) + ", expected " + std::to_string(h));
    }
    if (reached != node_count_) broken("unreachable allocated nodes");
    if (leaves != proxy_count_) broken("leaf count differs from object count");
}

}  // namespace meshcol
