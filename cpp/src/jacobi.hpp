// One rotation of the cyclic Jacobi method for small symmetric eigenproblems (Golub and Van
// Loan, sec. 8.5), shared by the principal axes of hull.cpp, the fits of fit.cpp and the
// minimum ellipsoid's axes: each keeps its own stopping rule, the rotation is this one.
#pragma once

#include <cmath>

namespace meshcol {

/// Zero a[p][q] (a[p][q] != 0) of the symmetric m x m block of `a` (m <= 3) by the rotation
/// that also turns the columns p and q of the 3 x 3 eigenvector matrix `v`.
inline void jacobi_rotate(double a[3][3], double v[3][3], int p, int q, int m) {
    const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
    const double t =
        (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
    const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
    for (int k = 0; k < m; ++k) {
        const double akp = a[k][p], akq = a[k][q];
        a[k][p] = c * akp - s * akq;
        a[k][q] = s * akp + c * akq;
    }
    for (int k = 0; k < m; ++k) {
        const double apk = a[p][k], aqk = a[q][k];
        a[p][k] = c * apk - s * aqk;
        a[q][k] = s * apk + c * aqk;
    }
    for (int k = 0; k < 3; ++k) {
        const double vkp = v[k][p], vkq = v[k][q];
        v[k][p] = c * vkp - s * vkq;
        v[k][q] = s * vkp + c * vkq;
    }
}

}  // namespace meshcol
