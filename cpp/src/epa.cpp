#include "meshcol/epa.hpp"

#include <cmath>
#include <limits>
#include <vector>

namespace meshcol {

namespace {

struct EpaFace {
    int v[3];        // counter-clockwise seen from outside
    int adj[3];      // face across edge (v[e], v[e + 1])
    int adj_edge[3]; // that edge's index in the neighbour
    Vec3 normal;     // outward unit normal (zero when the face is a sliver)
    double distance; // distance of its plane from the origin (+inf for a sliver)
    bool alive;
};

struct HorizonEdge {
    int face;  // the living face beyond the edge
    int edge;  // edge index in that face
};

struct Polytope {
    std::vector<SimplexVertex> vertices;
    std::vector<EpaFace> faces;
    std::vector<HorizonEdge> horizon;

    int add_face(int i, int j, int k) {
        EpaFace f{{i, j, k}, {-1, -1, -1}, {-1, -1, -1}, Vec3{},
                  std::numeric_limits<double>::infinity(), true};
        const Vec3& a = vertices[i].w;
        const Vec3 n = cross(vertices[j].w - a, vertices[k].w - a);
        const double len = norm(n);
        if (len > 0.0 && std::isfinite(len)) {
            f.normal = n / len;
            f.distance = dot(f.normal, a);
        }
        faces.push_back(f);
        return static_cast<int>(faces.size()) - 1;
    }

    void link(int f, int e, int g, int h) {
        faces[f].adj[e] = g;
        faces[f].adj_edge[e] = h;
        faces[g].adj[h] = f;
        faces[g].adj_edge[h] = e;
    }

    // Depth-first walk over the faces that see w (van den Bergen 2003, sec. 4.3.9): the
    // visible region stays connected, so its border is one loop, collected in order.
    void silhouette(int f, int e, const Vec3& w) {
        EpaFace& face = faces[f];
        if (!face.alive) return;
        if (dot(face.normal, w - vertices[face.v[0]].w) <= 0.0) {
            horizon.push_back({f, e});
            return;
        }
        face.alive = false;
        for (int k = 1; k <= 2; ++k) {
            const int edge = (e + k) % 3;
            silhouette(faces[f].adj[edge], faces[f].adj_edge[edge], w);
        }
    }
};

// Barycentric weights of the projection p of the origin on face f (Ericson 2004, sec. 3.4).
void face_weights(const Polytope& poly, const EpaFace& f, double w[3]) {
    const Vec3 p = f.normal * f.distance;
    const Vec3 a = poly.vertices[f.v[0]].w, b = poly.vertices[f.v[1]].w, c = poly.vertices[f.v[2]].w;
    const double u = dot(cross(b - p, c - p), f.normal);
    const double v = dot(cross(c - p, a - p), f.normal);
    const double x = dot(cross(a - p, b - p), f.normal);
    const double total = u + v + x;
    if (total > 0.0 && std::isfinite(total)) {
        w[0] = u / total;
        w[1] = v / total;
        w[2] = x / total;
    } else {
        w[0] = w[1] = w[2] = 1.0 / 3.0;
    }
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
        for (const Vec3& e : {e1, -e1, e2, -e2, e1 + e2, -e1 - e2, e1 - e2, e2 - e1}) {
            const SimplexVertex w = md.support(e);
            const double off = norm(cross(w.w - s.vertices[0].w, d)) / dn;
            if (off > best) {
                best = off;
                best_w = w;
            }
        }
        if (!(best > tol)) return false;
        s.vertices[2] = best_w;
        s.size = 3;
    }
    if (s.size == 3) {
        const Vec3 n = cross(s.vertices[1].w - s.vertices[0].w, s.vertices[2].w - s.vertices[0].w);
        const double nn = norm(n);
        if (!(nn > 0.0)) return false;
        const SimplexVertex up = md.support(n), down = md.support(-n);
        const double hu = dot(up.w - s.vertices[0].w, n) / nn;
        const double hd = -dot(down.w - s.vertices[0].w, n) / nn;
        if (!(std::fmax(hu, hd) > tol)) return false;
        s.vertices[3] = hu >= hd ? up : down;
        s.size = 4;
    }
    return true;
}

}  // namespace

// EPA after van den Bergen 2003 (sec. 4.3.9): the closest face of the polytope to the origin
// gives a lower bound on the depth, the support point in its normal an upper bound; a new
// support point removes every face it sees and closes the hole with a fan over the silhouette
// (no 1-to-3 splitting, which leaves the polytope non-convex). Ends exactly on polytopes
// when a support point repeats.
EpaResult epa_penetration(MinkowskiDifference& md, const Simplex& start, const EpaOptions& opt) {
    EpaResult res;
    const double tol = opt.contact_tolerance * md.scale;
    Simplex s = start;
    if (s.size < 4 && !blow_up(md, s, tol)) {
        // The Minkowski difference is flat: the shapes touch, depth zero.
        res.status = Status::CONVERGED;
        Vec3 pa{}, pb{};
        for (int i = 0; i < s.size; ++i) {
            pa += s.vertices[i].a * s.weights[i];
            pb += s.vertices[i].b * s.weights[i];
        }
        res.point_a = pa;
        res.point_b = pa;
        // The normal of the flat set when it has one, oriented from a to b.
        Vec3 n = md.translation_b;
        if (s.size == 3) {
            const Vec3 c = cross(s.vertices[1].w - s.vertices[0].w, s.vertices[2].w - s.vertices[0].w);
            if (norm(c) > 0.0) n = dot(c, md.translation_b) < 0.0 ? -c : c;
        } else if (s.size == 2) {
            const Vec3 d = s.vertices[1].w - s.vertices[0].w;
            const Vec3 c = n - d * (dot(n, d) / std::fmax(squared_norm(d), 1e-300));
            if (norm(c) > 0.0) n = c;
        }
        const double nn = norm(n);
        res.normal = nn > 0.0 ? n / nn : Vec3{1.0, 0.0, 0.0};
        return res;
    }
    thread_local Polytope poly;
    poly.vertices.clear();
    poly.faces.clear();
    for (int i = 0; i < 4; ++i) poly.vertices.push_back(s.vertices[i]);
    {
        const Vec3 a = s.vertices[0].w, b = s.vertices[1].w, c = s.vertices[2].w, d = s.vertices[3].w;
        if (dot(cross(b - a, c - a), d - a) > 0.0) std::swap(poly.vertices[1], poly.vertices[2]);
    }
    // Outward orientation: (0,1,2) has the opposite vertex 3 behind it.
    poly.add_face(0, 1, 2);
    poly.add_face(0, 3, 1);
    poly.add_face(0, 2, 3);
    poly.add_face(1, 3, 2);
    for (int f = 0; f < 4; ++f)
        for (int e = 0; e < 3; ++e)
            for (int g = 0; g < 4; ++g)
                for (int h = 0; h < 3; ++h)
                    if (poly.faces[f].v[e] == poly.faces[g].v[(h + 1) % 3] &&
                        poly.faces[f].v[(e + 1) % 3] == poly.faces[g].v[h])
                        poly.link(f, e, g, h);

    res.status = Status::MAX_ITERATIONS;
    int best_face = -1;
    int it = 0;
    for (; it < opt.max_iterations; ++it) {
        best_face = -1;
        double best = std::numeric_limits<double>::infinity();
        for (int f = 0; f < static_cast<int>(poly.faces.size()); ++f)
            if (poly.faces[f].alive && poly.faces[f].distance < best) {
                best = poly.faces[f].distance;
                best_face = f;
            }
        if (best_face < 0 || !std::isfinite(best)) {
            res.status = Status::DEGENERATE;
            break;
        }
        const EpaFace closest = poly.faces[best_face];
        // Warm start: the new support point lies near the face's own support points.
        const SimplexVertex& near = poly.vertices[closest.v[0]];
        if (near.index_a >= 0) md.hint_a = near.index_a;
        if (near.index_b >= 0) md.hint_b = near.index_b;
        const SimplexVertex w = md.support(closest.normal);
        const double upper = dot(closest.normal, w.w);
        bool repeated = false;
        if (w.index_a >= 0 && w.index_b >= 0)
            for (const SimplexVertex& x : poly.vertices)
                if (x.index_a == w.index_a && x.index_b == w.index_b) repeated = true;
        if (repeated || upper - closest.distance <= opt.relative_tolerance * upper + tol * 1e-2) {
            res.status = Status::CONVERGED;
            break;
        }
        if (static_cast<int>(poly.vertices.size()) >= defaults::epa_max_vertices) break;
        const int nw = static_cast<int>(poly.vertices.size());
        poly.vertices.push_back(w);
        // Remove the faces the new point sees (the closest one does, by construction) and
        // close the hole with a fan of faces over the silhouette.
        poly.horizon.clear();
        poly.faces[best_face].alive = false;
        for (int e = 0; e < 3; ++e)
            poly.silhouette(poly.faces[best_face].adj[e], poly.faces[best_face].adj_edge[e], w.w);
        const int first = static_cast<int>(poly.faces.size());
        const int count = static_cast<int>(poly.horizon.size());
        bool ok = count >= 3;
        for (int k = 0; k < count && ok; ++k) {
            const HorizonEdge& h = poly.horizon[k];
            const EpaFace& beyond = poly.faces[h.face];
            // The edge runs b -> a in the living face, so a -> b in the new one.
            const int a = beyond.v[(h.edge + 1) % 3], b = beyond.v[h.edge];
            const int f = poly.add_face(a, b, nw);
            poly.link(f, 0, h.face, h.edge);
            if (poly.faces[f].distance < -tol) ok = false;
        }
        if (!ok) {
            res.status = Status::DEGENERATE;
            break;
        }
        for (int k = 0; k < count; ++k) {
            const int f = first + k, g = first + (k + 1) % count;
            if (poly.faces[f].v[1] != poly.faces[g].v[0]) {
                ok = false;
                break;
            }
            poly.link(f, 1, g, 2);
        }
        if (!ok) {
            res.status = Status::DEGENERATE;
            break;
        }
    }
    res.iterations = it;
    if (best_face < 0) {
        res.status = Status::DEGENERATE;
        return res;
    }
    const EpaFace& f = poly.faces[best_face];
    double wts[3];
    face_weights(poly, f, wts);
    Vec3 pa{}, pb{};
    for (int i = 0; i < 3; ++i) {
        pa += poly.vertices[f.v[i]].a * wts[i];
        pb += poly.vertices[f.v[i]].b * wts[i];
    }
    res.depth = std::fmax(0.0, f.distance);
    res.normal = f.normal;
    res.point_a = pa;
    res.point_b = pb;
    return res;
}

}  // namespace meshcol
