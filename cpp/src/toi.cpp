#include "meshcol/toi.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include "meshcol/batch.hpp"
#include "meshcol/gjk.hpp"
#include "rescale.hpp"

namespace meshcol {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const Vec3 kNaN3{kNaN, kNaN, kNaN};

}  // namespace

Mat3 axis_angle_matrix(const Vec3& k, double angle) {
    const double c = std::cos(angle), s = std::sin(angle), t = 1.0 - c;
    Mat3 r;
    r.m[0][0] = c + t * k.x * k.x;
    r.m[0][1] = t * k.x * k.y - s * k.z;
    r.m[0][2] = t * k.x * k.z + s * k.y;
    r.m[1][0] = t * k.y * k.x + s * k.z;
    r.m[1][1] = c + t * k.y * k.y;
    r.m[1][2] = t * k.y * k.z - s * k.x;
    r.m[2][0] = t * k.z * k.x - s * k.y;
    r.m[2][1] = t * k.z * k.y + s * k.x;
    r.m[2][2] = c + t * k.z * k.z;
    return r;
}

namespace {

// Unit quaternion (w, x, y, z) of a rotation matrix, w >= 0 (Shepperd 1978: the largest of
// the four diagonal combinations keeps the square root well conditioned, also near pi).
void matrix_quaternion(const Mat3& r, double q[4]) {
    const double tr = r.m[0][0] + r.m[1][1] + r.m[2][2];
    if (tr >= r.m[0][0] && tr >= r.m[1][1] && tr >= r.m[2][2]) {
        const double s = 2.0 * std::sqrt(std::fmax(0.0, 1.0 + tr));
        q[0] = 0.25 * s;
        q[1] = (r.m[2][1] - r.m[1][2]) / s;
        q[2] = (r.m[0][2] - r.m[2][0]) / s;
        q[3] = (r.m[1][0] - r.m[0][1]) / s;
    } else if (r.m[0][0] >= r.m[1][1] && r.m[0][0] >= r.m[2][2]) {
        const double s = 2.0 * std::sqrt(std::fmax(0.0, 1.0 + r.m[0][0] - r.m[1][1] - r.m[2][2]));
        q[0] = (r.m[2][1] - r.m[1][2]) / s;
        q[1] = 0.25 * s;
        q[2] = (r.m[0][1] + r.m[1][0]) / s;
        q[3] = (r.m[0][2] + r.m[2][0]) / s;
    } else if (r.m[1][1] >= r.m[2][2]) {
        const double s = 2.0 * std::sqrt(std::fmax(0.0, 1.0 + r.m[1][1] - r.m[0][0] - r.m[2][2]));
        q[0] = (r.m[0][2] - r.m[2][0]) / s;
        q[1] = (r.m[0][1] + r.m[1][0]) / s;
        q[2] = 0.25 * s;
        q[3] = (r.m[1][2] + r.m[2][1]) / s;
    } else {
        const double s = 2.0 * std::sqrt(std::fmax(0.0, 1.0 + r.m[2][2] - r.m[0][0] - r.m[1][1]));
        q[0] = (r.m[1][0] - r.m[0][1]) / s;
        q[1] = (r.m[0][2] + r.m[2][0]) / s;
        q[2] = (r.m[1][2] + r.m[2][1]) / s;
        q[3] = 0.25 * s;
    }
    if (q[0] < 0.0)
        for (int i = 0; i < 4; ++i) q[i] = -q[i];
}

bool same_rotation(const Mat3& x, const Mat3& y) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (x.m[i][j] != y.m[i][j]) return false;
    return true;
}

bool same_feature(const SimplexVertex& x, const SimplexVertex& y) {
    return x.index_a >= 0 && x.index_b >= 0 && x.index_a == y.index_a && x.index_b == y.index_b;
}

ToiResult invalid_result() {
    ToiResult r;
    r.status = TimeOfImpactStatus::INVALID_INPUT;
    r.toi = kNaN;
    r.point = kNaN3;
    r.normal = kNaN3;
    return r;
}

ToiResult separated_result(int iterations) {
    ToiResult r;
    r.status = TimeOfImpactStatus::SEPARATED;
    r.toi = kNaN;
    r.point = kNaN3;
    r.normal = kNaN3;
    r.iterations = iterations;
    return r;
}

// The largest distance of the shape's points from its motion's axis line (through the pivot):
// the lever arm of the turn. A point's speed from turning is angle x its distance from that
// line, which the turn about the line keeps constant, so this bounds the turning speed of every
// point at every instant; it is at most the bounding radius about the pivot, and much less for a
// body long along its axis (a shaft, a drill). |x - pivot| off the axis is convex in x, so its
// maximum over a polytope or box is at a vertex.
double turning_radius(const ShapeView& s, const Motion& m) {
    const Vec3 k = m.start.rotate_inverse(m.axis_world);          // axis, local frame
    const Vec3 c = m.start.apply_inverse(m.pivot);                 // pivot, local frame
    auto off_axis = [&](const Vec3& x) {
        const Vec3 r = x - c;
        return safe_norm(r - k * dot(r, k));
    };
    double arm = 0.0;
    switch (s.kind) {
        case ShapeKind::POLYTOPE:
            for (int i = 0; i < s.vertex_count; ++i) arm = std::fmax(arm, off_axis(s.vertices[i]));
            return arm;
        case ShapeKind::BOX:
            for (int i = 0; i < 8; ++i)
                arm = std::fmax(arm, off_axis(Vec3{(i & 1 ? 1 : -1) * s.params[0],
                                                   (i & 2 ? 1 : -1) * s.params[1],
                                                   (i & 4 ? 1 : -1) * s.params[2]}));
            return arm;
        case ShapeKind::SPHERE:
            // Swept-ball shapes: the support is the core's plus the radius in every direction,
            // so the gap closes only as fast as the core turns (their radius adds nothing).
            return off_axis(Vec3{});
        case ShapeKind::CAPSULE:
            return std::fmax(off_axis(Vec3{0, 0, s.params[1]}), off_axis(Vec3{0, 0, -s.params[1]}));
        case ShapeKind::CYLINDER:
            // Its rims lie within the radius of the end centres, and its farthest point off any
            // line is on a rim.
            return std::fmax(off_axis(Vec3{0, 0, s.params[1]}), off_axis(Vec3{0, 0, -s.params[1]})) +
                   s.params[0];
        case ShapeKind::ELLIPSOID: {
            // It lies in its box (+-a) and in the ball of radius max(a) about its centre:
            // the lesser of the two bounds.
            for (int i = 0; i < 8; ++i)
                arm = std::fmax(arm, off_axis(Vec3{(i & 1 ? 1 : -1) * s.params[0],
                                                   (i & 2 ? 1 : -1) * s.params[1],
                                                   (i & 4 ? 1 : -1) * s.params[2]}));
            return std::fmin(arm, off_axis(Vec3{}) + bounding_radius(s));
        }
        case ShapeKind::HALFSPACE:
            return std::numeric_limits<double>::infinity();  // unbounded: any turn sweeps far
    }
    return bounding_radius(s) + m.pivot_offset;
}

// A body's motion as the pair query sees it: a sphere turning about its own centre moves no
// point, so its angle is 0 and its orientation the start one.
struct Mover {
    const ShapeView* shape;
    Motion motion;
    double radius;  // lever arm of the turn: largest distance of a point from the axis line
    double reach;   // bounding radius about the local origin (the pair's size, rescale.hpp)
};

Mover make_mover(const ShapeView& shape, const Motion& motion) {
    Mover m{&shape, motion, motion.angle == 0.0 ? 0.0 : turning_radius(shape, motion),
            bounding_radius(shape)};
    if (shape.kind == ShapeKind::SPHERE && m.motion.pivot_offset == 0.0 && m.motion.angle != 0.0) {
        m.motion.end.rotation = m.motion.start.rotation;
        m.motion.angle = 0.0;
        m.radius = 0.0;
    }
    return m;
}

// Two spheres: the centre distance |c0 + t dv| is the square root of a quadratic in t.
ToiResult sphere_sphere(const Mover& a, const Mover& b, double tol) {
    ToiResult r;
    r.iterations = 1;
    const double ra = a.shape->params[0], rb = b.shape->params[0], rsum = ra + rb;
    const Vec3 c0 = b.motion.start.translation - a.motion.start.translation;
    const Vec3 dv = b.motion.velocity - a.motion.velocity;
    const double d0 = norm(c0) - rsum;
    auto finish = [&](double t, TimeOfImpactStatus status) {
        const Vec3 ca = a.motion.start.translation + a.motion.velocity * t;
        const Vec3 c = c0 + dv * t;
        const double len = norm(c);
        Vec3 n;
        if (len > 0.0) n = c / len;
        else if (squared_norm(dv) > 0.0) n = dv * (-1.0 / norm(dv));
        const Vec3 pa = ca + n * ra, pb = ca + c - n * rb;
        r.status = status;
        r.toi = t;
        r.point = (pa + pb) * 0.5;
        r.normal = n;
        if (status == TimeOfImpactStatus::OVERLAPPED_AT_START && d0 <= 0.0) r.normal = Vec3{};
        return r;
    };
    if (d0 <= tol) return finish(0.0, TimeOfImpactStatus::OVERLAPPED_AT_START);
    const double qa = dot(dv, dv), qb = 2.0 * dot(c0, dv);
    if (!(qa > 0.0) || qb >= 0.0) return separated_result(1);  // not approaching
    // Smallest root of |c0 + t dv| = radius, in the cancellation-free form 2c / (-b + sqrt(D)).
    auto first_root = [&](double radius, double& t) {
        const double qc = dot(c0, c0) - radius * radius;
        const double disc = qb * qb - 4.0 * qa * qc;
        if (disc < 0.0) return false;
        t = 2.0 * qc / (-qb + std::sqrt(disc));
        return true;
    };
    double t = 0.0;
    if (first_root(rsum, t) && t <= 1.0) return finish(t, TimeOfImpactStatus::HIT);
    // No touching: still a hit when the closest approach in [0, 1] is within the tolerance.
    const double tm = std::fmin(1.0, -dot(c0, dv) / qa);
    if (norm(c0 + dv * tm) - rsum <= tol && first_root(rsum + tol, t))
        return finish(std::fmin(t, tm), TimeOfImpactStatus::HIT);
    return separated_result(1);
}

// Conservative advancement from time `t` (Mirtich 1996; Zhang et al. 2006). At each step GJK
// gives the distance d and the unit normal n (a to b) of the closest points: A lies behind the
// plane through its closest point, B beyond the parallel plane through its own. A point of A
// at r = x - c_a(t) from a's pivot moves along n at speed (v_a + w_a x r).n
// <= v_a.n + angle_a |n x k_a| |r| (w_a = angle_a k_a, constant over the motion whatever the
// angle), and the same for B along -n, so the gap between the planes closes no faster than
//   mu = (v_a - v_b).n + angle_a |n x k_a| rho_a + angle_b |n x k_b| rho_b
// (rho: the lever arm, the largest distance of a point from the axis line through the pivot,
// constant under the turn: `turning_radius`). Advancing by (d - tol/2) / mu keeps the
// distance above tol/2 on the whole step: rigorous, so contact is never stepped over.
ToiResult conservative_advancement(const Mover& a, const Mover& b, const ToiOptions& opt,
                                   double t, int iterations) {
    const double tol = opt.tolerance;
    const double wa = a.motion.angle * a.radius, wb = b.motion.angle * b.radius;
    const Vec3 dv = a.motion.velocity - b.motion.velocity;
    Vec3 last_normal;
    ToiResult r;
    GjkOptions gopt;
    while (iterations < opt.max_iterations) {
        ++iterations;
        const Pose pa = a.motion.at(t), pb = b.motion.at(t);
        const GjkResult g = gjk_distance(*a.shape, pa, *b.shape, pb, gopt);
        // GJK's distance is exact on polytopes and within defaults::gjk_relative_tolerance on
        // curved shapes, far inside the tol/2 slack of the step.
        const double d = g.distance;
        if (d <= tol) {
            r.status = t == 0.0 ? TimeOfImpactStatus::OVERLAPPED_AT_START : TimeOfImpactStatus::HIT;
            r.toi = t;
            r.point = (g.point_a + g.point_b) * 0.5;
            r.normal = d > 0.0 ? g.normal : (t == 0.0 ? Vec3{} : last_normal);
            r.iterations = iterations;
            return r;
        }
        const Vec3 n = g.normal;
        last_normal = n;
        const double mu = dot(dv, n) + wa * norm(cross(n, a.motion.axis_world)) +
                          wb * norm(cross(n, b.motion.axis_world));
        if (!(mu > 0.0)) return separated_result(iterations);  // the gap never closes
        const double step = (d - 0.5 * tol) / mu;
        if (t + step > 1.0) return separated_result(iterations);
        r.toi = t;
        r.point = (g.point_a + g.point_b) * 0.5;
        r.normal = n;
        t += step;
    }
    // Cap reached: t is still a safe lower bound (every step was).
    const Pose pa = a.motion.at(t), pb = b.motion.at(t);
    const GjkResult g = gjk_distance(*a.shape, pa, *b.shape, pb, gopt);
    r.status = TimeOfImpactStatus::FAILED;
    r.toi = t;
    r.point = (g.point_a + g.point_b) * 0.5;
    r.normal = g.distance > 0.0 ? g.normal : last_normal;
    r.iterations = iterations;
    return r;
}

// Linear cast for bodies that do not turn (van den Bergen 2004, sec. 3; the margin handling as
// Box2D's b2ShapeCast). In a's frame, b's core moves by lambda * dir; the cores touch the
// margin-inflated set when lambda * dir enters C + ball(delta), C = A - B(0). The loop keeps a
// point x = lambda * dir on the ray and a GJK simplex of support points p of C; v = x - (closest
// point of the simplex to x). When the support plane of C in direction v lies farther than
// delta + tol/2 from x, x advances along the ray to that plane (a safe step: every point passed
// is farther than delta + tol/2 from C), or the ray misses. The loop stops when |v| <=
// delta + tol: the distance at lambda is then <= tol.
ToiResult linear_cast(const Mover& a, const Mover& b, const ToiOptions& opt, bool& stalled) {
    stalled = false;
    const double tol = opt.tolerance;
    const Pose& pose_a = a.motion.start;
    MinkowskiDifference md(*a.shape, pose_a, *b.shape, b.motion.start, false);
    const Vec3 dir = pose_a.rotate_inverse(b.motion.velocity - a.motion.velocity);
    const double delta = margin(*a.shape) + margin(*b.shape);
    const double target = delta + 0.5 * tol, stop = delta + tol;

    double lambda = 0.0;
    Vec3 x;
    Vec3 plane_normal;  // last separating direction (a's frame, a to b)
    Simplex s;
    Vec3 start_dir = md.translation_b;
    if (!(squared_norm(start_dir) > 0.0)) start_dir = squared_norm(dir) > 0.0 ? dir : Vec3{1, 0, 0};
    Vec3 v = x - md.support(start_dir).w;
    int it = 0;
    bool inside = false;
    while (true) {
        const double vv = squared_norm(v);
        if (vv <= stop * stop) break;
        if (it >= opt.max_iterations) {
            ToiResult r;
            r.status = TimeOfImpactStatus::FAILED;
            r.toi = lambda;
            r.iterations = it;
            // Report the closest points of the current simplex, as for a hit.
            Vec3 pa, pb;
            for (int i = 0; i < s.size; ++i) {
                pa += s.vertices[i].a * s.weights[i];
                pb += s.vertices[i].b * s.weights[i];
            }
            const Vec3 n = v / std::sqrt(vv);
            const Pose at = a.motion.at(lambda);
            r.point = at.apply((pa + n * margin(*a.shape) + pb + x - n * margin(*b.shape)) * 0.5);
            r.normal = at.rotate(n);
            if (s.size == 0) r.point = kNaN3;
            return r;
        }
        ++it;
        const double vn = std::sqrt(vv);
        const Vec3 vhat = v / vn;
        SimplexVertex w = md.support(vhat);
        const double gap = dot(vhat, x - w.w);
        bool advanced = false;
        if (gap > target) {
            const double vr = dot(vhat, dir);
            if (!(vr < 0.0)) return separated_result(it);  // moving away from the plane
            const double next = lambda + (gap - target) / -vr;
            if (next > 1.0) return separated_result(it);
            advanced = next > lambda;
            lambda = next;
            x = dir * lambda;
            plane_normal = vhat;
        }
        bool repeated = false;
        for (int i = 0; i < s.size; ++i)
            if (same_feature(s.vertices[i], w)) repeated = true;
        if (!repeated) {
            s.vertices[s.size] = w;
            ++s.size;
        } else if (!advanced) {
            stalled = true;  // rounding: no new support point and no step
            ToiResult r;
            r.toi = lambda;
            r.iterations = it;
            return r;
        }
        // The simplex holds points p of C; its closest point to x is the closest point of
        // {x - p} to the origin.
        for (int i = 0; i < s.size; ++i) s.vertices[i].w = x - (s.vertices[i].a - s.vertices[i].b);
        Vec3 c;
        if (!closest_point_on_simplex(s, c)) {
            inside = true;  // x inside C: the cores touch at lambda
            v = Vec3{};
            break;
        }
        if (!advanced && !(squared_norm(c) < vv)) {
            stalled = true;
            ToiResult r;
            r.toi = lambda;
            r.iterations = it;
            return r;
        }
        v = c;
    }
    ToiResult r;
    r.status = lambda == 0.0 ? TimeOfImpactStatus::OVERLAPPED_AT_START : TimeOfImpactStatus::HIT;
    r.toi = lambda;
    r.iterations = it;
    Vec3 pa, pb;
    if (s.size == 0) {
        // Stopped before any simplex was built: v came from the first support point alone.
        const SimplexVertex w0 = md.support(start_dir);
        pa = w0.a;
        pb = w0.b;
    } else {
        for (int i = 0; i < s.size; ++i) {
            pa += s.vertices[i].a * s.weights[i];
            pb += s.vertices[i].b * s.weights[i];
        }
    }
    pb += x;
    const double vn = norm(v);
    Vec3 n;
    if (!inside && vn > 0.0) n = v / vn;
    else if (r.status == TimeOfImpactStatus::HIT) n = plane_normal;
    pa += n * margin(*a.shape);
    pb -= n * margin(*b.shape);
    const Pose at = a.motion.at(lambda);
    r.point = at.apply((pa + pb) * 0.5);
    r.normal = at.rotate(n);
    if (r.status == TimeOfImpactStatus::OVERLAPPED_AT_START && vn <= delta) r.normal = Vec3{};
    return r;
}

ToiResult pair_toi_in_range(const Mover& a, const Mover& b, const ToiOptions& opt) {
    if (a.shape->kind == ShapeKind::SPHERE && b.shape->kind == ShapeKind::SPHERE &&
        a.motion.angle == 0.0 && b.motion.angle == 0.0)
        return sphere_sphere(a, b, opt.tolerance);
    if (a.motion.angle == 0.0 && b.motion.angle == 0.0 &&
        same_rotation(a.motion.start.rotation, a.motion.end.rotation) &&
        same_rotation(b.motion.start.rotation, b.motion.end.rotation)) {
        bool stalled = false;
        ToiResult r = linear_cast(a, b, opt, stalled);
        if (!stalled) return r;
        // Rounding stalled the cast: finish with conservative advancement from its safe bound
        // (exact for translation: mu is the relative speed along the normal).
        return conservative_advancement(a, b, opt, r.toi, r.iterations);
    }
    return conservative_advancement(a, b, opt, 0.0, 0);
}

// A mover in the frame `f` (rescale.hpp): its shape scaled into `storage`, its motion's points
// moved and scaled; angles and axes do not change.
Mover scaled_mover(const Mover& m, const rescale::Frame& f, ShapeView& shape,
                   std::vector<Vec3>& storage) {
    shape = rescale::scaled(*m.shape, f, storage);
    Mover s = m;
    s.shape = &shape;
    s.radius = f.length(m.radius);
    s.reach = f.length(m.reach);
    s.motion.start.translation = f.point(m.motion.start.translation);
    s.motion.end.translation = f.point(m.motion.end.translation);
    s.motion.pivot = f.point(m.motion.pivot);
    s.motion.velocity = f.vector(m.motion.velocity);
    s.motion.pivot_offset = f.length(m.motion.pivot_offset);
    return s;
}

// Every pair goes through here: a pair whose lengths (start and end positions, pivots, radii)
// leave the range where GJK's products are safe runs moved and scaled by a power of two, as
// the narrow phase does (rescale.hpp); the fraction and the normal do not change.
ToiResult pair_toi(const Mover& a, const Mover& b, const ToiOptions& opt) {
    const Vec3 origin = a.motion.start.translation;
    double half = std::fmax(std::fmax(0.5 * a.reach, 0.5 * b.reach),
                            std::fmax(0.5 * a.radius, 0.5 * b.radius));
    for (const Mover* m : {&a, &b}) {
        rescale::reach(half, origin, m->motion.start.translation);
        rescale::reach(half, origin, m->motion.end.translation);
        rescale::reach(half, origin, m->motion.pivot);
    }
    const rescale::Frame f = rescale::choose(origin, half);
    if (!f.finite) return invalid_result();
    if (!f.active) return pair_toi_in_range(a, b, opt);
    ToiOptions scaled_opt = opt;
    scaled_opt.tolerance = f.length(opt.tolerance);
    if (!(scaled_opt.tolerance > 0.0)) return invalid_result();  // below the scene's precision
    ShapeView shape_a, shape_b;
    std::vector<Vec3> storage_a, storage_b;
    ToiResult r = pair_toi_in_range(scaled_mover(a, f, shape_a, storage_a),
                                    scaled_mover(b, f, shape_b, storage_b), scaled_opt);
    r.point = f.world_point(r.point);
    return r;
}

}  // namespace

Vec3 shortest_rotation(const Mat3& start, const Mat3& end) {
    if (same_rotation(start, end)) return Vec3{};
    double q[4];
    matrix_quaternion(start.transposed() * end, q);
    const Vec3 xyz{q[1], q[2], q[3]};
    const double s = norm(xyz);
    if (!(s > 0.0)) return Vec3{};
    // The relative rotation is about the start-frame axis; the world axis is start * axis.
    return start * (xyz * (2.0 * std::atan2(s, q[0]) / s));
}

Motion::Motion(const Pose& start_pose, const Pose& end_pose) : start(start_pose), end(end_pose) {
    pivot = start.translation;
    velocity = end.translation - start.translation;
    const Vec3 rotation = shortest_rotation(start.rotation, end.rotation);
    const double a = norm(rotation);
    if (a > 0.0) {
        axis_world = rotation / a;
        angle = a;
    }
}

bool Motion::from_turn(const Pose& start_pose, const Pose& end_pose, const Vec3& rotation,
                       const Vec3& pivot_point, double tolerance, Motion& out) {
    if (!is_finite(rotation) || !is_finite(pivot_point)) return false;
    Motion m;
    m.start = start_pose;
    m.end = end_pose;
    m.pivot = pivot_point;
    const double a = norm(rotation);
    if (a > 0.0) {
        m.axis_world = rotation / a;
        m.angle = a;
    }
    const Mat3 turn = axis_angle_matrix(m.axis_world, m.angle);
    const Mat3 reached = turn * start_pose.rotation;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (!(std::fabs(reached.m[i][j] - end_pose.rotation.m[i][j]) <= tolerance))
                return false;
    const Vec3 arm = start_pose.translation - pivot_point;
    m.pivot_offset = norm(arm);
    // T1 = c0 + v + Rot(angle) (T0 - c0), so the pivot's displacement follows from the end pose.
    m.velocity = end_pose.translation - pivot_point - turn * arm;
    if (!is_finite(m.velocity) || !std::isfinite(m.pivot_offset)) return false;
    out = m;
    return true;
}

Pose Motion::at(double t) const {
    if (t == 0.0) return start;
    if (t == 1.0) return end;
    Pose p;
    if (angle == 0.0) {
        p.rotation = start.rotation;
        p.translation = start.translation + velocity * t;
        return p;
    }
    const Mat3 turn = axis_angle_matrix(axis_world, angle * t);
    p.rotation = turn * start.rotation;
    p.translation = pivot + velocity * t + turn * (start.translation - pivot);
    return p;
}

bool make_motion(const double* start_pose, const double* end_pose, const double* rotation,
                 const double* pivot, Motion& motion) {
    if (!is_rigid_matrix4(start_pose, defaults::rigid_tolerance) ||
        !is_rigid_matrix4(end_pose, defaults::rigid_tolerance))
        return false;
    const Pose p0 = Pose::from_matrix4(start_pose), p1 = Pose::from_matrix4(end_pose);
    if (rotation == nullptr && pivot == nullptr) {
        motion = Motion(p0, p1);
        return is_finite(motion.velocity);  // a path longer than DBL_MAX
    }
    const Vec3 turn = rotation != nullptr ? Vec3{rotation[0], rotation[1], rotation[2]}
                                          : shortest_rotation(p0.rotation, p1.rotation);
    const Vec3 centre = pivot != nullptr ? Vec3{pivot[0], pivot[1], pivot[2]} : p0.translation;
    return Motion::from_turn(p0, p1, turn, centre, defaults::rigid_tolerance, motion);
}

void make_motions(long long count, const double* start_poses, const double* end_poses,
                  const double* rotations, const double* pivots, Motion* motions, char* ok) {
    for (long long h = 0; h < count; ++h)
        ok[h] = make_motion(start_poses + 16 * h, end_poses + 16 * h,
                            rotations != nullptr ? rotations + 3 * h : nullptr,
                            pivots != nullptr ? pivots + 3 * h : nullptr, motions[h])
                    ? 1
                    : 0;
}

ToiResult time_of_impact(const ShapeView& a, const Motion& motion_a, const ShapeView& b,
                         const Motion& motion_b, const ToiOptions& options) {
    if (!is_valid(a) || !is_valid(b) || !(options.tolerance > 0.0) ||
        !std::isfinite(options.tolerance))
        return invalid_result();
    return pair_toi(make_mover(a, motion_a), make_mover(b, motion_b), options);
}

void run_toi_batch(const ConvexSetView& set, const double* start_poses, const double* end_poses,
                   const double* rotations, const double* pivots, const std::int64_t* pairs,
                   long long pair_count, const ToiOptions& options, int threads,
                   const ToiBatchOutput& out) {
    const std::int64_t h_count = set.shape_count;
    const bool options_ok = options.tolerance > 0.0 && std::isfinite(options.tolerance);
    // Shapes, motions and their lever arms once per shape of the batch, not once per pair
    // nor for the shapes no pair names (`BatchShapes`).
    BatchShapes batch(h_count, pairs, pair_count);
    const std::int64_t slots = batch.size();
    std::vector<ShapeView> shapes(static_cast<size_t>(slots));  // the movers point at these
    std::vector<Mover> movers(static_cast<size_t>(slots));
    std::vector<char> ok = batch.take_used();
    for (std::int64_t k = 0; k < slots; ++k) {
        if (!ok[k]) continue;
        const std::int64_t h = batch.shape(k);
        const ShapeView& shape = shapes[k] = set.shape(h);
        Motion motion;
        ok[k] = options_ok && is_valid(shape) &&
                make_motion(start_poses + 16 * h, end_poses + 16 * h,
                            rotations != nullptr ? rotations + 3 * h : nullptr,
                            pivots != nullptr ? pivots + 3 * h : nullptr, motion);
        if (ok[k]) movers[k] = make_mover(shape, motion);
    }
    // Advancement can take many GJK calls per pair: smaller chunks balance better.
    const int n_threads = resolve_threads(threads, pair_count, defaults::toi_min_pairs_per_thread);
    parallel_for(pair_count, n_threads, [&](long long begin, long long end) {
        for (long long i = begin; i < end; ++i) {
            const std::int64_t ka = batch.slot_of(2 * i), kb = batch.slot_of(2 * i + 1);
            ToiResult r;
            if (!ok[ka] || !ok[kb]) {
                r = invalid_result();
            } else {
                r = pair_toi(movers[ka], movers[kb], options);
            }
            if (out.toi) out.toi[i] = r.toi;
            store_row(out.point, i, r.point);
            store_row(out.normal, i, r.normal);
            if (out.iterations) out.iterations[i] = r.iterations;
            if (out.status) out.status[i] = static_cast<std::int8_t>(r.status);
        }
    });
}

}  // namespace meshcol
