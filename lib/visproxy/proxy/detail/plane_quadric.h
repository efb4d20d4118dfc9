#pragma once
// Private to lib/visproxy/proxy (detail/, not installed): the quadric error of Garland & Heckbert (1997), the
// weighted sum of squared distances to planes, shared by quadric:N (quadric_simplify.cpp)
// and the conservative decimation of outer:N and inner:N.

#include <Eigen/Core>
#include <Eigen/Cholesky>
#include <limits>

namespace visproxy::detail {

/// Symmetric 4x4 quadric [A b; b^T c] in its 10 distinct entries, with the weight (area)
/// it stands for.
struct PlaneQuadric {
  double xx = 0, xy = 0, xz = 0, xw = 0, yy = 0, yz = 0, yw = 0, zz = 0, zw = 0, ww = 0;
  double weight = 0;

  /// weight * (n.p + d)^2 for a unit normal n.
  static PlaneQuadric plane(const Eigen::Vector3d& n, double d, double weight) {
    PlaneQuadric q;
    q.xx = weight * n.x() * n.x();
    q.xy = weight * n.x() * n.y();
    q.xz = weight * n.x() * n.z();
    q.xw = weight * n.x() * d;
    q.yy = weight * n.y() * n.y();
    q.yz = weight * n.y() * n.z();
    q.yw = weight * n.y() * d;
    q.zz = weight * n.z() * n.z();
    q.zw = weight * n.z() * d;
    q.ww = weight * d * d;
    q.weight = weight;
    return q;
  }

  PlaneQuadric& operator+=(const PlaneQuadric& o) {
    xx += o.xx, xy += o.xy, xz += o.xz, xw += o.xw, yy += o.yy;
    yz += o.yz, yw += o.yw, zz += o.zz, zw += o.zw, ww += o.ww;
    weight += o.weight;
    return *this;
  }
  friend PlaneQuadric operator+(PlaneQuadric a, const PlaneQuadric& b) { return a += b; }

  /// Sum of the weighted squared distances of p to the planes (may round below 0).
  double sum(const Eigen::Vector3d& p) const {
    const double x = p.x(), y = p.y(), z = p.z();
    return x * (xx * x + 2 * (xy * y + xz * z + xw)) + y * (yy * y + 2 * (yz * z + yw)) + z * (zz * z + 2 * zw) + ww;
  }

  /// The minimiser, if det(A) / (trace(A)/3)^3 (1 for an isotropic quadric, 0 for a flat
  /// or ridge-like one) exceeds `min_relative_determinant`.
  bool minimiser(Eigen::Vector3d& out, double min_relative_determinant) const {
    const double c00 = yy * zz - yz * yz, c01 = xz * yz - xy * zz, c02 = xy * yz - xz * yy;
    const double det = xx * c00 + xy * c01 + xz * c02;
    const double third_trace = (xx + yy + zz) / 3;
    if (!(third_trace > 0) || !(det > min_relative_determinant * third_trace * third_trace * third_trace)) return false;
    const double c11 = xx * zz - xz * xz, c12 = xy * xz - xx * yz, c22 = xx * yy - xy * xy;
    const double inverse_det = 1 / det;
    out = {-(c00 * xw + c01 * yw + c02 * zw) * inverse_det, -(c01 * xw + c11 * yw + c12 * zw) * inverse_det,
           -(c02 * xw + c12 * yw + c22 * zw) * inverse_det};
    return out.allFinite();
  }

  /// The minimiser of the quadric plus 1e-6 trace(A) |p - anchor|^2: where the quadric is
  /// (nearly) flat, the point nearest `anchor`.
  Eigen::Vector3d regularised_minimiser(const Eigen::Vector3d& anchor) const {
    Eigen::Matrix3d a;
    a << xx, xy, xz, xy, yy, yz, xz, yz, zz;
    const double lambda = 1e-6 * a.trace() + std::numeric_limits<double>::min();
    a.diagonal().array() += lambda;
    return a.ldlt().solve(lambda * anchor - Eigen::Vector3d(xw, yw, zw));
  }
};

}  // namespace visproxy::detail
