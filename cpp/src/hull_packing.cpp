// Many hulls packed in one call for a ConvexSet (hull.hpp: pack_polytopes): each shape's hull
// (hull.cpp) with its vertex adjacency for hill climbing and its face normals and true edges
// for SAT, on threads, concatenated; and the edges' direction classes, which SAT computes for
// a shape when it first needs them (edge_direction_classes).
#include <algorithm>
#include <array>
#include <atomic>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <numeric>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

#include "meshcol/batch.hpp"
#include "meshcol/defaults.hpp"
#include "meshcol/hull.hpp"
#include "hull_detail.hpp"

namespace meshcol {
namespace {

using namespace hull_detail;

// The pages of `v`'s room from element `from` to element `to` (within its capacity) made
// present and writable in one call (Linux 5.14's MADV_POPULATE_WRITE; elsewhere, or on an
// older kernel, nothing: it is advice, and the pages then fault one by one as they are first
// written). A packing writes every byte of its result once, into fresh memory: at 64 points a
// shape about 8.5 kB a hull, two page faults, whose traps cost more than their pages' zeroing
// (prefaulting a chunk's room in one call saved 5-7% of the CPU of 40,000 hulls).
template <class T>
void prefault(const std::vector<T>& v, size_t from, size_t to) {
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
    to = std::min(to, v.capacity());
    if (to <= from) return;
    static const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
    const auto begin = reinterpret_cast<std::uintptr_t>(v.data() + from) & ~(page - 1);
    const auto end = reinterpret_cast<std::uintptr_t>(v.data() + to);
    madvise(reinterpret_cast<void*>(begin), end - begin, MADV_POPULATE_WRITE);
#else
    (void)v, (void)from, (void)to;
#endif
}

// Keeps the room of a growing vector prefaulted a window ahead of its end (prefault): a
// call every few hundred small hulls.
class PrefaultAhead {
public:
    template <class T>
    void keep(const std::vector<T>& v) {
        constexpr size_t kWindowBytes = size_t{1} << 18;
        constexpr size_t kWindow = kWindowBytes / sizeof(T);
        if (v.size() + kWindow / 2 <= done_) return;
        const size_t from = std::max(done_, v.size());
        done_ = v.size() + kWindow;
        prefault(v, from, done_);
    }

private:
    size_t done_ = 0;  // the room below this element was prefaulted (or written)
};

// The packed arrays of a run of consecutive shapes, concatenated (per-shape vectors cost an
// allocation each, about as much as a small hull): the chunks are joined in order at the end.
// Vertices and face normals as flat (x, y, z) triples, edges as flat (from, to) pairs: a
// single chunk's arrays become the result's without a copy.
struct ChunkPack {
    std::vector<HullStatus> status;
    std::vector<double> vertices;
    std::vector<std::int64_t> vertex_counts, face_counts, edge_counts;  // per shape
    std::vector<std::int64_t> adjacency_counts;                          // per vertex
    std::vector<std::int32_t> adjacency;
    std::vector<double> faces;
    std::vector<std::int32_t> edges;  // (from, to) pairs
    std::vector<std::int64_t> climb_counts;  // per shape: its climb lists, 0 or its vertices
    std::vector<ClimbList> climb_lists;
    PrefaultAhead ahead[6];  // of vertices, adjacency_counts, adjacency, faces, edges, climb_lists

    // Room for shapes of `points` points in all (a hull of k vertices has at most 2k - 4
    // triangles and 3k - 6 edges), so the arrays never move while they fill (points_to_reserve
    // bounds the room of large inputs: mostly interior points, their arrays grow as they fill).
    void reserve(long long shapes, long long points) {
        const auto p = static_cast<size_t>(points);
        const auto h = static_cast<size_t>(shapes);
        status.reserve(h);
        vertex_counts.reserve(h);
        face_counts.reserve(h);
        edge_counts.reserve(h);
        climb_counts.reserve(h);
        vertices.reserve(3 * p);
        adjacency_counts.reserve(p);
        adjacency.reserve(6 * p + 3 * p + 4 * h);
        faces.reserve(3 * (2 * p + 2 * h));
        edges.reserve(2 * (3 * p + h));
        climb_lists.reserve(p);
    }

    /// After a shape: the room of the large arrays prefaulted ahead of their ends (the
    /// pages stay present when the buffers are cleared for the next chunk).
    void prefault_ahead() {
        ahead[0].keep(vertices);
        ahead[1].keep(adjacency_counts);
        ahead[2].keep(adjacency);
        ahead[3].keep(faces);
        ahead[4].keep(edges);
        ahead[5].keep(climb_lists);
    }

    /// Empty, keeping the room (the buffers of the next chunk).
    void clear() {
        status.clear();
        vertices.clear();
        vertex_counts.clear();
        face_counts.clear();
        edge_counts.clear();
        adjacency_counts.clear();
        adjacency.clear();
        faces.clear();
        edges.clear();
        climb_counts.clear();
        climb_lists.clear();
    }
};

void push(std::vector<double>& dst, const Vec3& v) { dst.insert(dst.end(), {v.x, v.y, v.z}); }

// A cell of unique_directions' table: the index of a direction in the call's list (its key
// the class's), current when its stamp is the call's (8 bytes: a 1,024-vertex hull's table stays
// within the L2 cache).
struct DirectionCell {
    unsigned stamp;
    std::int32_t key;
};

// Scratch of the packing, kept across the shapes of a chunk.
struct PackScratch {
    std::vector<std::pair<int, int>> pairs;  // undirected edges of the triangulation
    std::vector<std::int64_t> start, fill;
    std::vector<std::int32_t> around;  // adjacency_from_edges' neighbours, unordered
    std::vector<DirectionCell> table;  // unique_directions' hash table
    std::vector<double> unit, keys;    // and each direction's unit vector and key (unit_keys)
    std::vector<char> valid;
    unsigned stamp = 0;                // the table's cells of the current call carry it
    std::vector<Vec3> directions;
    std::vector<double> unique;  // pack_one's vertices before they are appended
    std::vector<double> classes;  // edge_direction_class_count's (discarded) classes
    // The climb lists adjacency_from_masks wrote for the shape (0 or its vertex count), or -1
    // when it wrote none and left them to append_climb_lists.
    std::int64_t climb_written = -1;
};

// The unit direction of d[i] and its grouping key into unit[3 i ..] and key[3 i ..]
// (valid[i] 0 for a zero or NaN length: no class): the unit vector d / |d|, sign-flipped for
// unsigned classes when its first component clearly non-zero (beyond 1e-12) is negative;
// the key floor(u * 1e12 + 0.5) of each component, as a double (|u| <= 1 and a little: an
// integer far below 2^51, exact). Ties may round either way (as np.round's half-to-even does
// differently), which only splits a class in two.
//
// Two directions at a time in SSE2 lanes: IEEE's operations are the same in a lane as alone,
// so the bits are the scalar loop's; floor as rint(t) (t + 1.5 * 2^52 - 1.5 * 2^52, exact
// for |t| < 2^51) less one where that is above t.
#if defined(__SSE2__)
void unit_keys(const Vec3* d, size_t count, bool signed_classes, double* unit, double* key,
               char* valid) {
    const __m128d zero = _mm_setzero_pd();
    const __m128d sign = _mm_set1_pd(-0.0);
    const __m128d tiny = _mm_set1_pd(1e-12);
    const __m128d scale = _mm_set1_pd(1e12);
    const __m128d half = _mm_set1_pd(0.5);
    const __m128d one = _mm_set1_pd(1.0);
    const __m128d magic = _mm_set1_pd(6755399441055744.0);  // 1.5 * 2^52
    for (size_t i = 0; i < count; i += 2) {
        const size_t j = i + 1 < count ? i + 1 : i;  // an odd count's last one twice
        __m128d x = _mm_set_pd(d[j].x, d[i].x);
        __m128d y = _mm_set_pd(d[j].y, d[i].y);
        __m128d z = _mm_set_pd(d[j].z, d[i].z);
        const __m128d len = _mm_sqrt_pd(_mm_add_pd(
            _mm_add_pd(_mm_mul_pd(x, x), _mm_mul_pd(y, y)), _mm_mul_pd(z, z)));
        const int ok = _mm_movemask_pd(_mm_cmpgt_pd(len, zero));
        x = _mm_div_pd(x, len);
        y = _mm_div_pd(y, len);
        z = _mm_div_pd(z, len);
        if (!signed_classes) {
            const __m128d clear_x = _mm_cmpgt_pd(_mm_andnot_pd(sign, x), tiny);
            const __m128d clear_y = _mm_cmpgt_pd(_mm_andnot_pd(sign, y), tiny);
            __m128d lead = _mm_or_pd(_mm_and_pd(clear_y, y), _mm_andnot_pd(clear_y, z));
            lead = _mm_or_pd(_mm_and_pd(clear_x, x), _mm_andnot_pd(clear_x, lead));
            const __m128d flip =
                _mm_and_pd(_mm_and_pd(_mm_cmplt_pd(lead, zero),
                                      _mm_cmpgt_pd(_mm_andnot_pd(sign, lead), tiny)),
                           sign);
            x = _mm_xor_pd(x, flip);
            y = _mm_xor_pd(y, flip);
            z = _mm_xor_pd(z, flip);
        }
        const __m128d c[3] = {x, y, z};
        __m128d k[3];
        for (int a = 0; a < 3; ++a) {
            const __m128d t = _mm_add_pd(_mm_mul_pd(c[a], scale), half);
            const __m128d r = _mm_sub_pd(_mm_add_pd(t, magic), magic);
            k[a] = _mm_sub_pd(r, _mm_and_pd(_mm_cmpgt_pd(r, t), one));
        }
        // Lane 1 is written to j's place (i's again for an odd count's last one, after
        // lane 0, which it equals).
        for (int a = 0; a < 3; ++a) {
            _mm_storel_pd(unit + 3 * i + a, c[a]);
            _mm_storel_pd(key + 3 * i + a, k[a]);
            _mm_storeh_pd(unit + 3 * j + a, c[a]);
            _mm_storeh_pd(key + 3 * j + a, k[a]);
        }
        valid[i] = static_cast<char>(ok & 1);
        valid[j] = static_cast<char>(ok >> 1);
    }
}
#else
// floor(x) for |x| < 2^62 as the library's floor gives it (an inline conversion where
// std::floor is a libm call on some targets).
inline long long floor_to_integer(double x) {
    const auto t = static_cast<long long>(x);  // truncation towards zero
    return t - (static_cast<double>(t) > x ? 1 : 0);
}

void unit_keys(const Vec3* d, size_t count, bool signed_classes, double* unit, double* key,
               char* valid) {
    for (size_t i = 0; i < count; ++i) {
        double x = d[i].x, y = d[i].y, z = d[i].z;
        const double len = std::sqrt(x * x + y * y + z * z);
        valid[i] = len > 0.0;
        x = x / len, y = y / len, z = z / len;
        if (!signed_classes) {
            // The first component clearly non-zero decides the sign.
            const double lead = std::fabs(x) > 1e-12 ? x : (std::fabs(y) > 1e-12 ? y : z);
            if (lead < 0.0 && std::fabs(lead) > 1e-12) x = -x, y = -y, z = -z;
        }
        unit[3 * i] = x, unit[3 * i + 1] = y, unit[3 * i + 2] = z;
        if (!valid[i]) continue;
        key[3 * i] = static_cast<double>(floor_to_integer(x * 1e12 + 0.5));
        key[3 * i + 1] = static_cast<double>(floor_to_integer(y * 1e12 + 0.5));
        key[3 * i + 2] = static_cast<double>(floor_to_integer(z * 1e12 + 0.5));
    }
}
#endif

// One direction per class of the `count` directions `d`, appended to `out`: unit, rounded to
// 12 digits for grouping; unsigned classes get a canonical sign (the first component clearly
// non-zero positive) (unit_keys). First occurrences kept, in input order (an open-addressing
// table of the rounded keys: linear in the count). Returns how many were appended.
std::int64_t unique_directions(const Vec3* d, size_t count, bool signed_classes, PackScratch& s,
                               std::vector<double>& out, std::int32_t* class_of = nullptr) {
    size_t size = 16;
    while (size < 4 * count) size *= 2;  // a quarter full at most: few probes collide
    // Stamped cells: the table is cleared by a new stamp, not rewritten, on every call.
    if (s.table.size() < size || ++s.stamp == 0) {
        s.table.assign(std::max(size, s.table.size()), DirectionCell{0, 0});
        s.stamp = 1;
    }
    size = s.table.size();
    const size_t mask = size - 1;
    const unsigned stamp = s.stamp;
    DirectionCell* table = s.table.data();
    if (s.unit.size() < 3 * count) {
        s.unit.resize(3 * count);
        s.keys.resize(3 * count);
        s.valid.resize(count);
    }
    unit_keys(d, count, signed_classes, s.unit.data(), s.keys.data(), s.valid.data());
    const double* keys = s.keys.data();
    // The kept unit vectors are compacted in place (kept <= i: nothing unread is written over;
    // with no repeat nor zero, nothing moves) and appended once (a resize of `out` would zero
    // its room first).
    double* unit = s.unit.data();
    std::int64_t kept = 0;
    for (size_t i = 0; i < count; ++i) {
        if (!s.valid[i]) {
            if (class_of != nullptr) class_of[i] = -1;
            continue;
        }
        const double* k = keys + 3 * i;
        std::uint64_t bits[3];
        std::memcpy(bits, k, sizeof bits);
        std::uint64_t hash = 1469598103934665603ull;
        hash = (hash ^ bits[0]) * 1099511628211ull;
        hash = (hash ^ bits[1]) * 1099511628211ull;
        hash = (hash ^ bits[2]) * 1099511628211ull;
        size_t slot = static_cast<size_t>(hash ^ (hash >> 29)) & mask;
        bool fresh = true;
        for (;; slot = (slot + 1) & mask) {
            DirectionCell& cell = table[slot];
            if (cell.stamp != stamp) {
                cell.stamp = stamp;
                cell.key = static_cast<std::int32_t>(i);
                break;
            }
            const double* seen = keys + 3 * static_cast<size_t>(cell.key);
            if (seen[0] == k[0] && seen[1] == k[1] && seen[2] == k[2]) {
                fresh = false;
                if (class_of != nullptr) class_of[i] = class_of[cell.key];
                break;
            }
        }
        if (!fresh) continue;
        if (class_of != nullptr) class_of[i] = static_cast<std::int32_t>(kept);
        if (static_cast<size_t>(kept) != i) {
            const double* u = unit + 3 * i;
            double* o = unit + 3 * kept;
            o[0] = u[0], o[1] = u[1], o[2] = u[2];
        }
        ++kept;
    }
    out.insert(out.end(), unit, unit + 3 * kept);
    return kept;
}

}  // namespace

namespace hull_detail {
std::vector<double> unique_directions_of(const Vec3* d, size_t count, bool signed_classes) {
    PackScratch s;
    std::vector<double> out;
    unique_directions(d, count, signed_classes, s, out);
    return out;
}
}  // namespace hull_detail

namespace {

// A block of four neighbour indices as the entries of a climb list at `to` (unaligned), in
// SSE2 lanes where four scalar stores took their addresses too: 8-bit entries (each in
// [0, 256)) by two saturating packs, exact in that range; 16-bit ones (each in [0, 65536))
// biased by 2^15 into the signed pack's range and back.
inline void narrow_block(const std::int32_t* from, std::uint8_t* to) {
#if defined(__SSE2__)
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(from));
    const __m128i words = _mm_packs_epi32(v, v);
    const int bytes = _mm_cvtsi128_si32(_mm_packus_epi16(words, words));
    std::memcpy(to, &bytes, 4);
#else
    for (int l = 0; l < 4; ++l) to[l] = static_cast<std::uint8_t>(from[l]);
#endif
}

inline void narrow_block(const std::int32_t* from, std::uint16_t* to) {
#if defined(__SSE2__)
    const __m128i v = _mm_sub_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(from)),
                                    _mm_set1_epi32(0x8000));
    const __m128i packed = _mm_xor_si128(_mm_packs_epi32(v, v), _mm_set1_epi32(0x80008000));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(to), packed);
#else
    for (int l = 0; l < 4; ++l) to[l] = static_cast<std::uint16_t>(from[l]);
#endif
}

// A padded CSR list (`count` a multiple of four, as the packing pads them, at most
// kClimbListSlots) as the `Record` at `at` (zeroed rows: its unused slots stay zero), four
// entries at a time.
template <class Record>
inline void write_climb_list(const std::int32_t* from, std::int64_t count, ClimbList* at) {
    Record& record = *reinterpret_cast<Record*>(at);
    record.count = static_cast<decltype(Record::count)>(count);
    for (std::int64_t k = 0; k < count; k += 4) narrow_block(from + k, record.neighbours + k);
}

// adjacency_from_edges for at most 64 vertices: each vertex's neighbours as a bit mask,
// read out lowest bit first (ascending), then padded. The same lists when every edge is listed
// once (a triangulation's edges are); false, with nothing appended, when an edge repeats (the
// lists would then hold it twice). With `kLists`, each list also to its `record` (shapes.hpp:
// `ClimbList`, zeroed) in the same pass.
template <bool kLists>
void write_mask_lists(size_t n, const std::uint64_t* mask, const std::int64_t* counts,
                      std::int32_t* list, ClimbList* record) {
    for (size_t i = 0; i < n; ++i) {
        std::int32_t* const end = list + counts[i];
        ClimbIndex* slot = nullptr;
        if constexpr (kLists) {
            record[i].count = static_cast<ClimbIndex>(counts[i]);
            slot = record[i].neighbours;
        }
        // The padding (fewer than four) first, as the list's last block whole: the neighbours
        // then overwrite the part of it they fill (no loop whose length follows the degree).
        if (counts[i] != 0) {
            const auto self = static_cast<std::int32_t>(i);
            end[-4] = self, end[-3] = self, end[-2] = self, end[-1] = self;
            if constexpr (kLists) {
                ClimbIndex* const last = slot + counts[i];
                const auto self8 = static_cast<ClimbIndex>(i);
                last[-4] = self8, last[-3] = self8, last[-2] = self8, last[-1] = self8;
            }
        }
        // Each neighbour to both lists (a second pass over the list, four at a time in SSE2
        // lanes, took more instructions).
        for (std::uint64_t m = mask[i]; m != 0; m &= m - 1) {
            const auto j = __builtin_ctzll(m);
            *list++ = static_cast<std::int32_t>(j);
            if constexpr (kLists) *slot++ = static_cast<ClimbIndex>(j);
        }
        list = end;
    }
}

bool adjacency_from_masks(int count, PackScratch& s, ChunkPack& out) {
    const auto n = static_cast<size_t>(count);
    std::uint64_t mask[64];
    int degree[64];
    std::fill(mask, mask + n, std::uint64_t{0});
    std::fill(degree, degree + n, 0);
    std::uint64_t repeated = 0;  // a bit already set: the edge came before
    for (const auto& [a, b] : s.pairs) {
        repeated |= mask[a] >> b;
        mask[a] |= std::uint64_t{1} << b;
        mask[b] |= std::uint64_t{1} << a;
        ++degree[a], ++degree[b];
    }
    if (repeated & 1) return false;
    // Each list's padded length, written through a pointer (a push_back a vertex checked the
    // capacity every time: 1.4k instructions a 64-vertex hull).
    const size_t counts_first = out.adjacency_counts.size();
    out.adjacency_counts.resize(counts_first + n);
    std::int64_t* counts = out.adjacency_counts.data() + counts_first;
    size_t padded_total = 0;
    std::int64_t longest = 0;
    for (size_t i = 0; i < n; ++i) {
        counts[i] = (degree[i] + 3) / 4 * 4;
        padded_total += static_cast<size_t>(counts[i]);
        longest = std::max(longest, counts[i]);
    }
    const size_t first = out.adjacency.size();
    out.adjacency.resize(first + padded_total);
    std::int32_t* list = out.adjacency.data() + first;
    // The climb lists too, in the same pass, when the shape keeps them.
    if (keeps_climb_lists(count, longest)) {
        const size_t lists_first = out.climb_lists.size();
        out.climb_lists.resize(lists_first + n);  // zeroed: the unused slots
        write_mask_lists<true>(n, mask, counts, list, out.climb_lists.data() + lists_first);
        s.climb_written = count;
    } else {
        write_mask_lists<false>(n, mask, counts, list, nullptr);
        s.climb_written = 0;
    }
    return true;
}

// Neighbour lists of `count` vertices from undirected edges, ascending, padded with the
// vertex itself to a multiple of four (the climb's blocks: see climb.hpp), appended. Two
// counting passes, no comparisons (a sort per list mispredicted a branch per shift): the
// edges bucketed by one end give each vertex's neighbours; walking the vertices in order
// and appending each to its neighbours' lists leaves every list ascending.
void adjacency_from_edges(int count, PackScratch& s, ChunkPack& out) {
    if (count <= 64 && adjacency_from_masks(count, s, out)) return;
    const auto n = static_cast<size_t>(count);
    std::vector<std::int64_t>& start = s.start;
    start.assign(n + 1, 0);
    for (const auto& [a, b] : s.pairs) ++start[a + 1], ++start[b + 1];
    for (size_t i = 0; i < n; ++i) start[i + 1] += start[i];
    // Each vertex's neighbours, unordered, at start[v] .. start[v + 1].
    std::vector<std::int32_t>& around = s.around;
    around.resize(static_cast<size_t>(start[n]));
    std::vector<std::int64_t>& fill = s.fill;
    fill.assign(start.begin(), start.end() - 1);
    for (const auto& [a, b] : s.pairs) around[fill[b]++] = a, around[fill[a]++] = b;
    // Each list padded to a multiple of four: room for the padding first.
    const size_t first = out.adjacency.size();
    const size_t counts_first = out.adjacency_counts.size();
    out.adjacency_counts.resize(counts_first + n);
    std::int64_t* counts = out.adjacency_counts.data() + counts_first;
    std::int64_t at = static_cast<std::int64_t>(first);
    for (size_t i = 0; i < n; ++i) {
        counts[i] = (start[i + 1] - start[i] + 3) / 4 * 4;
        fill[i] = at;
        at += counts[i];
    }
    out.adjacency.resize(static_cast<size_t>(at));
    std::int32_t* list = out.adjacency.data();
    for (size_t v = 0; v < n; ++v)
        for (std::int64_t k = start[v]; k < start[v + 1]; ++k)
            list[fill[around[k]]++] = static_cast<std::int32_t>(v);
    at = static_cast<std::int64_t>(first);
    for (size_t i = 0; i < n; ++i) {
        for (std::int64_t k = fill[i]; k < at + counts[i]; ++k) list[k] = static_cast<std::int32_t>(i);
        at += counts[i];
    }
}

// The climb lists (shapes.hpp: `ClimbList`) of a shape of `count` vertices whose CSR lists
// were just appended (from `counts_first` in `out.adjacency_counts`, `first` in
// `out.adjacency`), while they are in the cache: what `make_climb_lists` makes of them, byte
// for byte (the indices are in range by construction). Appends its count of rows (0, or
// `count` times `climb_rows(count)`) to `out.climb_counts`: none for a shape that keeps none
// (`keeps_climb_lists`).
void append_climb_lists(int count, size_t counts_first, size_t first, ChunkPack& out) {
    // The vertex count first (most shapes do not climb), then the lists' lengths.
    if (!keeps_climb_lists(count, 0)) {
        out.climb_counts.push_back(0);
        return;
    }
    const auto n = static_cast<size_t>(count);
    const std::int64_t* counts = out.adjacency_counts.data() + counts_first;
    std::int64_t longest = 0;
    for (size_t i = 0; i < n; ++i) longest = std::max(longest, counts[i]);
    if (!keeps_climb_lists(count, longest)) {
        out.climb_counts.push_back(0);
        return;
    }
    const auto rows = static_cast<size_t>(climb_rows(count));
    const size_t lists_first = out.climb_lists.size();
    // Zeroed: the unused slots as make_climb_lists leaves them.
    out.climb_lists.resize(lists_first + rows * n);
    ClimbList* list = out.climb_lists.data() + lists_first;
    const std::int32_t* from = out.adjacency.data() + first;
    for (size_t i = 0; i < n; ++i) {
        if (rows == 1)
            write_climb_list<ClimbList>(from, counts[i], list + i);
        else
            write_climb_list<WideClimbList>(from, counts[i], list + 2 * i);
        from += counts[i];
    }
    out.climb_counts.push_back(static_cast<std::int64_t>(rows * n));
}

void pack_one(const Vec3* points, long long n, Workspace& w, Analysis& analysis,
              PackScratch& s, ChunkPack& out) {
    hull_with(points, n, w, analysis);
    const Hull& hull = analysis.hull;
    const Triangulation& t = analysis.t;
    const Planes& pl = analysis.pl;
    out.status.push_back(hull.status);
    const size_t vertices_before = out.vertices.size();
    std::int64_t faces = 0;
    const size_t edges_before = out.edges.size();
    const size_t adjacency_counts_before = out.adjacency_counts.size();
    const size_t adjacency_before = out.adjacency.size();
    s.pairs.clear();
    s.climb_written = -1;
    const Vec3 zero{0.0, 0.0, 0.0};
    const int k = static_cast<int>(hull.vertices.size());
    if (hull.dimension < 0) {
        // Kept as given: the core reports INVALID_INPUT for every pair that uses it.
        for (long long i = 0; i < n; ++i) push(out.vertices, points[i]);
        out.adjacency_counts.resize(out.adjacency_counts.size() +
                                    static_cast<size_t>(std::max<long long>(n, 0)), 0);
    } else {
        const size_t coordinates = 3 * static_cast<size_t>(k);
        if (s.unique.size() < coordinates) s.unique.resize(coordinates);
        double* const first = s.unique.data();
        double* o = first;
        for (int v : hull.vertices) {
            const Vec3 q = points[v] + zero;  // -0.0 as 0.0
            o[0] = q.x, o[1] = q.y, o[2] = q.z;
            o += 3;
        }
        out.vertices.insert(out.vertices.end(), first, o);
    }
    if (hull.dimension == 0) {
        out.adjacency_counts.push_back(0);
    } else if (hull.dimension == 1) {
        s.pairs.emplace_back(0, 1);
        adjacency_from_edges(2, s, out);
        out.edges.insert(out.edges.end(), {0, 1});
    } else if (hull.dimension == 2) {
        for (int i = 0; i < k; ++i) s.pairs.emplace_back(i, (i + 1) % k);
        adjacency_from_edges(k, s, out);
        for (const auto& [a, b] : s.pairs) out.edges.insert(out.edges.end(), {a, b});
        push(out.faces, hull.normal);
        push(out.faces, -hull.normal);
        faces = 2;
    } else if (hull.dimension == 3) {
        // Every triangulation edge drives hill climbing; edges between different planes
        // are the polytope's true edges (SAT).
        // Each edge once (from its lower triangle: the triangulation's list).
        s.pairs.resize(t.edges.size());
        out.edges.resize(edges_before + 2 * t.edges.size());
        std::int32_t* e = out.edges.data() + edges_before;
        const int* local = w.local.data();  // hull_with's vertex index of each point
        size_t kept = 0;
        for (size_t g = 0; g < t.edges.size(); ++g) {
            const TriangulationEdge& edge = t.edges[g];
            const auto& tri = t.tri[edge.i];
            const int a = local[tri[edge.e]], b = local[tri[kNextCorner[edge.e]]];
            s.pairs[g] = {a, b};
            e[2 * kept] = a, e[2 * kept + 1] = b;
            kept += pl.group[edge.i] != pl.group[edge.j];  // no branch: no pattern
        }
        out.edges.resize(edges_before + 2 * kept);
        adjacency_from_edges(k, s, out);
        const bool own_planes = pl.groups == static_cast<int>(t.tri.size());
        const std::vector<Vec3>& normals = own_planes ? t.normal : hull.plane_normals;
        faces = unique_directions(normals.data(), normals.size(), true, s, out.faces);
    }
    const auto vertex_count = static_cast<std::int64_t>(out.vertices.size() - vertices_before) / 3;
    if (s.climb_written >= 0)
        out.climb_counts.push_back(s.climb_written);
    else
        append_climb_lists(static_cast<int>(std::min<std::int64_t>(vertex_count, INT_MAX)),
                           adjacency_counts_before, adjacency_before, out);
    out.vertex_counts.push_back(vertex_count);
    out.face_counts.push_back(faces);
    out.edge_counts.push_back(static_cast<std::int64_t>(out.edges.size() - edges_before) / 2);
}

// One thread's packing of consecutive shapes: the scratch of every hull, kept across them.
struct Packer {
    const Vec3* points;
    const std::int64_t* offsets;
    Workspace w;
    Analysis analysis;
    PackScratch scratch;

    Packer(const Vec3* p, const std::int64_t* o) : points(p), offsets(o) {
        analysis.geometry = false;  // the per-face geometry of a Hull is not packed
    }

    void pack(long long first, long long last, ChunkPack& out) {
        for (long long h = first; h < last; ++h) {
            pack_one(points + offsets[h], offsets[h + 1] - offsets[h], w, analysis, scratch, out);
            out.prefault_ahead();
        }
    }
};

// The points a packing reserves room for: every point of shapes up to 4,096 points (a smooth
// hull keeps them all), at least 2^20 in all for larger ones (mostly interior points: their
// arrays grow as they fill instead), never more than there are, nor than 2^24 (about 3 GB of
// address space: past it the arrays grow as they fill).
long long points_to_reserve(const std::int64_t* offsets, long long first, long long last) {
    constexpr long long kAllPointsUpTo = 4096, kAtLeast = 1 << 20, kAtMost = 1 << 24;
    long long small = 0;
    for (long long h = first; h < last; ++h)
        small += std::min<long long>(offsets[h + 1] - offsets[h], kAllPointsUpTo);
    const long long room = std::max(std::min(small, kAtMost), kAtLeast);
    return std::min<long long>(offsets[last] - offsets[first], room);
}

// The running sums of `counts` after offsets' last one (offsets holds at least its 0).
void append_offsets(const std::vector<std::int64_t>& counts, std::vector<std::int64_t>& offsets) {
    const size_t first = offsets.size();
    offsets.resize(first + counts.size());
    std::int64_t* o = offsets.data() + first;
    std::int64_t sum = o[-1];
    for (size_t k = 0; k < counts.size(); ++k) o[k] = sum += counts[k];
}

// The result of many chunks, filled in chunk order as they finish: a chunk's arrays are
// copied in while they are still in the cache, and its buffers then pack the next chunk, so
// the packing touches fresh memory once, for the result. (Packing every chunk into arrays of
// its own and joining them at the end touched twice as much: each page costs a fault, about
// a third of the time of 40,000 small hulls.)
//
// A finished chunk is parked, and one thread at a time (the committer) copies the parked
// chunks that come next in order, outside the lock. The copies fault the result's fresh
// pages: about a fifth of the packing's CPU at 64 points a shape. A thread that finishes a
// chunk while another copies parks it and packs on instead of waiting for the copy (under
// one lock for both, that wait kept a core idle).
class OrderedCommits {
public:
    OrderedCommits(PackedPolytopes& out, long long chunks)
        : out_(out), parked_(static_cast<size_t>(chunks)) {}

    /// Chunk c's arrays, packed into `pack`: parked, then committed with the parked chunks
    /// after it by this thread unless another is committing (which then commits them).
    /// Returns empty buffers to pack the next chunk into.
    std::unique_ptr<ChunkPack> finish(long long c, std::unique_ptr<ChunkPack> pack) {
        std::unique_lock<std::mutex> hold(lock_);
        parked_[static_cast<size_t>(c)] = std::move(pack);
        if (committing_) return take_spare();
        committing_ = true;
        for (;;) {
            std::unique_ptr<ChunkPack> ready;
            if (next_ < static_cast<long long>(parked_.size()))
                ready = std::move(parked_[static_cast<size_t>(next_)]);
            if (!ready) break;
            ++next_;
            hold.unlock();  // only the committer touches the result
            append(*ready);
            hold.lock();
            spare_.push_back(std::move(ready));
        }
        committing_ = false;
        return take_spare();
    }

    /// Buffers a thread no longer needs, for another to reuse.
    void give_back(std::unique_ptr<ChunkPack> pack) {
        const std::lock_guard<std::mutex> hold(lock_);
        spare_.push_back(std::move(pack));
    }

    std::unique_ptr<ChunkPack> take() {
        const std::lock_guard<std::mutex> hold(lock_);
        return take_spare();
    }

private:
    std::unique_ptr<ChunkPack> take_spare() {
        if (spare_.empty()) return std::make_unique<ChunkPack>();
        std::unique_ptr<ChunkPack> pack = std::move(spare_.back());
        spare_.pop_back();
        return pack;
    }

    void append(ChunkPack& s) {
        PackedPolytopes& o = out_;
        // The result's room for this chunk prefaulted in a call an array (prefault).
        prefault(o.vertices, o.vertices.size(), o.vertices.size() + s.vertices.size());
        prefault(o.adjacency_offsets, o.adjacency_offsets.size(),
                 o.adjacency_offsets.size() + s.adjacency_counts.size());
        prefault(o.adjacency, o.adjacency.size(), o.adjacency.size() + s.adjacency.size());
        prefault(o.face_normals, o.face_normals.size(), o.face_normals.size() + s.faces.size());
        prefault(o.edge_pairs, o.edge_pairs.size(), o.edge_pairs.size() + s.edges.size());
        prefault(o.climb_lists, o.climb_lists.size(), o.climb_lists.size() + s.climb_lists.size());
        o.status.insert(o.status.end(), s.status.begin(), s.status.end());
        append_offsets(s.vertex_counts, o.offsets);
        append_offsets(s.face_counts, o.face_offsets);
        append_offsets(s.edge_counts, o.edge_pair_offsets);
        append_offsets(s.adjacency_counts, o.adjacency_offsets);
        append_offsets(s.climb_counts, o.climb_list_offsets);
        o.vertices.insert(o.vertices.end(), s.vertices.begin(), s.vertices.end());
        o.adjacency.insert(o.adjacency.end(), s.adjacency.begin(), s.adjacency.end());
        o.face_normals.insert(o.face_normals.end(), s.faces.begin(), s.faces.end());
        o.edge_pairs.insert(o.edge_pairs.end(), s.edges.begin(), s.edges.end());
        o.climb_lists.insert(o.climb_lists.end(), s.climb_lists.begin(), s.climb_lists.end());
        s.clear();
    }

    PackedPolytopes& out_;
    std::mutex lock_;
    bool committing_ = false;  // a thread is copying parked chunks into the result
    long long next_ = 0;       // the first chunk not yet committed
    std::vector<std::unique_ptr<ChunkPack>> parked_;  // by chunk
    std::vector<std::unique_ptr<ChunkPack>> spare_;
};

}  // namespace

PackedPolytopes pack_polytopes(const Vec3* points, const std::int64_t* offsets, long long shapes,
                               int threads) {
    shapes = std::max<long long>(shapes, 0);
    const int t = resolve_threads(threads, shapes, defaults::hull_min_shapes_per_thread);
    PackedPolytopes out;
    const auto hs = static_cast<size_t>(shapes);
    // On threads: chunks of consecutive shapes of about kChunkPoints points (their arrays stay
    // in the cache until they are committed), and about 8 a thread (handed out dynamically).
    // The result never depends on the chunks or the threads: their arrays are joined in order.
    // At 64 points a shape a chunk's arrays are about 0.55 MB (2.2 MB at 2^14 points, more than
    // a core's L2 with the result's room zeroed beside them: 2-4% more CPU, session 32).
    constexpr long long kChunkPoints = 1 << 12;
    const long long total = shapes > 0 ? offsets[shapes] - offsets[0] : 0;
    const long long per_shape = std::max<long long>(1, total / std::max<long long>(shapes, 1));
    const long long chunk = std::min(std::max<long long>(1, kChunkPoints / per_shape),
                                     std::max<long long>(1, (shapes + 8LL * t - 1) / (8LL * t)));
    const long long chunks = shapes > 0 ? (shapes + chunk - 1) / chunk : 0;
    if (t <= 1 || chunks <= 1) {
        // One thread, or one chunk: the shapes are packed straight into the arrays that become
        // the result, never copied (and, reserved by points_to_reserve, never moved by shapes
        // of up to 4,096 points).
        ChunkPack pack;
        if (shapes > 0) {
            pack.reserve(shapes, points_to_reserve(offsets, 0, shapes));
            Packer(points, offsets).pack(0, shapes, pack);
        }
        out.offsets.assign(1, 0);
        out.face_offsets.assign(1, 0);
        out.edge_pair_offsets.assign(1, 0);
        out.adjacency_offsets.assign(1, 0);
        out.climb_list_offsets.assign(1, 0);
        append_offsets(pack.vertex_counts, out.offsets);
        append_offsets(pack.face_counts, out.face_offsets);
        append_offsets(pack.edge_counts, out.edge_pair_offsets);
        append_offsets(pack.adjacency_counts, out.adjacency_offsets);
        append_offsets(pack.climb_counts, out.climb_list_offsets);
        out.status = std::move(pack.status);
        out.vertices = std::move(pack.vertices);
        out.adjacency = std::move(pack.adjacency);
        out.face_normals = std::move(pack.faces);
        out.edge_pairs = std::move(pack.edges);
        out.climb_lists = std::move(pack.climb_lists);
        return out;
    }
    // Room for the whole result, so that it never moves while chunks are copied in.
    const auto p = static_cast<size_t>(points_to_reserve(offsets, 0, shapes));
    out.status.reserve(hs);
    out.offsets.reserve(hs + 1);
    out.face_offsets.reserve(hs + 1);
    out.edge_pair_offsets.reserve(hs + 1);
    out.vertices.reserve(3 * p);
    out.adjacency_offsets.reserve(p + 1);
    out.adjacency.reserve(6 * p + 3 * p + 4 * hs);
    out.face_normals.reserve(3 * (2 * p + 2 * hs));
    out.edge_pairs.reserve(2 * (3 * p + hs));
    out.climb_list_offsets.reserve(hs + 1);
    out.climb_lists.reserve(p);
    out.offsets.push_back(0);
    out.face_offsets.push_back(0);
    out.edge_pair_offsets.push_back(0);
    out.adjacency_offsets.push_back(0);
    out.climb_list_offsets.push_back(0);
    OrderedCommits commits(out, chunks);
    // One packer a thread, which claims the chunks one at a time: the threads finish within
    // a chunk of each other (parallel_for's own blocks of chunks, 9 of 157 at 40,000 shapes of
    // 64 points, left one thread packing alone for up to 9 chunks at the end).
    std::atomic<long long> next_chunk{0};
    parallel_for(t, t, [&](long long, long long) {
        Packer packer(points, offsets);
        std::unique_ptr<ChunkPack> pack = commits.take();
        for (long long c = next_chunk++; c < chunks; c = next_chunk++) {
            const long long first = c * chunk, last = std::min(shapes, (c + 1) * chunk);
            pack->reserve(last - first, points_to_reserve(offsets, first, last));
            packer.pack(first, last, *pack);
            pack = commits.finish(c, std::move(pack));
        }
        commits.give_back(std::move(pack));
    });
    return out;
}

namespace {

// The directions of `count` true edges, vertices[to] - vertices[from], into s.directions.
void edge_vectors(const Vec3* vertices, const std::int32_t* pairs, size_t count, PackScratch& s) {
    s.directions.resize(count);
    for (size_t i = 0; i < count; ++i)
        s.directions[i] = vertices[pairs[2 * i + 1]] - vertices[pairs[2 * i]];
}

// Each thread's scratch for the classes SAT computes one shape at a time (its table and
// buffers are kept, as the packing keeps them across a chunk's shapes).
PackScratch& class_scratch() {
    thread_local PackScratch s;
    return s;
}

}  // namespace

std::int64_t edge_direction_classes(const Vec3* vertices, const std::int32_t* pairs,
                                    size_t count, std::vector<double>& out,
                                    std::int32_t* class_of) {
    PackScratch& s = class_scratch();
    edge_vectors(vertices, pairs, count, s);
    return unique_directions(s.directions.data(), count, false, s, out, class_of);
}

std::int64_t edge_direction_class_count(const Vec3* vertices, const std::int32_t* pairs,
                                        size_t count) {
    PackScratch& s = class_scratch();
    edge_vectors(vertices, pairs, count, s);
    s.classes.clear();
    return unique_directions(s.directions.data(), count, false, s, s.classes);
}

}  // namespace meshcol
