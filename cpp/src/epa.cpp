#include "meshcol/epa.hpp"

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <new>

namespace meshcol {

namespace {

struct EpaFace {
    int v[3];        // counter-clockwise seen from outside
    int adj[3];      // face across edge (v[e], v[e + 1])
    int adj_edge[3]; // that edge's index in the neighbour
    bool alive;
    Vec3 normal;     // outward normal, not normalised (zero when the face is a sliver)
    double offset;   // dot(normal, vertex): the plane's distance from the origin times |normal|
};

struct HorizonEdge {
    int face;  // the living face beyond the edge
    int edge;  // edge index in that face
};

constexpr int kNext[3] = {1, 2, 0};
constexpr int kPrev[3] = {2, 0, 1};

// A closed triangulated polytope of V vertices has 2V - 4 faces; dead faces' slots are reused,
// so this many slots always suffice.
constexpr int kMaxFaces = 2 * defaults::epa_max_vertices;

// The expanding polytope in fixed-capacity arrays: trivially constructible, so one
// thread_local instance serves every pair on a thread with no allocation and no guard. The
// faces' plane distances sit in their own array, so the search for the closest face reads
// one contiguous run of doubles.
struct Polytope {
    // One slot more: EPA's support call writes its point into the next slot, where
    // `expand` keeps it without a copy (it is overwritten when the point is not kept).
    SimplexVertex vertices[defaults::epa_max_vertices + 1];
    // (index_a, index_b) of each vertex packed in one word, for the repeated-point test;
    // kNoKey when a support point came from a curved surface (never equal to another).
    std::uint64_t keys[defaults::epa_max_vertices];
    EpaFace faces[kMaxFaces];
    // The plane's signed squared distance from the origin, d |d| (+inf: sliver or dead face):
    // ordered as the distance, and found with one division and no square root per face.
    double distance[kMaxFaces];
    // One slot more than faces: `release` copies pairs, and may read and write one past
    // the last dead face.
    int free_faces[kMaxFaces + 1];
    int dead[kMaxFaces + 1];
    HorizonEdge stack[kMaxFaces + 2];
    // One bit a vertex (its key's `key_bit`): a key whose bit is clear is no vertex's, and
    // `has_vertex` answers without the scan (most calls, which find nothing).
    std::uint64_t key_bits;
    int vertex_count;
    int face_count;  // slots in use, alive or dead
    int free_count;  // dead slots ready for reuse
    int dead_count;

    static constexpr std::uint64_t kNoKey = ~std::uint64_t{0};

    static std::uint64_t key_of(const SimplexVertex& w) {
        if (w.index_a < 0 || w.index_b < 0) return kNoKey;
        return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(w.index_a)) << 32) |
               static_cast<std::uint32_t>(w.index_b);
    }

    static std::uint64_t key_bit(std::uint64_t key) {
        return std::uint64_t{1} << ((key ^ (key >> 29) ^ (key >> 35)) & 63);
    }

    void reset() {
        vertex_count = face_count = free_count = dead_count = 0;
        key_bits = 0;
    }

    void add_vertex(const SimplexVertex& w) {
        vertices[vertex_count] = w;
        keep_next_vertex();
    }

    // Adds the point already written in the next slot, `vertices[vertex_count]`.
    void keep_next_vertex() {
        const std::uint64_t key = key_of(vertices[vertex_count]);
        keys[vertex_count] = key;
        key_bits |= key_bit(key);
        ++vertex_count;
    }

    bool has_vertex(std::uint64_t key) const {
        if (key == kNoKey || (key_bits & key_bit(key)) == 0) return false;
        bool found = false;
        for (int i = 0; i < vertex_count; ++i) found |= keys[i] == key;
        return found;
    }

    // -1 when out of slots.
    int add_face(int i, int j, int k) {
        int f;
        if (free_count > 0) f = free_faces[--free_count];
        else if (face_count < kMaxFaces) f = face_count++;
        else return -1;
        EpaFace& face = faces[f];
        face.v[0] = i;
        face.v[1] = j;
        face.v[2] = k;
        face.alive = true;
        // cross(b - a, c - a), squared_norm and dot written out in their order: the same
        // numbers, in scalar registers (GCC's vectorised form of the Vec3 code shuffles and
        // spills).
        const Vec3& a = vertices[i].w;
        const Vec3& b = vertices[j].w;
        const Vec3& c = vertices[k].w;
        const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
        const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
        const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
        const double nn = nx * nx + ny * ny + nz * nz;
        if (nn > 0.0 && std::isfinite(nn)) {
            const double offset = nx * a.x + ny * a.y + nz * a.z;
            face.normal = Vec3{nx, ny, nz};
            face.offset = offset;
            distance[f] = offset * std::fabs(offset) / nn;
        } else {
            face.normal = Vec3{};
            face.offset = 0.0;
            distance[f] = std::numeric_limits<double>::infinity();
        }
        return f;
    }

    void link(int f, int e, int g, int h) {
        faces[f].adj[e] = g;
        faces[f].adj_edge[e] = h;
        faces[g].adj[h] = f;
        faces[g].adj_edge[h] = e;
    }

    void kill(int f) {
        faces[f].alive = false;
        distance[f] = std::numeric_limits<double>::infinity();
        dead[dead_count++] = f;
    }

    // The walk over the faces that see w (van den Bergen 2003, sec. 4.3.9), depth first from
    // the edges of a killed face (`start_walk`): the visible region stays connected, so its
    // border is one loop, and `next_border` hands it over edge by edge in order (each edge's
    // living face and the edge's index in it), killing the visible faces it passes; false
    // when the walk is over. An explicit stack instead of recursion; edges are pushed in
    // reverse so they are visited in the recursive order. Killed faces are freed only after
    // the new faces are made (`release`), so none is reused while the walk still reads it,
    // and the closest face keeps its data. The caller may make faces and link them to living
    // faces between the calls: the walk reads only the adjacency of faces it kills, and a
    // face beyond the border is never killed.
    int start_walk(int first) {
        const EpaFace& start = faces[first];
        int top = 0;
        for (int e = 2; e >= 0; --e) stack[top++] = {start.adj[e], start.adj_edge[e]};
        return top;
    }

    bool next_border(const Vec3& w, int& top, HorizonEdge& h) {
        if (top == 0) return false;
        h = stack[--top];
        for (;;) {
            EpaFace& face = faces[h.face];
            if (face.alive) {
                // w sees the face when it lies beyond the face's plane (a sliver's zero
                // normal and offset: never); the stored offset saves loading a vertex.
                if (!(dot(face.normal, w) > face.offset)) return true;
                kill(h.face);
                // Recursion visits edge e+1, then e+2: e+2 waits on the stack, e+1 is next
                // (what a push and a pop would hand over).
                const int e2 = kPrev[h.edge], e1 = kNext[h.edge];
                stack[top++] = {face.adj[e2], face.adj_edge[e2]};
                h = {face.adj[e1], face.adj_edge[e1]};
                continue;
            }
            if (top == 0) return false;
            h = stack[--top];
        }
    }

    void release() {
        // Two at a time: a plain copy loop becomes a `memcpy` call, which costs more than
        // the copy of the one to four slots an expansion frees. A pair may copy one slot
        // past the last dead one: it lies beyond `free_count`, in the arrays' spare slot.
        int* const to = free_faces + free_count;
        for (int k = 0; k < dead_count; k += 2) {
            to[k] = dead[k];
            to[k + 1] = dead[k + 1];
        }
        free_count += dead_count;
        dead_count = 0;
    }
};

// Barycentric weights of the projection p of the origin on face f (Ericson 2004, sec. 3.4);
// `normal` is the face's unit normal, `distance` its plane's distance from the origin.
inline void face_weights(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& normal,
                         double distance, double w[3]) {
    const Vec3 p = normal * distance;
    const double u = dot(cross(b - p, c - p), normal);
    const double v = dot(cross(c - p, a - p), normal);
    const double x = dot(cross(a - p, b - p), normal);
    const double total = u + v + x;
    if (total > 0.0 && std::isfinite(total)) {
        w[0] = u / total;
        w[1] = v / total;
        w[2] = x / total;
    } else {
        w[0] = w[1] = w[2] = 1.0 / 3.0;
    }
}

void face_weights(const Polytope& poly, const EpaFace& f, const Vec3& normal, double distance,
                  double w[3]) {
    face_weights(poly.vertices[f.v[0]].w, poly.vertices[f.v[1]].w, poly.vertices[f.v[2]].w,
                 normal, distance, w);
}

// Adds the support point written in the polytope's next vertex slot
// (`poly.vertices[poly.vertex_count]`): removes every face it sees, starting from `visible`
// (a face it sees), and closes the hole with a fan of faces over the silhouette. False when
// the silhouette does not close or a new face passes the wrong side of the origin (rounding
// on a degenerate polytope).
inline bool expand(Polytope& poly, int visible, double tol) {
    const int nw = poly.vertex_count;
    const Vec3 w = poly.vertices[nw].w;
    poly.keep_next_vertex();
    // Remove the faces the new point sees (the closest one does, by construction) and
    // close the hole with a fan of faces over the silhouette, made as the walk finds its
    // edges (no list of them in between): each new face is linked to the living face beyond
    // its edge and to the previous new face, once the loop is seen to close there (the
    // previous face's edge ends where this one's starts); the last closes on the first.
    // The first border edge is taken before the loop over the others, so no step asks
    // whether a fan face exists yet (a branch whose outcome varied with the walk). A failure
    // ends the walk at once: the polytope is then dropped, and the closest face's slot
    // (killed, not released) keeps its data.
    poly.dead_count = 0;
    poly.kill(visible);
    int top = poly.start_walk(visible);
    // Adds the fan face over border edge h (b -> a in the living face, so a -> b in the new
    // one) and links it to h's face; -1 when out of slots or on the wrong side of the origin.
    const double limit = -tol * tol;
    const auto fan_face = [&](const HorizonEdge& h, int& a, int& b) {
        const EpaFace& beyond = poly.faces[h.face];
        a = beyond.v[kNext[h.edge]];
        b = beyond.v[h.edge];
        const int f = poly.add_face(a, b, nw);
        if (f < 0) return -1;
        poly.link(f, 0, h.face, h.edge);
        return poly.distance[f] < limit ? -1 : f;
    };
    HorizonEdge h;
    if (!poly.next_border(w, top, h)) return false;
    int first_start, previous_end;
    const int first = fan_face(h, first_start, previous_end);
    if (first < 0) return false;
    int previous = first, count = 1;
    while (poly.next_border(w, top, h)) {
        int a, b;
        const int f = fan_face(h, a, b);
        if (f < 0 || previous_end != a) return false;
        poly.link(previous, 1, f, 2);
        previous = f;
        previous_end = b;
        ++count;
    }
    if (count < 3 || previous_end != first_start) return false;
    poly.link(previous, 1, first, 2);
    poly.release();
    return true;
}

// Blows a touching simplex of fewer than four vertices up to a tetrahedron holding the origin
// (as coal and parry do): supports along directions spanning the missing dimensions.
// Returns false when a - b is flat (zero volume): the depth is then zero.
bool blow_up(MinkowskiDifference& md, Simplex& s, double tol) {
    const Vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    if (s.size == 1) {
        for (int k = 0; k < 6 && s.size == 1; ++k) {
            const SimplexVertex w = md.support(axes[k / 2] * (k % 2 == 0 ? 1.0 : -1.0));
            if (norm(w.w - s.vertices[0].w) > tol) {
                s.vertices[1] = w;
                s.size = 2;
            }
        }
        if (s.size == 1) return false;
    }
    if (s.size == 2) {
        const Vec3 d = s.vertices[1].w - s.vertices[0].w;
        // An axis least aligned with d gives a well-conditioned perpendicular.
        int k = 0;
        if (std::fabs(d.y) < std::fabs(d[k])) k = 1;
        if (std::fabs(d.z) < std::fabs(d[k])) k = 2;
        const Vec3 e1 = cross(d, axes[k]);
        const Vec3 e2 = cross(d, e1);
        const double dn = norm(d);
        double best = -1.0;
        SimplexVertex best_w;
        const Vec3 dirs[8] = {e1, -e1, e2, -e2, e1 + e2, -e1 - e2, e1 - e2, e2 - e1};
        for (int k = 0; k < 8; ++k) {
            const SimplexVertex w = md.support(dirs[k]);
            const double off = norm(cross(w.w - s.vertices[0].w, d)) / dn;
            if (off > best) {
                best = off;
                best_w = w;
            }
            // After each opposite pair: a point as far off the line as the segment is long
            // makes a well-shaped triangle, and the remaining directions cost a support each.
            if (k % 2 == 1 && best > tol && best >= defaults::epa_blow_up_enough * dn) break;
        }
        if (!(best > tol)) return false;
        s.vertices[2] = best_w;
        s.size = 3;
    }
    if (s.size == 3) {
        const Vec3 n = cross(s.vertices[1].w - s.vertices[0].w, s.vertices[2].w - s.vertices[0].w);
        const double nn = norm(n);
        if (!(nn > 0.0)) return false;
        // Up first; down only when up lies no farther off the plane than the triangle's
        // longest edge (else the tetrahedron is already well shaped).
        const SimplexVertex up = md.support(n);
        const double hu = dot(up.w - s.vertices[0].w, n) / nn;
        const double edge = std::sqrt(std::fmax(
            std::fmax(squared_norm(s.vertices[1].w - s.vertices[0].w),
                      squared_norm(s.vertices[2].w - s.vertices[0].w)),
            squared_norm(s.vertices[2].w - s.vertices[1].w)));
        if (hu > tol && hu >= defaults::epa_blow_up_enough * edge) {
            s.vertices[3] = up;
        } else {
            const SimplexVertex down = md.support(-n);
            const double hd = -dot(down.w - s.vertices[0].w, n) / nn;
            if (!(std::fmax(hu, hd) > tol)) return false;
            s.vertices[3] = hu >= hd ? up : down;
        }
        s.size = 4;
    }
    return true;
}

// A touching pair's normal without EPA, from candidate faces through the origin, each checked
// by one support along its outward normal: true, and `res` set, when the shapes overlap along
// one by at most `tol` (a contact normal within the contact distance). The first candidate is
// the simplex's face nearest the origin (a tetrahedron's face opposite its least weight, a
// triangle's plane oriented towards b); when it fails and the origin lies on an edge of the
// tetrahedron (a vertex-edge contact, whose normals form a wedge around that edge), the faces
// of the wedge around the edge follow, each failed support replacing its side, as EPA would
// expand around that edge (up to `defaults::epa_touching_supports` supports in all). A
// segment's or point's candidate is the centre line, perpendicular to the segment. False
// when none holds, with `md`'s climb state as it was (EPA then runs as if this had not).
// The part of `line` perpendicular to segment direction d (a flat simplex's normal towards b
// when the simplex is a segment).
Vec3 off_segment(const Vec3& line, const Vec3& d) {
    return line - d * (dot(line, d) / std::fmax(squared_norm(d), defaults::epa_min_squared_length));
}

bool touching_normal(MinkowskiDifference& md, const Simplex& s, double tol, EpaResult& res) {
    const SimplexVertex* v = s.vertices;
    const Vec3 line = md.translation_b;
    const int hint_a = md.hint_a, hint_b = md.hint_b;
    const Vec3 last_direction = md.last_direction;
    const auto restore = [&] {
        md.hint_a = hint_a;
        md.hint_b = hint_b;
        md.last_direction = last_direction;
    };
    if (s.size <= 2) {
        const Vec3 n = s.size == 2 ? off_segment(line, v[1].w - v[0].w) : line;
        const double nn = squared_norm(n);
        if (!(nn > 0.0) || !std::isfinite(nn)) return false;
        const double length = std::sqrt(nn);
        const double offset = dot(n, v[0].w);
        if (!(std::fabs(offset) <= tol * length)) return false;
        const SimplexVertex w = md.support_from(n, v[0].index_a, v[0].index_b);
        const double h = dot(n, w.w) / length;
        if (!(h <= tol)) {
            restore();
            return false;
        }
        res.status = Status::CONVERGED;
        res.depth = std::fmax(0.0, h);
        res.normal = n * (1.0 / length);
        weighted_points(s, res.point_a, res.point_b);
        res.iterations = 1;
        return true;
    }
    // The candidate face (e0, e1, side) with the point `away` behind it (a vertex, or for a
    // triangle at first a point beside it): e0 and e1 are the edge the wedge turns about
    // (the origin on it, or near). Pointers into the simplex and `found` (the last three
    // supports), so that a try copies no vertex.
    const SimplexVertex *e0, *e1, *side, *away = nullptr;
    Vec3 away_w;
    SimplexVertex found[3];
    if (s.size == 4) {
        int low = 0;
        for (int i = 1; i < 4; ++i)
            if (s.weights[i] < s.weights[low]) low = i;
        int low2 = low == 0 ? 1 : 0;
        for (int i = 0; i < 4; ++i)
            if (i != low && s.weights[i] < s.weights[low2]) low2 = i;
        int k = 0, edge[2] = {0, 0};
        for (int i = 0; i < 4; ++i)
            if (i != low && i != low2) edge[k++] = i;
        e0 = &v[edge[0]];
        e1 = &v[edge[1]];
        side = &v[low2];
        away = &v[low];
        away_w = away->w;
    } else {
        // The edge opposite the least weight (the origin on it, when it is on an edge).
        int low = 0;
        for (int i = 1; i < 3; ++i)
            if (s.weights[i] < s.weights[low]) low = i;
        e0 = &v[(low + 1) % 3];
        e1 = &v[(low + 2) % 3];
        side = &v[low];
        const Vec3 n = cross(e1->w - e0->w, side->w - e0->w);
        away_w = e0->w - (dot(n, line) < 0.0 ? -n : n);  // on the side away from b
    }
    for (int tries = 0; tries < defaults::epa_touching_supports; ++tries) {
        Vec3 n = cross(e1->w - e0->w, side->w - e0->w);
        const bool flip = dot(n, away_w - e0->w) > 0.0;
        if (flip) n = -n;
        const double nn = squared_norm(n);
        if (!(nn > 0.0) || !std::isfinite(nn)) break;
        const double length = std::sqrt(nn);
        // Only a plane through the origin (within the contact distance) can be a contact
        // plane: a deep pair's tetrahedron, which holds the origin well inside, pays no
        // support here.
        const double offset = dot(n, e0->w);
        if (!(std::fabs(offset) <= tol * length)) break;
        // The climbs start from the face's vertex highest along n.
        const SimplexVertex* top = e0;
        if (dot(n, e1->w) > dot(n, top->w)) top = e1;
        if (dot(n, side->w) > dot(n, top->w)) top = side;
        SimplexVertex& w = found[tries % 3];
        w = md.support_from(n, top->index_a, top->index_b);
        const double h = dot(n, w.w) / length;
        if (h <= tol) {
            // As EPA's: the weights of the origin's projection on the face, counter-clockwise
            // about the outward normal.
            const Vec3 normal = n * (1.0 / length);
            const SimplexVertex& f1 = flip ? *side : *e1;
            const SimplexVertex& f2 = flip ? *e1 : *side;
            double wts[3];
            face_weights(e0->w, f1.w, f2.w, normal, offset / length, wts);
            res.status = Status::CONVERGED;
            res.depth = std::fmax(0.0, h);
            res.normal = normal;
            res.point_a = e0->a * wts[0] + f1.a * wts[1] + f2.a * wts[2];
            res.point_b = e0->b * wts[0] + f1.b * wts[1] + f2.b * wts[2];
            res.iterations = tries + 1;
            return true;
        }
        // The support lies beyond this face. A triangle's plane is tried again the other way
        // round (the support behind it); else the support replaces the face's side, and the
        // wedge's other face is tried next (`found` keeps the wedge's two and the new one).
        if (away != nullptr) side = away;
        away = &w;
        away_w = w.w;
    }
    restore();
    return false;
}

// The polytope of this thread: trivially constructible, so no allocation and no guard.
Polytope& thread_polytope() {
    thread_local Polytope scratch;
    // Read through a volatile pointer so the compiler cannot see the helpers work on the
    // thread_local and specialise them to look it up on every access.
    Polytope* volatile scratch_address = &scratch;
    return *scratch_address;
}

// Starts `poly` from the tetrahedron `v` (any orientation: v[1] and v[2] are added the
// other way round when it is clockwise).
void start_tetrahedron(Polytope& poly, const SimplexVertex v[4]) {
    poly.reset();
    const Vec3 a = v[0].w, b = v[1].w, c = v[2].w, d = v[3].w;
    const bool swap = dot(cross(b - a, c - a), d - a) > 0.0;
    poly.add_vertex(v[0]);
    poly.add_vertex(v[swap ? 2 : 1]);
    poly.add_vertex(v[swap ? 1 : 2]);
    poly.add_vertex(v[3]);
    // Outward orientation: (0,1,2) has the opposite vertex 3 behind it. Each edge i -> j of a
    // face meets j -> i of its neighbour.
    poly.add_face(0, 1, 2);
    poly.add_face(0, 3, 1);
    poly.add_face(0, 2, 3);
    poly.add_face(1, 3, 2);
    poly.link(0, 0, 1, 2);
    poly.link(0, 1, 3, 2);
    poly.link(0, 2, 2, 0);
    poly.link(1, 0, 2, 2);
    poly.link(1, 1, 3, 0);
    poly.link(2, 1, 3, 1);
}

// True when the origin lies strictly inside the tetrahedron abcd (either orientation): the
// four signed volumes with the origin in place of each vertex share the sign of the whole's.
bool holds_origin(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    const double whole = dot(d - a, cross(b - a, c - a));
    const double va = dot(d, cross(b, c));
    const double vb = dot(d, cross(c, a));
    const double vc = dot(d, cross(a, b));
    const double vd = whole - va - vb - vc;
    if (whole > 0.0) return va > 0.0 && vb > 0.0 && vc > 0.0 && vd > 0.0;
    return whole < 0.0 && va < 0.0 && vb < 0.0 && vc < 0.0 && vd < 0.0;
}

// Starts `poly` from the octahedron with apexes `first` and `back` and the ring's four points
// around them, when it is the six points' convex hull (every face has the other three
// vertices strictly behind it) and holds the origin clear of every face by more than `tol`.
// The same polytope as a tetrahedron of them with the other two ring points added, without
// the two expansions; false (and `poly` to be reset) otherwise.
bool start_octahedron(Polytope& poly, const SimplexVertex& first, const SimplexVertex& back,
                      const SimplexVertex ring[4], double tol) {
    poly.reset();
    poly.add_vertex(first);  // 0
    poly.add_vertex(back);   // 1
    // The ring in the order that makes (first, ring[i], ring[i + 1]) face away from `back`
    // (when the guess is wrong, the tests below fail).
    const bool forward =
        dot(cross(ring[0].w - first.w, ring[1].w - first.w), back.w - first.w) < 0.0;
    for (int r = 0; r < 4; ++r) poly.add_vertex(ring[forward ? r : 3 - r]);  // 2 to 5
    // Slots 0-3: (first, ring i, ring i + 1); slots 4-7: (back, ring i + 1, ring i).
    for (int i = 0; i < 4; ++i) poly.add_face(0, 2 + i, 2 + (i + 1) % 4);
    for (int i = 0; i < 4; ++i) poly.add_face(1, 2 + (i + 1) % 4, 2 + i);
    for (int f = 0; f < 8; ++f) {
        const EpaFace& face = poly.faces[f];
        if (!(poly.distance[f] > tol * tol) || !std::isfinite(poly.distance[f])) return false;
        for (int q = 0; q < 6; ++q) {
            if (q == face.v[0] || q == face.v[1] || q == face.v[2]) continue;
            if (!(dot(face.normal, poly.vertices[q].w) < face.offset)) return false;
        }
    }
    for (int i = 0; i < 4; ++i) {
        const int next = (i + 1) % 4;
        poly.link(i, 2, next, 0);          // ring i + 1 -> first, first -> ring i + 1
        poly.link(i, 1, 4 + i, 1);         // ring i -> ring i + 1, and back below it
        poly.link(4 + i, 0, 4 + next, 2);  // back -> ring i + 1, ring i + 1 -> back
    }
    return true;
}

// EPA's loop on a polytope that holds the origin (van den Bergen 2003, sec. 4.3.9): the
// closest face of the polytope to the origin gives a lower bound on the depth, the support
// point in its normal an upper bound; a new support point removes every face it sees and
// closes the hole with a fan over the silhouette (no 1-to-3 splitting, which leaves the
// polytope non-convex). Ends exactly on polytopes when a support point repeats.
EpaResult expand_to_depth(MinkowskiDifference& md, Polytope& poly, const EpaOptions& opt,
                          double tol) {
    EpaResult res;
    res.status = Status::MAX_ITERATIONS;
    // The closest face of the last iteration: its slot keeps its data to the end (a killed
    // face is released only after the new faces are made, and nothing is added after that).
    int last_face = -1;
    int it = 0;
    for (; it < opt.max_iterations; ++it) {
        // The closest face: a linear scan over a few dozen slots (dead ones hold +inf).
        int best_face = -1;
        double best = std::numeric_limits<double>::infinity();
        for (int f = 0; f < poly.face_count; ++f)
            if (poly.distance[f] < best) {
                best = poly.distance[f];
                best_face = f;
            }
        if (best_face < 0 || !std::isfinite(best)) {
            res.status = Status::DEGENERATE;
            break;
        }
        last_face = best_face;
        const EpaFace& closest = poly.faces[best_face];
        // Warm start: the new support point lies near the face's own support points.
        const SimplexVertex& near = poly.vertices[closest.v[0]];
        // Made in the next vertex slot, where `expand` keeps it: initialised by the call's
        // result (no temporary, as an assignment would make, and no copy).
        const SimplexVertex& w = *new (&poly.vertices[poly.vertex_count])
            SimplexVertex(md.support_from(closest.normal, near.index_a, near.index_b));
        // Lower (the face's plane) and upper (the support plane) bounds on the depth, both
        // times |normal|: the test needs no normalised normal.
        const double upper = dot(closest.normal, w.w);
        const double scale = std::sqrt(squared_norm(closest.normal));
        const std::uint64_t key = Polytope::key_of(w);
        if (upper - closest.offset <=
                opt.relative_tolerance * upper +
                    tol * defaults::epa_absolute_tolerance_ratio * scale ||
            poly.has_vertex(key)) {
            res.status = Status::CONVERGED;
            break;
        }
        if (poly.vertex_count >= defaults::epa_max_vertices) break;
        if (!expand(poly, best_face, tol)) {
            res.status = Status::DEGENERATE;
            break;
        }
    }
    res.iterations = it;
    if (last_face < 0) {
        res.status = Status::DEGENERATE;
        return res;
    }
    const EpaFace& f = poly.faces[last_face];
    const double length = std::sqrt(squared_norm(f.normal));
    const Vec3 normal = f.normal * (1.0 / length);
    const double distance = f.offset / length;
    double wts[3];
    face_weights(poly, f, normal, distance, wts);
    Vec3 pa{}, pb{};
    for (int i = 0; i < 3; ++i) {
        pa += poly.vertices[f.v[i]].a * wts[i];
        pb += poly.vertices[f.v[i]].b * wts[i];
    }
    res.depth = std::fmax(0.0, distance);
    res.normal = normal;
    res.point_a = pa;
    res.point_b = pb;
    return res;
}

}  // namespace

// EPA from GJK's simplex, blown up to a tetrahedron when the pair touches.
EpaResult epa_penetration(MinkowskiDifference& md, const Simplex& start, const EpaOptions& opt) {
    EpaResult res;
    const double tol = opt.contact_tolerance * md.scale;
    // A tetrahedron holding the origin clear of its faces (every weight above
    // `defaults::epa_touching_max_weight`: a deep pair's) has no face through it.
    bool clear = start.size == 4;
    for (int i = 0; i < start.size && clear; ++i)
        clear = start.weights[i] > defaults::epa_touching_max_weight;
    if (!clear && touching_normal(md, start, tol, res)) return res;
    if (start.size == 4) {
        // GJK's tetrahedron as it is: no copy of the simplex.
        Polytope& poly = thread_polytope();
        start_tetrahedron(poly, start.vertices);
        return expand_to_depth(md, poly, opt, tol);
    }
    Simplex s = start;
    if (!blow_up(md, s, tol)) {
        // The Minkowski difference is flat: the shapes touch, depth zero.
        res.status = Status::CONVERGED;
        Vec3 pb;
        weighted_points(s, res.point_a, pb);
        res.point_b = res.point_a;
        // The normal of the flat set when it has one, oriented from a to b.
        Vec3 n = md.translation_b;
        if (s.size == 3) {
            const Vec3 c = cross(s.vertices[1].w - s.vertices[0].w, s.vertices[2].w - s.vertices[0].w);
            if (norm(c) > 0.0) n = dot(c, md.translation_b) < 0.0 ? -c : c;
        } else if (s.size == 2) {
            const Vec3 c = off_segment(n, s.vertices[1].w - s.vertices[0].w);
            if (norm(c) > 0.0) n = c;
        }
        const double nn = norm(n);
        res.normal = nn > 0.0 ? n / nn : Vec3{1.0, 0.0, 0.0};
        return res;
    }
    Polytope& poly = thread_polytope();
    start_tetrahedron(poly, s.vertices);
    return expand_to_depth(md, poly, opt, tol);
}

EpaResult epa_penetration_deep(MinkowskiDifference& md, const SimplexVertex& first,
                               const EpaOptions& opt) {
    EpaResult res;
    const double tol = opt.contact_tolerance * md.scale;
    const Vec3 n = md.translation_b;
    const double nn = squared_norm(n);
    if (!(nn > 0.0) || !std::isfinite(nn)) return res;
    // Each support bounds the depth from above (the depth is the least, over directions, of
    // how far the support lies past the origin): a pair that is shallow along any of them is
    // left to GJK at once.
    const double length = std::sqrt(nn);
    const double deep = defaults::epa_deep_start_depth * md.scale;
    if (!(dot(first.w, n) > deep * length)) return res;
    // Two directions perpendicular to n, each defaults::epa_deep_start_spread times as long:
    // n plus or minus either points that far off the centre line.
    int k = 0;
    if (std::fabs(n.y) < std::fabs(n[k])) k = 1;
    if (std::fabs(n.z) < std::fabs(n[k])) k = 2;
    const Vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const Vec3 c = cross(n, axes[k]);
    const Vec3 u = c * (defaults::epa_deep_start_spread * length / norm(c));
    const Vec3 v = cross(n, u) * (1.0 / length);
    // A ring around the centre line, in order, then the far side. Each ring climb starts
    // from the centre line's support points, which lie nearer each ring direction (about 33
    // degrees off) than the previous ring point's (about 45 degrees); the far side's climbs
    // start from a few samples.
    const Vec3 directions[4] = {n + u, n + v, n - u, n - v};
    const double ring_length = length * std::sqrt(1.0 + defaults::epa_deep_start_spread *
                                                            defaults::epa_deep_start_spread);
    SimplexVertex ring[4];
    for (int r = 0; r < 4; ++r) {
        ring[r] = md.support_from(directions[r], first.index_a, first.index_b);
        if (!(dot(ring[r].w, directions[r]) > deep * ring_length)) return res;
    }
    const SimplexVertex back = md.support(-n);
    // The segment back -> first crosses the ring's span near the origin on a deep pair, and
    // the six points' hull is most often the octahedron around that segment: EPA starts there
    // when it holds the origin clear of its faces by more than the contact distance.
    Polytope& poly = thread_polytope();
    if (start_octahedron(poly, first, back, ring, tol)) {
        res = expand_to_depth(md, poly, opt, tol);
        res.iterations += 6;
        return res;
    }
    // Else one of the four tetrahedra around the segment must hold the origin, clear of its
    // faces (else the pair is left to GJK), and the other two ring points are added to it.
    int held = -1;
    for (int r = 0; r < 4 && held < 0; ++r)
        if (holds_origin(back.w, first.w, ring[r].w, ring[(r + 1) % 4].w)) held = r;
    if (held < 0) return res;
    SimplexVertex start[4] = {back, first, ring[held], ring[(held + 1) % 4]};
    start_tetrahedron(poly, start);
    for (int f = 0; f < 4; ++f)
        if (!(poly.distance[f] > tol * tol) || !std::isfinite(poly.distance[f])) return res;
    // The rest of the ring, where it lies outside: each one from the face it sees most.
    for (int q = 2; q < 4; ++q) {
        const SimplexVertex& w = ring[(held + q) % 4];
        if (poly.has_vertex(Polytope::key_of(w))) continue;
        int visible = -1;
        double most = 0.0;
        for (int f = 0; f < poly.face_count; ++f) {
            const EpaFace& face = poly.faces[f];
            const double x = dot(face.normal, w.w) - face.offset;
            if (face.alive && x > most) {
                most = x;
                visible = f;
            }
        }
        if (visible < 0) continue;
        poly.vertices[poly.vertex_count] = w;
        if (!expand(poly, visible, tol)) return res;
    }
    res = expand_to_depth(md, poly, opt, tol);
    res.iterations += 6;
    return res;
}

}  // namespace meshcol
