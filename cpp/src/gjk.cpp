#include "meshcol/gjk.hpp"

#include <cmath>
#include <limits>

namespace meshcol {

MinkowskiDifference::MinkowskiDifference(const ShapeView& shape_a, const Pose& pose_a,
                                         const ShapeView& shape_b, const Pose& pose_b,
                                         bool margins, double radius_a, double radius_b)
    : a(&shape_a), b(&shape_b), with_margins(margins) {
    // b in a's frame: x_a = Ra^T (Rb x_b + tb - ta).
    rotation_b = pose_a.rotation.transposed() * pose_b.rotation;
    translation_b = pose_a.rotation.transpose_times(pose_b.translation - pose_a.translation);
    if (radius_a < 0.0) radius_a = bounding_radius(shape_a);
    if (radius_b < 0.0) radius_b = bounding_radius(shape_b);
    scale = radius_a + radius_b + norm(translation_b);
    if (!(scale > 0.0)) scale = 1.0;
}

SimplexVertex MinkowskiDifference::support(const Vec3& d) {
    SimplexVertex v;
    const SupportPoint sa = support_core(*a, d, hint_a);
    const SupportPoint sb = support_core(*b, rotation_b.transpose_times(-d), hint_b);
    hint_a = sa.index;
    hint_b = sb.index;
    v.a = sa.point;
    v.b = rotation_b * sb.point + translation_b;
    v.index_a = sa.index;
    v.index_b = sb.index;
    if (with_margins) {
        const double ma = margin(*a), mb = margin(*b);
        if (ma > 0.0 || mb > 0.0) {
            const double n = norm(d);
            if (n > 0.0) {
                v.a += d * (ma / n);
                v.b -= d * (mb / n);
            }
            if (ma > 0.0) v.index_a = -1;
            if (mb > 0.0) v.index_b = -1;
        }
    }
    v.w = v.a - v.b;
    return v;
}

namespace {

void set_vertex(Simplex& s, const SimplexVertex& v) {
    s.vertices[0] = v;
    s.weights[0] = 1.0;
    s.size = 1;
}

void set_edge(Simplex& s, const SimplexVertex& p, const SimplexVertex& q, double t) {
    s.vertices[0] = p;
    s.vertices[1] = q;
    s.weights[0] = 1.0 - t;
    s.weights[1] = t;
    s.size = 2;
}

// Closest point of segment pq to the origin (Ericson 2004, sec. 5.1.2).
Vec3 closest_segment(Simplex& s, const SimplexVertex p, const SimplexVertex q) {
    const Vec3 pq = q.w - p.w;
    const double len2 = squared_norm(pq);
    const double t_num = -dot(p.w, pq);
    if (t_num <= 0.0 || len2 <= 0.0) {
        set_vertex(s, p);
        return p.w;
    }
    if (t_num >= len2) {
        set_vertex(s, q);
        return q.w;
    }
    const double t = t_num / len2;
    set_edge(s, p, q, t);
    return p.w + pq * t;
}

// Closest point of triangle pqr to the origin by Voronoi regions (Ericson 2004, sec. 5.1.5).
// In the face region the point is the plane projection n (n.p)/(n.n), which is more accurate
// than a barycentric sum when the face is far from the origin (parallel faces).
Vec3 closest_triangle(Simplex& s, const SimplexVertex p, const SimplexVertex q,
                      const SimplexVertex r) {
    const Vec3 a = p.w, b = q.w, c = r.w;
    const Vec3 ab = b - a, ac = c - a;
    const double d1 = -dot(ab, a), d2 = -dot(ac, a);
    if (d1 <= 0.0 && d2 <= 0.0) {
        set_vertex(s, p);
        return a;
    }
    const double d3 = -dot(ab, b), d4 = -dot(ac, b);
    if (d3 >= 0.0 && d4 <= d3) {
        set_vertex(s, q);
        return b;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return closest_segment(s, p, q);
    const double d5 = -dot(ab, c), d6 = -dot(ac, c);
    if (d6 >= 0.0 && d5 <= d6) {
        set_vertex(s, r);
        return c;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return closest_segment(s, p, r);
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) return closest_segment(s, q, r);
    const double sum = va + vb + vc;
    const Vec3 n = cross(ab, ac);
    const double nn = squared_norm(n);
    if (!(sum > 0.0) || !(nn > 0.0)) {
        // Flat (collinear) triangle: the best of its three edges.
        Simplex s1, s2, s3;
        const Vec3 x1 = closest_segment(s1, p, q);
        const Vec3 x2 = closest_segment(s2, p, r);
        const Vec3 x3 = closest_segment(s3, q, r);
        const double n1 = squared_norm(x1), n2 = squared_norm(x2), n3 = squared_norm(x3);
        if (n1 <= n2 && n1 <= n3) {
            s = s1;
            return x1;
        }
        if (n2 <= n3) {
            s = s2;
            return x2;
        }
        s = s3;
        return x3;
    }
    s.vertices[0] = p;
    s.vertices[1] = q;
    s.vertices[2] = r;
    s.weights[0] = va / sum;
    s.weights[1] = vb / sum;
    s.weights[2] = vc / sum;
    s.size = 3;
    return n * (dot(n, a) / nn);
}

}  // namespace

bool closest_point_on_simplex(Simplex& s, Vec3& closest) {
    const SimplexVertex* v = s.vertices;
    switch (s.size) {
        case 1:
            s.weights[0] = 1.0;
            closest = v[0].w;
            return true;
        case 2:
            closest = closest_segment(s, v[0], v[1]);
            return true;
        case 3:
            closest = closest_triangle(s, v[0], v[1], v[2]);
            return true;
        default:
            break;
    }
    // Tetrahedron (Ericson 2004, sec. 5.1.6): test the origin against each face plane,
    // oriented away from the opposite vertex; the closest of the faces it lies outside of.
    const SimplexVertex p = v[0], q = v[1], r = v[2], t = v[3];
    const Vec3 a = p.w, b = q.w, c = r.w, d = t.w;
    const double volume = dot(d - a, cross(b - a, c - a));
    const double size = std::fmax(std::fmax(max_abs(b - a), max_abs(c - a)), max_abs(d - a));
    const bool flat = std::fabs(volume) <= 1e-14 * size * size * size;
    struct Face {
        const SimplexVertex *x, *y, *z;
        const SimplexVertex* opposite;
    };
    const Face faces[4] = {{&p, &q, &r, &t}, {&p, &r, &t, &q}, {&p, &t, &q, &r}, {&q, &t, &r, &p}};
    // Barycentric weights of the origin (signed sub-volumes), kept for an inside answer.
    double best = std::numeric_limits<double>::infinity();
    bool outside_any = false;
    Simplex best_s;
    Vec3 best_x;
    for (const Face& f : faces) {
        const Vec3 n = cross(f.y->w - f.x->w, f.z->w - f.x->w);
        const double side_origin = -dot(n, f.x->w);
        const double side_opposite = dot(n, f.opposite->w - f.x->w);
        const bool outside = flat || side_origin * side_opposite < 0.0;
        if (!outside) continue;
        outside_any = true;
        Simplex fs;
        const Vec3 x = closest_triangle(fs, *f.x, *f.y, *f.z);
        const double dist = squared_norm(x);
        if (dist < best) {
            best = dist;
            best_s = fs;
            best_x = x;
        }
    }
    if (outside_any && !(flat && best == 0.0)) {
        s = best_s;
        closest = best_x;
        return true;
    }
    // Inside: the weights are the signed sub-volumes with the origin replacing each vertex.
    auto sub_volume = [](const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
        return dot(x3 - x0, cross(x1 - x0, x2 - x0));
    };
    const Vec3 o{0.0, 0.0, 0.0};
    const double w0 = sub_volume(o, b, c, d), w1 = sub_volume(a, o, c, d);
    const double w2 = sub_volume(a, b, o, d), w3 = sub_volume(a, b, c, o);
    const double total = w0 + w1 + w2 + w3;
    if (total != 0.0 && std::isfinite(total)) {
        s.weights[0] = w0 / total;
        s.weights[1] = w1 / total;
        s.weights[2] = w2 / total;
        s.weights[3] = w3 / total;
    } else {
        s.weights[0] = s.weights[1] = s.weights[2] = s.weights[3] = 0.25;
    }
    closest = Vec3{0.0, 0.0, 0.0};
    return false;
}

namespace {

bool same_feature(const SimplexVertex& x, const SimplexVertex& y) {
    return x.index_a >= 0 && x.index_b >= 0 && x.index_a == y.index_a && x.index_b == y.index_b;
}

void weighted_points(const Simplex& s, Vec3& pa, Vec3& pb) {
    pa = Vec3{};
    pb = Vec3{};
    for (int i = 0; i < s.size; ++i) {
        pa += s.vertices[i].a * s.weights[i];
        pb += s.vertices[i].b * s.weights[i];
    }
}

}  // namespace

// GJK after van den Bergen 2003 (sec. 4.3): v is the closest point of the current simplex to
// the origin, w the support point of a - b in -v. v.v - v.w bounds the squared error; on
// polytopes the loop ends exactly when a support point repeats (a finite number of features).
GjkResult gjk_run(MinkowskiDifference& md, const GjkOptions& opt) {
    GjkResult res;
    Simplex& s = res.simplex;
    const double touch = opt.contact_tolerance * md.scale;
    const double touch2 = touch * touch;
    // On the cores of swept shapes, separation needs a gap wider than the two radii.
    const double separation_gap =
        touch + (opt.with_margins && !md.with_margins ? margin(*md.a) + margin(*md.b) : 0.0);
    // Start from the support in the direction of b's centre as seen from a: a good first guess.
    Vec3 dir = -md.translation_b;
    if (!(squared_norm(dir) > 0.0)) dir = Vec3{1.0, 0.0, 0.0};
    s.vertices[0] = md.support(dir);
    s.weights[0] = 1.0;
    s.size = 1;
    Vec3 v = s.vertices[0].w;
    double vv = squared_norm(v);
    res.status = Status::MAX_ITERATIONS;
    int it = 0;
    bool inside = false;
    while (it < opt.max_iterations) {
        ++it;
        if (vv <= touch2) {
            res.status = Status::CONVERGED;
            inside = true;
            break;
        }
        const SimplexVertex w = md.support(-v);
        bool repeated = false;
        for (int i = 0; i < s.size; ++i)
            if (same_feature(s.vertices[i], w)) repeated = true;
        const double vw = dot(v, w.w);
        if (opt.stop_when_separated && vw > separation_gap * std::sqrt(vv)) {
            // A separating plane with a positive gap: no contact (lower bound > tolerance).
            res.status = Status::CONVERGED;
            break;
        }
        if (repeated || vv - vw <= opt.relative_tolerance * vv) {
            res.status = Status::CONVERGED;
            break;
        }
        s.vertices[s.size] = w;
        ++s.size;
        Simplex trial = s;
        Vec3 nv;
        if (!closest_point_on_simplex(trial, nv)) {
            s = trial;
            inside = true;
            res.status = Status::CONVERGED;
            v = Vec3{};
            vv = 0.0;
            break;
        }
        const double nvv = squared_norm(nv);
        if (!(nvv < vv)) {
            // No progress in floating point: v is as close as rounding allows.
            --s.size;
            res.status = Status::CONVERGED;
            break;
        }
        s = trial;
        v = nv;
        vv = nvv;
    }
    res.iterations = it;
    res.overlap = inside || vv <= touch2;
    weighted_points(s, res.point_a, res.point_b);
    if (res.overlap) {
        res.distance = 0.0;
        res.normal = Vec3{};
    } else {
        const double d = std::sqrt(vv);
        res.distance = d;
        res.normal = v * (-1.0 / d);
    }
    return res;
}

GjkResult gjk_distance(const ShapeView& a, const Pose& pose_a, const ShapeView& b,
                       const Pose& pose_b, const GjkOptions& opt) {
    MinkowskiDifference md(a, pose_a, b, pose_b, false);
    GjkOptions core_opt = opt;
    GjkResult res = gjk_run(md, core_opt);
    const double ma = opt.with_margins ? margin(a) : 0.0;
    const double mb = opt.with_margins ? margin(b) : 0.0;
    if (!res.overlap && (ma > 0.0 || mb > 0.0)) {
        // Swept-sphere shapes: subtract the radii from the exact core distance.
        const double d = res.distance - ma - mb;
        const double touch = opt.contact_tolerance * md.scale;
        res.point_a += res.normal * ma;
        res.point_b -= res.normal * mb;
        if (d > touch) {
            res.distance = d;
        } else {
            res.distance = 0.0;
            res.overlap = true;
        }
    } else if (res.overlap && (ma > 0.0 || mb > 0.0)) {
        res.normal = Vec3{};
    }
    res.point_a = pose_a.apply(res.point_a);
    res.point_b = pose_a.apply(res.point_b);
    res.normal = pose_a.rotate(res.normal);
    if (res.overlap) res.normal = Vec3{};
    return res;
}

}  // namespace meshcol
