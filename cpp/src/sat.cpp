#include "meshcol/sat.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "meshcol/defaults.hpp"

namespace meshcol {

namespace {

const Vec3 kBoxFaces[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
const Vec3 kBoxEdges[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

struct Features {
    const Vec3* faces;
    int face_count;
    const Vec3* edges;
    int edge_count;
    int vertices;  // support cost
};

Features features_of(const ShapeView& s) {
    if (s.kind == ShapeKind::BOX) return {kBoxFaces, 6, kBoxEdges, 3, 1};
    return {s.face_normals, s.face_count, s.edge_directions, s.edge_count, s.vertex_count};
}

// A point of the shape's own frame to measure an inner ball from (the middle of its vertices'
// bounds; a box's centre), and the largest |coordinate| of its vertices (the scale of the
// rounding in its support values).
void middle_and_reach(const ShapeView& s, Vec3& middle, double& reach) {
    if (s.kind == ShapeKind::BOX) {
        middle = Vec3{};
        reach = std::fmax(std::fabs(s.params[0]), std::fmax(std::fabs(s.params[1]), std::fabs(s.params[2])));
        return;
    }
    Vec3 lo = s.vertices[0], hi = s.vertices[0];
    for (int i = 1; i < s.vertex_count; ++i) {
        lo = component_min(lo, s.vertices[i]);
        hi = component_max(hi, s.vertices[i]);
    }
    middle = (lo + hi) * 0.5;
    reach = std::fmax(std::fmax(std::fabs(lo.x), std::fabs(hi.x)),
                      std::fmax(std::fmax(std::fabs(lo.y), std::fabs(hi.y)),
                                std::fmax(std::fabs(lo.z), std::fabs(hi.z))));
}

// The index of the lowest set bit of a non-zero word.
int lowest_bit(std::uint64_t word) {
    int i = 0;
    while ((word & 1) == 0) {
        word >>= 1;
        ++i;
    }
    return i;
}

// SAT's work on shapes of these features with `ea` and `eb` edge classes: (candidate axes) x
// (vertices of both), what max_work bounds.
long long work(const Features& fa, long long ea, const Features& fb, long long eb) {
    const long long axes = static_cast<long long>(fa.face_count) + fb.face_count + 2LL * ea * eb;
    return axes * (fa.vertices + fb.vertices);
}

}  // namespace

bool has_sat_features(const ShapeView& s) {
    // A polytope's features are attached by the caller; a point has none and needs none.
    return s.kind == ShapeKind::BOX ||
           (s.kind == ShapeKind::POLYTOPE && (s.has_features || s.vertex_count == 1));
}

bool gauss_arcs(const Vec3* vertices, int vertex_count, const Vec3* face_normals, int face_count,
                const std::int32_t* pairs, const std::int32_t* class_of, size_t count,
                std::vector<GaussArc>& out) {
    // The faces through each vertex as the bits of a word (an edge's faces are then those of
    // both its ends). Beyond 64 faces, no arcs: SAT's work bound lets such a shape meet only
    // shapes of few edges, where the plain loop is cheap.
    if (vertex_count <= 0 || face_count <= 0 || face_count > 64 ||
        vertex_count > std::numeric_limits<std::int16_t>::max())
        return false;
    double reach = 0.0;
    for (int v = 0; v < vertex_count; ++v)
        reach = std::max({reach, std::fabs(vertices[v].x), std::fabs(vertices[v].y),
                          std::fabs(vertices[v].z)});
    const double tolerance = defaults::sat_arc_plane_tolerance * reach;
    if (!(tolerance > 0.0) || !std::isfinite(tolerance)) return false;
    std::vector<std::uint64_t> faces_of(static_cast<size_t>(vertex_count), 0);
    std::vector<double> heights(static_cast<size_t>(vertex_count));
    for (int f = 0; f < face_count; ++f) {
        double top = -std::numeric_limits<double>::infinity();
        for (int v = 0; v < vertex_count; ++v) {
            heights[v] = dot(face_normals[f], vertices[v]);
            top = std::max(top, heights[v]);
        }
        const std::uint64_t bit = std::uint64_t{1} << f;
        for (int v = 0; v < vertex_count; ++v)
            if (heights[v] >= top - tolerance) faces_of[v] |= bit;
    }
    const size_t kept = out.size();
    out.reserve(kept + count);
    for (size_t e = 0; e < count; ++e) {
        std::uint64_t both = faces_of[pairs[2 * e]] & faces_of[pairs[2 * e + 1]];
        // Exactly two bits: clearing the lowest leaves one.
        const std::uint64_t rest = both & (both - 1);
        if (both == 0 || rest == 0 || (rest & (rest - 1)) != 0 || class_of[e] < 0 ||
            class_of[e] > std::numeric_limits<std::int16_t>::max()) {
            out.resize(kept);
            return false;
        }
        GaussArc arc;
        arc.face_a = static_cast<std::int16_t>(lowest_bit(both));
        arc.face_b = static_cast<std::int16_t>(lowest_bit(rest));
        arc.vertex = static_cast<std::int16_t>(pairs[2 * e]);
        arc.direction_class = static_cast<std::int16_t>(class_of[e]);
        out.push_back(arc);
    }
    return true;
}

namespace {

#if defined(__SSE2__)
// The dots of entries k and k + 1 of columns x, y, z with (nx, ny, nz), rounded as `dot`
// rounds them (x, plus y, plus z).
inline __m128d lane_dots(const double* x, const double* y, const double* z, int k, __m128d nx,
                         __m128d ny, __m128d nz) {
    return _mm_add_pd(
        _mm_add_pd(_mm_mul_pd(_mm_load_pd(x + k), nx), _mm_mul_pd(_mm_load_pd(y + k), ny)),
        _mm_mul_pd(_mm_load_pd(z + k), nz));
}

// The two lanes of x or'ed.
inline std::uint64_t lanes_or(__m128i x) {
    return static_cast<std::uint64_t>(_mm_cvtsi128_si64(_mm_or_si128(x, _mm_unpackhi_epi64(x, x))));
}
#endif

// `crossing_classes`' answer, kept by each thread.
struct CrossingScratch {
    std::vector<int> found;
};

// The circle of an arc of shape s (its own frame): n_b x n_a, as the arc's two faces give it.
Vec3 arc_circle(const ShapeView& s, const GaussArc& arc) {
    return cross(s.face_normals[arc.face_b], s.face_normals[arc.face_a]);
}

// The axes of class pairs whose edges' arcs cross on the Gauss maps of a and of -b (in a's
// frame), or nearly: the axes that may be face normals of the Minkowski difference a - b
// (Gregorius, "The Separating Axis Test between convex polyhedra", GDC 2013). Each as
// 2 (i * (b's class count) + j) for the axis `Overlaps::edge_axis` of classes i and j, plus 1
// for its opposite: ascending (the plain loop's order), each once. Arcs AB (of a) and CD (of
// -b) cross when C and D lie on opposite sides of AB's great circle, A and B on opposite
// sides of CD's, and the crossing is on the near side (CBA and BDC of one sign). A sign test
// decides only beyond `sat_arc_crossing_margin`.
//
// Every sign is that of a face normal against a circle, so the tests are taken as sets:
// the faces of -b against each circle of a (bits over a's arcs, for each face of b), and the
// faces of a against each circle of -b (turned into bits over a's arcs through the arcs that
// end at each face). An arc of b then meets up to 64 arcs of a in a few word operations,
// without a branch an arc pair; the signs are those of the same products as a test of each
// pair would take, so the answer is the same.
//
// `keep(i, j, axis)` (classes i of a and j of b, their unnormalised axis) says which signs of
// a crossing are worth listing: bit 0 the axis, bit 1 its opposite.
template <class Keep>
const std::vector<int>& crossing_classes(const ShapeView& a, const ShapeView& b, const Mat3& rot,
                                         const Keep& keep) {
    // One lookup of the thread's scratch (in a shared library each names a call).
    thread_local CrossingScratch scratch;
    std::vector<int>& found = scratch.found;
    found.clear();
    // Both shapes have arcs, so at most 64 faces each (`gauss_arcs`); the counts padded to
    // even (two a lane), the padding's normals zero (no sign) and its arc sets empty.
    constexpr int kFaces = 64;
    const int faces_a = a.face_count, faces_b = b.face_count;
    const int padded_a = faces_a + (faces_a & 1), padded_b = faces_b + (faces_b & 1);
    alignas(16) double ax[kFaces], ay[kFaces], az[kFaces];  // a's normals
    alignas(16) double cx[kFaces], cy[kFaces], cz[kFaces];  // -b's normals, in a's frame
    for (int g = 0; g < padded_a; ++g) {
        const Vec3 n = g < faces_a ? a.face_normals[g] : Vec3{};
        ax[g] = n.x, ay[g] = n.y, az[g] = n.z;
    }
    for (int f = 0; f < padded_b; ++f) {
        const Vec3 c = f < faces_b ? -(rot * b.face_normals[f]) : Vec3{};
        cx[f] = c.x, cy[f] = c.y, cz[f] = c.z;
    }
    const double m = defaults::sat_arc_crossing_margin;
    // a's arcs 64 at a time: bit i of each set is the chunk's arc i.
    for (int first = 0; first < a.arc_count; first += 64) {
        const int arcs = std::min(a.arc_count - first, 64);
        const int padded = arcs + (arcs & 1);
        const std::uint64_t all = arcs == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << arcs) - 1;
        alignas(16) double qx[64], qy[64], qz[64];                // the arcs' circles
        alignas(16) std::uint64_t with_a[kFaces], with_b[kFaces];  // arcs from / to each face
        for (int g = 0; g < padded_a; ++g) with_a[g] = with_b[g] = 0;
        for (int i = 0; i < padded; ++i) {
            const Vec3 q = i < arcs ? arc_circle(a, a.arcs[first + i]) : Vec3{};
            qx[i] = q.x, qy[i] = q.y, qz[i] = q.z;
        }
        for (int i = 0; i < arcs; ++i) {
            with_a[a.arcs[first + i].face_a] |= std::uint64_t{1} << i;
            with_b[a.arcs[first + i].face_b] |= std::uint64_t{1} << i;
        }
        // Each face of -b against each circle of the chunk: above and below, bits over arcs.
        std::uint64_t above[kFaces], below[kFaces];
        for (int f = 0; f < faces_b; ++f) {
            std::uint64_t up = 0, down = 0;
#if defined(__SSE2__)
            const __m128d fx = _mm_set1_pd(cx[f]), fy = _mm_set1_pd(cy[f]), fz = _mm_set1_pd(cz[f]);
            const __m128d plus = _mm_set1_pd(m), minus = _mm_set1_pd(-m);
            __m128i bits = _mm_set_epi64x(2, 1), ups = _mm_setzero_si128(), downs = ups;
            for (int i = 0; i < padded; i += 2) {
                const __m128d t = lane_dots(qx, qy, qz, i, fx, fy, fz);  // c . q, as `dot(c, q)`
                const __m128i above_i = _mm_castpd_si128(_mm_cmpgt_pd(t, plus));
                const __m128i below_i = _mm_castpd_si128(_mm_cmplt_pd(t, minus));
                ups = _mm_or_si128(ups, _mm_and_si128(above_i, bits));
                downs = _mm_or_si128(downs, _mm_and_si128(below_i, bits));
                bits = _mm_slli_epi64(bits, 2);
            }
            up = lanes_or(ups);
            down = lanes_or(downs);
#else
            for (int i = 0; i < arcs; ++i) {
                const double t = cx[f] * qx[i] + cy[f] * qy[i] + cz[f] * qz[i];
                up |= static_cast<std::uint64_t>(t > m) << i;
                down |= static_cast<std::uint64_t>(t < -m) << i;
            }
#endif
            above[f] = up & all;
            below[f] = down & all;
        }
        for (int k = 0; k < b.arc_count; ++k) {
            const GaussArc& cd = b.arcs[k];
            const Vec3 circle = rot * arc_circle(b, cd);
            // a's faces against CD's circle, as the arcs of the chunk that start (A) or end
            // (B) at a face above or below it.
            std::uint64_t a_up = 0, a_down = 0, b_up = 0, b_down = 0;
#if defined(__SSE2__)
            const __m128d ux = _mm_set1_pd(circle.x), uy = _mm_set1_pd(circle.y);
            const __m128d uz = _mm_set1_pd(circle.z);
            const __m128d plus = _mm_set1_pd(m), minus = _mm_set1_pd(-m);
            __m128i au = _mm_setzero_si128(), ad = au, bu = au, bd = au;
            for (int g = 0; g < padded_a; g += 2) {
                const __m128d t = lane_dots(ax, ay, az, g, ux, uy, uz);
                const __m128i up = _mm_castpd_si128(_mm_cmpgt_pd(t, plus));
                const __m128i down = _mm_castpd_si128(_mm_cmplt_pd(t, minus));
                const __m128i from = _mm_load_si128(reinterpret_cast<const __m128i*>(with_a + g));
                const __m128i to = _mm_load_si128(reinterpret_cast<const __m128i*>(with_b + g));
                au = _mm_or_si128(au, _mm_and_si128(up, from));
                ad = _mm_or_si128(ad, _mm_and_si128(down, from));
                bu = _mm_or_si128(bu, _mm_and_si128(up, to));
                bd = _mm_or_si128(bd, _mm_and_si128(down, to));
            }
            a_up = lanes_or(au), a_down = lanes_or(ad), b_up = lanes_or(bu), b_down = lanes_or(bd);
#else
            for (int g = 0; g < faces_a; ++g) {
                const double t = ax[g] * circle.x + ay[g] * circle.y + az[g] * circle.z;
                const std::uint64_t up = t > m ? ~std::uint64_t{0} : 0;
                const std::uint64_t down = t < -m ? ~std::uint64_t{0} : 0;
                a_up |= up & with_a[g], a_down |= down & with_a[g];
                b_up |= up & with_b[g], b_down |= down & with_b[g];
            }
#endif
            const int c = cd.face_a, d = cd.face_b;
            // C and D on one side of AB's circle; A and B on one side of CD's; CBA and BDC
            // of opposite signs (CBA is C against AB's circle, BDC is B against CD's).
            const std::uint64_t same_cd = (above[c] & above[d]) | (below[c] & below[d]);
            const std::uint64_t same_ab = (a_up & b_up) | (a_down & b_down);
            const std::uint64_t far_side = (above[c] & b_down) | (below[c] & b_up);
            std::uint64_t crossing = all & ~(same_cd | same_ab | far_side);
            while (crossing != 0) {
                const int i = first + __builtin_ctzll(crossing);
                crossing &= crossing - 1;
                const GaussArc& ab = a.arcs[i];
                // The crossing is the axis of the two classes (`Overlaps::edge_axis`) or its
                // opposite: the one on AB's side, whose angle to the arc's ends is below pi.
                // Both when that is near a tie.
                const int pair = ab.direction_class * b.edge_count + cd.direction_class;
                const Vec3 axis = cross(a.edge_directions[ab.direction_class],
                                        rot * b.edge_directions[cd.direction_class]);
                const Vec3 middle = a.face_normals[ab.face_a] + a.face_normals[ab.face_b];
                const double side = dot(axis, middle), scale = m * norm(axis) * norm(middle);
                const int signs = ((side < -scale) ? 0 : 1) | ((side > scale) ? 0 : 2);
                const int wanted = signs & keep(ab.direction_class, cd.direction_class, axis);
                if (wanted & 1) found.push_back(2 * pair);
                if (wanted & 2) found.push_back(2 * pair + 1);
            }
        }
    }
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
    return found;
}

// `climb::scan_support` to the bit (the first vertex of the largest dot), with selects in
// place of branches: SAT's axes point anywhere, so which vertex leads is a coin toss that a
// branch predictor loses.
inline int first_max(const Vec3* v, int n, const Vec3& d) {
    int best = 0;
    double top = dot(v[0], d);
    for (int i = 1; i < n; ++i) {
        const double x = dot(v[i], d);
        const bool higher = x > top;
        top = higher ? x : top;
        best = higher ? i : best;
    }
    return best;
}

// The overlap of a and b along axes of a's frame, h_a(n) + h_b(-n), and the smallest so far:
// an axis replaces it only when strictly below, so the answer is the first smallest axis.
struct Overlaps {
    const ShapeView& a;
    const ShapeView& b;
    Mat3 rot;    // b's rotation in a's frame
    Vec3 trans;  // b's origin in a's frame
    bool scan_both;
    double best = std::numeric_limits<double>::infinity();
    Vec3 best_axis{1.0, 0.0, 0.0};
    Vec3 pa, pb_local;  // the supports of the last axis tested, pb_local in b's frame
    int axes = 0;

    Overlaps(const ShapeView& a_, const Pose& pose_a, const ShapeView& b_, const Pose& pose_b)
        : a(a_),
          b(b_),
          rot(pose_a.rotation.transposed() * pose_b.rotation),
          trans(pose_a.rotation.transpose_times(pose_b.translation - pose_a.translation)),
          // Two polytopes that scan their vertices scan them with selects (`first_max`, the
          // same supports as their support functions').
          scan_both(scans(a_) && scans(b_)) {}

    void test(const Vec3& n) { take(n, overlap_along(n)); }

    // An axis measured before (`overlap_along`), taken in its turn.
    void take(const Vec3& n, double overlap) {
        ++axes;
        if (overlap < best) {
            best = overlap;
            best_axis = n;
        }
    }

    // h_a(n) + h_b(-n), as `test` measures it (the supports kept in pa and pb_local).
    double overlap_along(const Vec3& n) {
        // b's support taken in b's frame.
        const Vec3 nb = rot.transpose_times(-n);
        if (scan_both) {
            pa = a.vertices[first_max(a.vertices, a.vertex_count, n)];
            pb_local = b.vertices[first_max(b.vertices, b.vertex_count, nb)];
        } else {
            pa = support_core(a, n).point;
            pb_local = support_core(b, nb).point;
        }
        const Vec3 pb = rot * pb_local + trans;
        return dot(n, pa) - dot(n, pb);
    }

    // The axis of edge directions e_a and e_b (b's frame), or false for parallel ones: they
    // span no face of their own, the face normals cover it.
    bool edge_axis(const Vec3& edge_a, const Vec3& edge_b, Vec3& n) const {
        const Vec3 c = cross(edge_a, rot * edge_b);
        const double len = norm(c);
        if (!(len > defaults::sat_parallel_edge_sine)) return false;
        n = c / len;
        return true;
    }

    SatResult result(const Pose& pose_a) const {
        SatResult res;
        res.axes = axes;
        if (!std::isfinite(best)) return res;
        res.ran = true;
        if (best < 0.0) {
            res.separated = true;
            res.depth = 0.0;
        } else {
            res.depth = best;
        }
        res.normal = pose_a.rotate(best_axis);
        return res;
    }
};

// The largest |coordinate| of a polytope's vertices.
double reach_of(const ShapeView& s) {
    // std::max from a number (never NaN) skips a NaN coordinate as std::fmax does, inline.
    double reach = 0.0;
    for (int i = 0; i < s.vertex_count; ++i) {
        reach = std::max(reach, std::fabs(s.vertices[i].x));
        reach = std::max(reach, std::fabs(s.vertices[i].y));
        reach = std::max(reach, std::fabs(s.vertices[i].z));
    }
    return reach;
}

// The rounding of an overlap of a and b (o's frame) that `NearOverlaps`' values allow for.
double near_slack(const ShapeView& a, const ShapeView& b, const Vec3& trans) {
    return 1e-12 * (reach_of(a) + reach_of(b) + norm(trans));
}

// The overlap along axes of a's frame as the largest of a's dots less the smallest of b's
// vertices moved to a's frame (as `Overlaps::overlap_along` moves its support point), two
// vertices a lane: a's part is the measured one (the same products, their maximum); b's
// smallest is at most the measured support point's (one of these vertices), which is chosen
// in b's frame and so is the smallest up to the rounding of the axis turned there and of the
// move, a few parts in 1e16 of the coordinates. So the measured overlap is at least this
// value less that rounding: an axis whose value is above the best by more than `slack`
// (1e-12 of the coordinates) would not replace it, and need not be measured. For two scanning
// polytopes of at most 64 vertices each, all finite.
struct NearOverlaps {
    static constexpr int kMaxVertices = 64;
    alignas(16) double ax[kMaxVertices], ay[kMaxVertices], az[kMaxVertices];
    alignas(16) double bx[kMaxVertices], by[kMaxVertices], bz[kMaxVertices];
    int padded_a = 0, padded_b = 0;

    // False (no values) unless both shapes scan, fit, and have finite coordinates and slack.
    bool fill(const Overlaps& o, double slack) {
        const ShapeView &a = o.a, &b = o.b;
        if (!o.scan_both || a.vertex_count > kMaxVertices || b.vertex_count > kMaxVertices ||
            !std::isfinite(slack))
            return false;
        // Odd counts padded with the last vertex again (no new maximum or minimum).
        padded_a = a.vertex_count + (a.vertex_count & 1);
        padded_b = b.vertex_count + (b.vertex_count & 1);
        double sum = 0.0;  // NaN or infinite when a coordinate is
        for (int i = 0; i < padded_a; ++i) {
            const Vec3& v = a.vertices[std::min(i, a.vertex_count - 1)];
            ax[i] = v.x, ay[i] = v.y, az[i] = v.z;
            sum += v.x + v.y + v.z;
        }
        for (int j = 0; j < padded_b; ++j) {
            const Vec3 w = o.rot * b.vertices[std::min(j, b.vertex_count - 1)] + o.trans;
            bx[j] = w.x, by[j] = w.y, bz[j] = w.z;
            sum += w.x + w.y + w.z;
        }
        return std::isfinite(sum * 0.0);
    }

    // The largest of a's dots along n.
    double high(const Vec3& n) const {
#if defined(__SSE2__)
        const __m128d nx = _mm_set1_pd(n.x), ny = _mm_set1_pd(n.y), nz = _mm_set1_pd(n.z);
        __m128d top = _mm_set1_pd(-std::numeric_limits<double>::infinity());
        for (int i = 0; i < padded_a; i += 2)
            top = _mm_max_pd(top, lane_dots(ax, ay, az, i, nx, ny, nz));
        return _mm_cvtsd_f64(_mm_max_pd(top, _mm_shuffle_pd(top, top, 1)));
#else
        double top = -std::numeric_limits<double>::infinity();
        for (int i = 0; i < padded_a; ++i) top = std::max(top, dot_a(n, i));
        return top;
#endif
    }

    // The smallest of b's moved vertices' dots along n.
    double low(const Vec3& n) const {
#if defined(__SSE2__)
        const __m128d nx = _mm_set1_pd(n.x), ny = _mm_set1_pd(n.y), nz = _mm_set1_pd(n.z);
        __m128d bottom = _mm_set1_pd(std::numeric_limits<double>::infinity());
        for (int j = 0; j < padded_b; j += 2)
            bottom = _mm_min_pd(bottom, lane_dots(bx, by, bz, j, nx, ny, nz));
        return _mm_cvtsd_f64(_mm_min_pd(bottom, _mm_shuffle_pd(bottom, bottom, 1)));
#else
        double bottom = std::numeric_limits<double>::infinity();
        for (int j = 0; j < padded_b; ++j) bottom = std::min(bottom, dot_b(n, j));
        return bottom;
#endif
    }

    double operator()(const Vec3& n) const { return high(n) - low(n); }

    // One vertex's dot: of a's vertex i, of b's moved vertex j. A vertex of a (on a face, at
    // an edge's end) in place of a's largest dot, or one of b in place of b's smallest,
    // gives a value at most the one above: still below the measured overlap up to rounding.
    double dot_a(const Vec3& n, int i) const { return ax[i] * n.x + ay[i] * n.y + az[i] * n.z; }
    double dot_b(const Vec3& n, int j) const { return bx[j] * n.x + by[j] * n.y + bz[j] * n.z; }
};

// A vertex on each face of both shapes (an end of one of its edges), from their arcs, and an
// end of an edge of each direction class; index 0 where none is known, which only loosens a
// value (`NearOverlaps::dot_a`). Unknown (`known_a`, `known_b` false) without arcs or beyond
// 64 faces or classes.
struct FaceVertices {
    static constexpr int kMost = 64;
    std::int16_t a[kMost] = {}, b[kMost] = {};            // on faces
    std::int16_t end_a[kMost] = {}, end_b[kMost] = {};    // at edges, by class
    bool known_a = false, known_b = false;

    static bool fill(const ShapeView& s, std::int16_t* on, std::int16_t* end) {
        if (s.arcs == nullptr || s.face_count > kMost || s.edge_count > kMost) return false;
        for (int k = 0; k < s.arc_count; ++k) {
            const GaussArc& arc = s.arcs[k];
            on[arc.face_a] = on[arc.face_b] = end[arc.direction_class] = arc.vertex;
        }
        return true;
    }

    FaceVertices(const ShapeView& sa, const ShapeView& sb)
        : known_a(fill(sa, a, end_a)), known_b(fill(sb, b, end_b)) {}
};

// The face axes (a's normals, then -b's in a's frame) with the same answer, bit for bit, as
// measuring each in order: first the axis of the smallest value (`NearOverlaps`) is measured,
// whose overlap is at least the final answer; an axis whose value is above that by more than
// `slack` cannot be the answer nor tie with it, and is skipped.
void measure_faces(Overlaps& o, const NearOverlaps& near, const Vec3* faces_a, int count_a,
                   const Vec3* faces_b, int count_b, double slack, const FaceVertices& on) {
    constexpr int kMost = 64;
    if (count_a > kMost || count_b > kMost) {
        for (int i = 0; i < count_a; ++i) o.test(faces_a[i]);
        for (int j = 0; j < count_b; ++j) o.test(-(o.rot * faces_b[j]));
        return;
    }
    double value[2 * kMost], x[2 * kMost], y[2 * kMost], z[2 * kMost];  // (Vec3 zeroes itself)
    const int count = count_a + count_b;
    int first = 0;
    for (int k = 0; k < count; ++k) {
        const Vec3 n = k < count_a ? faces_a[k] : -(o.rot * faces_b[k - count_a]);
        x[k] = n.x, y[k] = n.y, z[k] = n.z;
        // A vertex on the face in place of its shape's extreme: the same value up to rounding.
        if (k < count_a)
            value[k] = on.known_a ? near.dot_a(n, on.a[k]) - near.low(n) : near(n);
        else
            value[k] = on.known_b ? near.high(n) - near.dot_b(n, on.b[k - count_a]) : near(n);
        if (value[k] < value[first]) first = k;
    }
    // A NaN value is measured (the comparison fails), and so is every axis after a NaN cap.
    const double measured = count > 0 ? o.overlap_along(Vec3{x[first], y[first], z[first]}) : 0.0;
    const double cap = measured + slack;
    for (int k = 0; k < count; ++k) {
        if (k == first) o.take(Vec3{x[k], y[k], z[k]}, measured);
        else if (!(value[k] > cap)) o.test(Vec3{x[k], y[k], z[k]});
    }
}

// The Minkowski difference a - b of two polytopes has as face normals the face normals of a,
// minus those of b, and +-(e_a x e_b) for edge directions e_a, e_b: the smallest support value
// over these axes is the exact depth (the distance from the origin to the boundary), since any
// unit axis n gives an upper bound h(n) >= depth.
//
// Most edge axes cannot be that smallest one, and the loop skips them unmeasured, with the
// same answer to the bit: every axis is still taken in the same order and replaces the best
// only when strictly below it, and an axis is skipped only when it provably is not below the
// best so far. The bound: a holds the ball of radius r_a about a point c_a (r_a the smallest
// gap between c_a and a's face planes, measured in the face tests that come first), b likewise,
// so the overlap along a unit n is at least n . (c_a - c_b) + r_a + r_b. An axis whose bound
// exceeds the best by more than the rounding of either side (`slack`, a millionth of a
// millionth of the coordinates, where rounding is a few parts in 1e16) would not replace it.
//
// Both shapes have SAT data, and each its edge directions attached unless the other has no
// edges (then E_a E_b = 0 and the edge loop is empty: they would not be read).
SatResult sat_every_edge_pair(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                              const Pose& pose_b) {
    const Features fa = features_of(a), fb = features_of(b);
    Overlaps o(a, pose_a, b, pose_b);
    {
        // Two small scanning polytopes: the axes skipped by their near values (`NearOverlaps`).
        const double slack = near_slack(a, b, o.trans);
        NearOverlaps near;
        if (near.fill(o, slack)) {
            measure_faces(o, near, fa.faces, fa.face_count, fb.faces, fb.face_count, slack,
                          FaceVertices(a, b));
            for (int i = 0; i < fa.edge_count; ++i) {
                for (int j = 0; j < fb.edge_count; ++j) {
                    Vec3 n;
                    if (!o.edge_axis(fa.edges[i], fb.edges[j], n)) continue;
                    if (!(near(n) > o.best + slack)) o.test(n);
                    if (!(near(-n) > o.best + slack)) o.test(-n);
                }
            }
            return o.result(pose_a);
        }
    }
    Vec3 middle_a, middle_b;
    double reach_a, reach_b;
    middle_and_reach(a, middle_a, reach_a);
    middle_and_reach(b, middle_b, reach_b);
    // The inner balls' radii, from below: each face test's support point is a vertex, so its
    // height over the middle is at most the face plane's.
    double radius_a = fa.face_count > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    double radius_b = fb.face_count > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    for (int i = 0; i < fa.face_count; ++i) {
        o.test(fa.faces[i]);
        radius_a = std::fmin(radius_a, dot(fa.faces[i], o.pa - middle_a));
    }
    for (int j = 0; j < fb.face_count; ++j) {
        o.test(-(o.rot * fb.faces[j]));
        radius_b = std::fmin(radius_b, dot(fb.faces[j], o.pb_local - middle_b));
    }
    const double slack =
        1e-12 * (reach_a + reach_b + norm(o.trans) + norm(middle_a) + norm(middle_b));
    // Without a ball on both sides (a flat or degenerate shape, a NaN), every axis is measured.
    const bool bounded = radius_a > slack && radius_b > slack && std::isfinite(slack);
    const Vec3 apart = middle_a - (o.rot * middle_b + o.trans);
    const double inner = radius_a + radius_b;
    for (int i = 0; i < fa.edge_count; ++i) {
        for (int j = 0; j < fb.edge_count; ++j) {
            Vec3 n;
            if (!o.edge_axis(fa.edges[i], fb.edges[j], n)) continue;
            if (!bounded) {
                o.test(n);
                o.test(-n);
                continue;
            }
            const double along = dot(n, apart);
            if (!(along + inner > o.best + slack)) o.test(n);
            if (!(inner - along > o.best + slack)) o.test(-n);
        }
    }
    return o.result(pose_a);
}

// Two polytopes with arcs on their Gauss maps: the face normals of both, then the axes of the
// edge pairs whose arcs cross (Gregorius 2013), in the plain loop's order. Two polytopes
// overlap exactly when every face normal of their Minkowski difference shows an overlap, and
// the smallest is the depth: the axes of edge pairs whose arcs do not cross are above it, or
// tie with it within rounding when the shapes touch at a vertex or an edge of the difference
// (the depth is then 0 by rounding, and any of those axes a normal). Clearly apart, the plain
// loop's answer may be any axis: then false, and the plain loop answers.
bool sat_crossing_edge_pairs(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                             const Pose& pose_b, SatResult& res) {
    Overlaps o(a, pose_a, b, pose_b);
    const double slack = near_slack(a, b, o.trans);
    NearOverlaps near;
    const bool estimated = near.fill(o, slack);
    const FaceVertices on(a, b);
    if (estimated) {
        measure_faces(o, near, a.face_normals, a.face_count, b.face_normals, b.face_count, slack,
                      on);
    } else {
        for (int i = 0; i < a.face_count; ++i) o.test(a.face_normals[i]);
        for (int j = 0; j < b.face_count; ++j) o.test(-(o.rot * b.face_normals[j]));
    }
    // The crossings listed only when their value is within the slack of the best face axis
    // (the loop below checks again against the best so far, which is at most that).
    const double limit = o.best + slack;
    // The value of the axis n of a's class i and b's class j: where the arcs cross, the two
    // edges are the supports, and their ends give it.
    const auto edge_value = [&](const Vec3& n, int i, int j) {
        return on.known_a && on.known_b ? near.dot_a(n, on.end_a[i]) - near.dot_b(n, on.end_b[j])
                                        : near(n);
    };
    const auto keep = [&](int i, int j, const Vec3& axis) {
        if (!estimated) return 3;
        const double length = norm(axis);
        if (!(length > defaults::sat_parallel_edge_sine)) return 0;  // `edge_axis` drops it
        const Vec3 n = axis / length;  // as `edge_axis` makes it
        if (on.known_a && on.known_b) {
            // The opposite axis's value is this one negated, exactly.
            const double value = edge_value(n, i, j);
            return (value > limit ? 0 : 1) | (-value > limit ? 0 : 2);
        }
        return (near(n) > limit ? 0 : 1) | (near(-n) > limit ? 0 : 2);
    };
    for (const int signed_pair : crossing_classes(a, b, o.rot, keep)) {
        const int k = signed_pair / 2, i = k / b.edge_count, j = k % b.edge_count;
        Vec3 n;
        if (!o.edge_axis(a.edge_directions[i], b.edge_directions[j], n)) continue;
        if (signed_pair % 2 != 0) n = -n;
        if (estimated && edge_value(n, i, j) > o.best + slack) continue;
        o.test(n);
    }
    if (!(o.best >= -slack) || !std::isfinite(o.best)) return false;
    res = o.result(pose_a);
    return true;
}

// Both shapes have SAT data, and each its edge directions attached unless the other has no
// edges (then E_a E_b = 0 and the edge loop is empty: they would not be read).
SatResult sat_attached(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                       const Pose& pose_b, long long max_work) {
    const Features fa = features_of(a), fb = features_of(b);
    if (work(fa, fa.edge_count, fb, fb.edge_count) > max_work) return SatResult{};
    // The arcs pay where edge pairs are many and the test of an arc pair costs a fraction of
    // measuring an axis: 8-point hulls, not boxes and wedges (few classes of parallel edges).
    SatResult res;
    if (a.arcs != nullptr && b.arcs != nullptr && a.edge_count > 0 && b.edge_count > 0 &&
        2LL * a.edge_count * b.edge_count * (a.vertex_count + b.vertex_count) >=
            defaults::sat_arc_pair_cost * a.arc_count * b.arc_count &&
        sat_crossing_edge_pairs(a, pose_a, b, pose_b, res))
        return res;
    return sat_every_edge_pair(a, pose_a, b, pose_b);
}

}  // namespace

// A polytope whose edge classes are computed on first use (ShapeView::set) gets them attached
// only when the work bound may let SAT run and its partner may have edges. The work
// (F_a + F_b + 2 E_a E_b)(V_a + V_b) only grows with the class counts: when it is above
// max_work with lower bounds of the counts (0, then the classes of a prefix of the edges, as
// long as the pair needs: EdgeClasses::lower_bound), it is above with the counts themselves,
// and SAT returns unrun, as it would with the classes attached. Against a partner without
// edges a shape's count adds nothing to the work, and its directions are never read.
SatResult sat_penetration(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                          const Pose& pose_b, long long max_work) {
    if (!has_sat_features(a) || !has_sat_features(b)) return SatResult{};
    if (a.set == nullptr && b.set == nullptr) return sat_attached(a, pose_a, b, pose_b, max_work);
    const Features fa = features_of(a), fb = features_of(b);
    if (work(fa, fa.edge_count, fb, fb.edge_count) > max_work) return SatResult{};
    // The bounds (or counts) earlier pairs found, read without computing: they settle most
    // pairs of shapes met before.
    if (work(fa, a.set != nullptr ? edge_count_lower_bound(a, 0) : fa.edge_count, fb,
             b.set != nullptr ? edge_count_lower_bound(b, 0) : fb.edge_count) > max_work)
        return SatResult{};
    // Classes are at most the true edges: when the work with those counts is within the cap,
    // SAT runs. Else the counts that would put the work above the cap: against a known count,
    // the fewest such; both unknown, the fewest that do so on both sides alike (0: the count
    // adds nothing to the work, the partner having no edges).
    const int upper_a = a.set != nullptr ? edge_count_upper_bound(a) : fa.edge_count;
    const int upper_b = b.set != nullptr ? edge_count_upper_bound(b) : fb.edge_count;
    if (work(fa, upper_a, fb, upper_b) > max_work) {
        long long wanted_a = 0, wanted_b = 0;
        const long long vertices = std::max(fa.vertices + fb.vertices, 1);
        if (a.set != nullptr && b.set != nullptr) {
            const long long spare = max_work / vertices - fa.face_count - fb.face_count;
            auto both = static_cast<long long>(
                std::sqrt(0.5 * static_cast<double>(std::max(spare, 0LL))));
            const long long most = std::max(upper_a, upper_b);  // the work is above the cap there
            while (both < most && work(fa, both, fb, both) <= max_work) ++both;
            wanted_a = wanted_b = both;
        } else if (a.set != nullptr && fb.edge_count > 0) {
            wanted_a = (max_work - work(fa, 0, fb, 0)) / (2LL * fb.edge_count * vertices) + 1;
        } else if (b.set != nullptr && fa.edge_count > 0) {
            wanted_b = (max_work - work(fa, 0, fb, 0)) / (2LL * fa.edge_count * vertices) + 1;
        }
        const auto bound = [](const ShapeView& s, long long wanted, int upper) {
            if (wanted == 0) return 0;
            return edge_count_lower_bound(s, static_cast<int>(std::min<long long>(wanted, upper)));
        };
        const int lower_a = a.set != nullptr ? bound(a, wanted_a, upper_a) : fa.edge_count;
        const int lower_b = b.set != nullptr ? bound(b, wanted_b, upper_b) : fb.edge_count;
        if (work(fa, lower_a, fb, lower_b) > max_work) return SatResult{};
    }
    ShapeView whole_a = a, whole_b = b;
    if (b.set != nullptr || fb.edge_count > 0) attach_edges(whole_a);
    if (features_of(whole_a).edge_count > 0) attach_edges(whole_b);
    return sat_attached(whole_a, pose_a, whole_b, pose_b, max_work);
}

}  // namespace meshcol
